"""Copies a JavaScript file without its whole-line `//` comments.

The page's first load has a size budget (web/test_web.py); its scripts' comments
are for the source, not the download. Only lines that are nothing but a
comment go, and none inside a template literal (a backtick opened on an
earlier line), where such a line would be text. Usage: strip_comments.py IN OUT
"""

import sys


def strip(text: str) -> str:
    kept = []
    open_template = False
    for line in text.split("\n"):
        if not open_template and line.lstrip().startswith("//"):
            continue
        kept.append(line)
        if line.count("`") % 2:
            open_template = not open_template
    return "\n".join(kept)


if __name__ == "__main__":
    source, target = sys.argv[1], sys.argv[2]
    with open(source, encoding="utf-8") as f:
        text = f.read()
    with open(target, "w", encoding="utf-8") as f:
        f.write(strip(text))
