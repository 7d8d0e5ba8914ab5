"""The README's Python example runs as written."""

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                             capsys: pytest.CaptureFixture[str]) -> None:
    text = README.read_text()
    match = re.search(r"<!-- python-example[^>]*-->\n```python\n(.*?)```", text, re.S)
    assert match, "README has no marked Python example"
    code = match.group(1)
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    monkeypatch.chdir(tmp_path)
    exec(compile(code, str(README), "exec"), {"__name__": "readme"})
    printed = capsys.readouterr().out.splitlines()
    assert printed[-1] == "sheet OK"
    ids = sorted(int(line.split()[0]) for line in printed[:-1])
    assert ids == list(range(1, 17))
    assert (tmp_path / "swarm.pdf").exists() and (tmp_path / "swarm.json").exists()
