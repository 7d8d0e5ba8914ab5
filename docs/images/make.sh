#!/usr/bin/env bash
# Remakes the README's two pictures with the tool itself:
#   docs/images/sheet.png     page 1 of the default sheet, at 40 dpi
#   docs/images/detected.png  that page photographed by the simulator, as
#                             `whycode detect --annotate` draws it (cropped to
#                             the page, scaled to 60 %, 128 colours)
# Needs: a release build (cargo build --release), pdftoppm (Debian's
# poppler-utils) and Pillow (pip install pillow). Made with Pillow 13.0.0;
# whycode's own outputs are deterministic, so only another Pillow (or
# poppler) can change the bytes.
set -euo pipefail
cd "$(dirname "$0")/../.."
W="$PWD/target/release/whycode"
OUT="$PWD/docs/images"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
cd "$TMP"

"$W" sheet -o swarm.pdf
pdftoppm -png -r 40 -f 1 -l 1 swarm.pdf sheet
cp sheet-1.png "$OUT/sheet.png"

"$W" simulate --manifest swarm.json --tilt 30deg --pan 15deg --roll 20deg --background table -o view.png
"$W" detect --annotate out/ view.png
python3 - "$OUT/detected.png" <<'PY'
import sys
from PIL import Image

page = Image.open("out/view.annotated.png").crop((480, 20, 1300, 950))
small = page.resize((page.width * 3 // 5, page.height * 3 // 5), Image.LANCZOS)
small.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(sys.argv[1], optimize=True)
PY
