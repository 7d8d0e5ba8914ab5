#!/usr/bin/env bash
# Builds the static site into web/dist/: the whycode library compiled to
# WebAssembly (wasm-bindgen), the page's HTML/CSS/JS and an offline cache
# list. Works on a fresh machine: installs the wasm target and the
# wasm-bindgen CLI (the version Cargo.lock pins) when they are missing.
# Serve the result with any static server, e.g. `python3 -m http.server -d web/dist`.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
cd "$root"
target_dir=${CARGO_TARGET_DIR:-$root/target}

if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
fi

# The CLI must match the wasm-bindgen crate exactly: its output and the
# crate's generated glue share a private format.
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
if [ -z "$version" ]; then
    echo "web/build.sh: error: no wasm-bindgen version in Cargo.lock" >&2
    exit 1
fi
PATH="$HOME/.cargo/bin:$PATH"
if ! command -v wasm-bindgen >/dev/null 2>&1 || [ "$(wasm-bindgen --version | awk '{print $2}')" != "$version" ]; then
    echo "web/build.sh: installing wasm-bindgen-cli $version" >&2
    # --locked first, for the CLI's own tested dependency set; without it
    # when one of those has since been withdrawn from the registry.
    cargo install wasm-bindgen-cli --version "$version" --locked ||
        cargo install wasm-bindgen-cli --version "$version"
fi

# Built for size (the page's whole download) except the whycode crate
# itself, whose detector runs on every camera frame; one codegen unit and
# LTO let unused code of the PDF and image stacks fall away.
cargo build -p whycode-web --release --target wasm32-unknown-unknown \
    --config 'profile.release.debug=false' \
    --config 'profile.release.lto=true' \
    --config 'profile.release.codegen-units=1' \
    --config 'profile.release.opt-level="z"' \
    --config 'profile.release.package.whycode.opt-level=3'

staging="$here/dist.tmp"
rm -rf "$staging"
mkdir -p "$staging/pkg"
wasm-bindgen --target web --no-typescript --remove-name-section --remove-producers-section \
    --out-dir "$staging/pkg" \
    "$target_dir/wasm32-unknown-unknown/release/whycode_web.wasm"
cp "$here/site/index.html" "$here/site/style.css" "$here/site/app.js" "$here/site/worker.js" "$staging/"

# The offline cache: every file of the site, under a version that changes
# with any of them.
files=$(cd "$staging" && find . -type f | sed 's|^\./||' | sort)
hash=$(cd "$staging" && cat $files "$here/site/sw.js" | sha256sum | cut -c1-16)
list=$(printf '"./",'; for f in $files; do printf '"%s",' "$f"; done)
sed -e "s|__VERSION__|$hash|" -e "s|__FILES__|[${list%,}]|" "$here/site/sw.js" >"$staging/sw.js"

rm -rf "$here/dist"
mv "$staging" "$here/dist"
total=$(cd "$here/dist" && cat pkg/*.wasm pkg/*.js *.js *.css | wc -c)
packed=$(cd "$here/dist" && cat pkg/*.wasm pkg/*.js *.js *.css | gzip -9 | wc -c)
echo "web/build.sh: built web/dist: wasm + JS + CSS $((total / 1024)) KiB, $((packed / 1024)) KiB gzipped" >&2
