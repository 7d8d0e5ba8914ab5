#!/usr/bin/env bash
# The aarch64 Linux builds, checked on this x86_64 machine: the Python wheel
# (maturin, cross-linked by zig from PyPI, manylinux2014) and the `whycode`
# binary (cargo-zigbuild), each run under qemu-user (Debian's
# qemu-user-static) with Debian's own arm64 Python and C library unpacked
# into a private root. The wheel is installed by pip, resolved for aarch64,
# and imported; it and the binary each draw a marker and read it back.
#
# Both are built in the `cross` profile (unoptimised, no debug information):
# this proves the cross build, the wheel's tags and the code on arm64; the
# release workflow (.github/workflows/release.yml) builds the optimised
# wheels users get.
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
TARGET=${CARGO_TARGET_DIR:-$PWD/target}
TRIPLE=aarch64-unknown-linux-gnu
WORK=$(mktemp -d "${TMPDIR:-/tmp}/whycode-cross.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

# Debian's arm64 packages of Python 3.11 and the C library it needs, never
# installed on this machine: only downloaded and unpacked under $ROOT.
ARM_PACKAGES=(libc6 libgcc-s1 libstdc++6 zlib1g libexpat1 libffi8 libbz2-1.0 liblzma5
    libssl3 libcrypt1 libsqlite3-0 libuuid1 libncursesw6 libtinfo6 libreadline8 libdb5.3
    libpython3.11-minimal libpython3.11-stdlib python3.11-minimal)
if ! command -v qemu-aarch64-static >/dev/null 2>&1 \
    || ! dpkg --print-foreign-architectures | grep -qx arm64; then
    export DEBIAN_FRONTEND=noninteractive
    dpkg --add-architecture arm64
    apt-get update -qq
    apt-get install -y -qq qemu-user-static >/dev/null
fi
if ! rustup target list --installed | grep -qx "$TRIPLE"; then
    rustup target add "$TRIPLE"
fi

TOOLS="$TARGET/wheel-tools"
if ! "$TOOLS/bin/python" -c "import maturin, ziglang" 2>/dev/null \
    || [ ! -x "$TOOLS/bin/cargo-zigbuild" ]; then
    [ -x "$TOOLS/bin/python" ] || "$PYTHON" -m venv "$TOOLS"
    "$TOOLS/bin/python" -m pip install --quiet "maturin>=1.5,<2" ziglang cargo-zigbuild
fi
export PATH="$TOOLS/bin:$PATH"

ROOT="$TARGET/arm64-root"
if [ ! -x "$ROOT/usr/bin/python3.11" ]; then
    mkdir -p "$WORK/debs" "$ROOT.tmp"
    (cd "$WORK/debs" && apt-get download -qq "${ARM_PACKAGES[@]/%/:arm64}")
    for deb in "$WORK"/debs/*.deb; do
        dpkg-deb -x "$deb" "$ROOT.tmp"
    done
    rm -rf "$ROOT"
    mv "$ROOT.tmp" "$ROOT"
fi
arm() { qemu-aarch64-static -L "$ROOT" "$@"; }

echo "== aarch64 wheel"
maturin build --quiet --profile cross --zig --target "$TRIPLE" --compatibility manylinux2014 \
    -m python/Cargo.toml --out "$WORK/wheels"
wheel=$(ls "$WORK"/wheels/*.whl)
case "$wheel" in
    *manylinux2014_aarch64*) ;;
    *) echo "python/cross.sh: $wheel is not a manylinux2014 aarch64 wheel" >&2; exit 1 ;;
esac
# pip resolves the wheel and numpy for an aarch64 CPython 3.11, as on a
# Raspberry Pi or a Jetson.
"$TOOLS/bin/python" -m pip install --quiet --disable-pip-version-check --target "$WORK/site" \
    --platform manylinux2014_aarch64 --python-version 3.11 --implementation cp \
    --only-binary=:all: "$wheel" numpy
PYTHONPATH="$WORK/site" arm "$ROOT/usr/bin/python3.11" - <<'EOF'
import platform
import whycode

assert platform.machine() == "aarch64", platform.machine()
family = whycode.Family(8, 2)
image = whycode.render_marker_image(5, family=family, diameter_px=120.0)
found = whycode.Detector(family).detect(image)
assert [m.id for m in found] == [5], found
print(f"aarch64 wheel: whycode {whycode.__version__} on {platform.machine()} read ID 5")
EOF

echo "== aarch64 binary"
cargo zigbuild --quiet --profile cross --target "$TRIPLE.2.17" --bin whycode
bin="$TARGET/$TRIPLE/cross/whycode"
arm "$bin" marker --id 7 --diameter 20mm --dpi 200 -o "$WORK/marker.png"
out=$(arm "$bin" detect --format csv "$WORK/marker.png")
echo "$out"
if ! echo "$out" | awk -F, 'NR > 1 && $2 == 7 { found = 1 } END { exit !found }'; then
    echo "python/cross.sh: the aarch64 binary did not read ID 7 back" >&2
    exit 1
fi
echo "aarch64 binary: read ID 7"
