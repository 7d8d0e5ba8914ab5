"""Writes a wasm-metadce reachability graph that keeps only some of a module's exports.

printpdf marks its own JavaScript API (`Pdf_HtmlToDocumentSync` and six more)
with #[wasm_bindgen] whenever it is compiled for WebAssembly, so every cdylib
that links it exports them, and with them a PDF parser, an SVG renderer,
font subsetting and image decoders that whycode never calls: about half the
module. wasm-metadce removes exports that no root reaches; this script lists
the module's exports and roots the wanted ones plus wasm-bindgen's own
(memory, allocator, tables: every name that starts with "__").

    python3 web/wasm_exports.py MODULE.wasm GRAPH.json KEEP [KEEP ...]

A KEEP ending in "*" keeps every export with that prefix.
"""

import json
import sys


def leb128(data, pos):
    value = shift = 0
    while True:
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, pos


def export_names(data):
    if data[:4] != b"\0asm":
        raise SystemExit("not a WebAssembly module")
    pos = 8
    while pos < len(data):
        section = data[pos]
        size, pos = leb128(data, pos + 1)
        if section == 7:
            count, p = leb128(data, pos)
            names = []
            for _ in range(count):
                length, p = leb128(data, p)
                names.append(data[p:p + length].decode())
                p += length + 1  # the kind byte
                _, p = leb128(data, p)  # the index
            return names
        pos += size
    return []


def main():
    module, graph, *keep = sys.argv[1:]
    names = export_names(open(module, "rb").read())

    def wanted(name):
        if name.startswith("__") or name == "memory":
            return True
        return any(name.startswith(k[:-1]) if k.endswith("*") else name == k for k in keep)

    missing = [k for k in keep if not k.endswith("*") and k not in names]
    if missing:
        raise SystemExit(f"{module}: no export named {', '.join(missing)}")
    nodes = [{"name": "root", "root": True, "reaches": [f"export:{n}" for n in names if wanted(n)]}]
    nodes += [{"name": f"export:{n}", "export": n} for n in names]
    with open(graph, "w") as f:
        json.dump(nodes, f)
    dropped = [n for n in names if not wanted(n)]
    print(f"{module}: dropping {len(dropped)} unused exports: {' '.join(dropped)}", file=sys.stderr)


if __name__ == "__main__":
    main()
