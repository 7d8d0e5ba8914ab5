#!/usr/bin/env bash
# CI for the Python package: a clean virtual environment, maturin, pytest,
# numpy and mypy from PyPI, `pip install ./python`, then mypy on the stubs
# and pytest (which compares the bindings with the `whycode` binary).
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
VENV=$(mktemp -d "${TMPDIR:-/tmp}/whycode-venv.XXXXXX")
trap 'rm -rf "$VENV"' EXIT

"$PYTHON" -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet maturin pytest numpy mypy
"$VENV/bin/python" -m pip install --quiet ./python

# The binding crate is not a default workspace member: lint it here.
# .ci/run lints the whole workspace first and says so.
if [ -z "${WHYCODE_LINTED:-}" ]; then
    cargo clippy --quiet -p whycode-python --all-targets -- -D warnings
fi

# The tests compare with the CLI built from this checkout.
cargo build --release --quiet --bin whycode
export WHYCODE_BIN="${CARGO_TARGET_DIR:-$PWD/target}/release/whycode"

# The installed package and its stubs, as a user's mypy sees them.
"$VENV/bin/mypy" --strict python/mypy_check.py
"$VENV/bin/mypy" python/tests python/bench/overhead.py

# From outside python/, so `import whycode` is the installed package.
# Exit status 5 (no tests collected) fails like any other.
cd python/tests
"$VENV/bin/pytest" -q -p no:cacheprovider .
