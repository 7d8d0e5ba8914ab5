#!/usr/bin/env bash
# Browser tests of the page: builds the site (web/build.sh) and the CLI,
# then drives Debian's Chromium with Playwright (from PyPI; Playwright's own
# browser download is never used) through every panel and compares what the
# page makes with what `whycode` makes. Screenshots go to $WEB_TEST_OUT
# (default: target/web-test/screenshots). Ends with "N passed, N failed".
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
cd "$root"
target_dir=${CARGO_TARGET_DIR:-$root/target}

# Chromium drives the page; npm brings the build's binaryen (web/build.sh).
missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)
if [ ${#missing[@]} -gt 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq "${missing[@]}" >/dev/null
fi
# Playwright lives in a virtual environment of its own under the target
# directory, never in the system Python.
venv="$target_dir/web-venv"
if ! "$venv/bin/python" -c "import playwright" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "playwright==1.65.2"
fi

# The binding crate is not a default member, so the workspace lint skips it.
# .ci/run lints the whole workspace first and says so.
if [ -z "${WHYCODE_LINTED:-}" ]; then
    cargo clippy -p whycode-web --all-targets -- -D warnings
fi
"$here/build.sh"
# The CLI the page is compared with: this checkout's (or the one WHYCODE_BIN
# names: .ci/run hands on the Rust suite's).
if [ -z "${WHYCODE_BIN:-}" ]; then
    cargo build --release --bin whycode
    WHYCODE_BIN="$target_dir/release/whycode"
fi
"$venv/bin/python" "$here/test_web.py" --dist "$here/dist" --whycode "$WHYCODE_BIN" \
    --out "${WEB_TEST_OUT:-$target_dir/web-test}" "$@"
