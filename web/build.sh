#!/usr/bin/env bash
# Builds the static site into web/dist/: the whycode library compiled to
# WebAssembly (wasm-bindgen), the page's HTML/CSS/JS and an offline cache
# list. Works on a fresh machine with Rust (rustup), Python 3 and Node.js
# (npm): installs the wasm target, the wasm-bindgen CLI (the version
# Cargo.lock pins) and binaryen (npm) under the target directory when they
# are missing.
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
# crate's generated glue share a private format. It is installed under the
# target directory, so a different version installed for another project
# stays as it is.
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
if [ -z "$version" ]; then
    echo "web/build.sh: error: no wasm-bindgen version in Cargo.lock" >&2
    exit 1
fi
tools="$target_dir/web-tools"
PATH="$tools/bin:$HOME/.cargo/bin:$PATH"
if ! command -v wasm-bindgen >/dev/null 2>&1 || [ "$(wasm-bindgen --version | awk '{print $2}')" != "$version" ]; then
    echo "web/build.sh: installing wasm-bindgen-cli $version into $tools (a few minutes, once)" >&2
    # Built without LTO and with parallel codegen: it only rewrites a few
    # megabytes of WebAssembly, and an optimised build takes several times
    # as long. --locked first, for the CLI's own tested dependency set;
    # without it when one of those has since been yanked. Both attempts
    # share one target directory, so the second reuses what the first built.
    install() {
        CARGO_TARGET_DIR="$tools/build" CARGO_PROFILE_RELEASE_LTO=false \
            CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16 CARGO_PROFILE_RELEASE_OPT_LEVEL=1 \
            cargo install wasm-bindgen-cli --version "$version" --root "$tools" "$@"
    }
    echo "web/build.sh: trying the CLI's locked dependency set first; should one of them have been yanked since, cargo prints an error and the install is retried unlocked" >&2
    install --locked || install
    rm -rf "$tools/build"
fi
# Binaryen's wasm-opt and wasm-metadce, at a version that reads
# wasm-bindgen's externref table right (Debian 12's binaryen 108 exports
# the function table in its place, and the page fails to start), from npm.
binaryen_version=132.0.0
binaryen="$tools/npm/node_modules/binaryen"
if [ "$(node -p "require('$binaryen/package.json').version" 2>/dev/null)" != "$binaryen_version" ]; then
    if ! command -v npm >/dev/null 2>&1; then
        echo "web/build.sh: error: needs Node.js and npm (for binaryen's wasm-opt), e.g. apt-get install nodejs npm" >&2
        exit 1
    fi
    echo "web/build.sh: installing binaryen $binaryen_version from npm into $tools/npm" >&2
    mkdir -p "$tools/npm"
    npm install --silent --no-audit --no-fund --prefix "$tools/npm" "binaryen@$binaryen_version"
fi
wasm_opt="$tools/npm/node_modules/.bin/wasm-opt"
wasm_metadce="$tools/npm/node_modules/.bin/wasm-metadce"

staging="$here/dist.tmp"
rm -rf "$staging"
mkdir -p "$staging/pkg" "$staging/raw"

# Two modules of one crate (profile `web` in Cargo.toml: built for size).
# whycode_web, loaded by every visit, is the whole library except PDF
# output; whycode_pdf adds printpdf (with its PDF parser, fonts and ICC
# profile, as large again) and is fetched only when a PDF is made.
# `module`: output name, then cargo's extra arguments.
module() {
    local name=$1
    shift
    cargo build -p whycode-web --profile web --target wasm32-unknown-unknown "$@"
    wasm-bindgen --target web --no-typescript --out-name "$name" --out-dir "$staging/raw" \
        "$target_dir/wasm32-unknown-unknown/web/whycode_web.wasm"
    mv "$staging/raw/$name.js" "$staging/pkg/"
}
module whycode_web
module whycode_pdf --features pdf,files

# The PDF module keeps only what worker.js calls on it (see wasm_exports.py:
# printpdf's own JavaScript API goes, and all it alone reaches).
python3 "$here/wasm_exports.py" "$staging/raw/whycode_pdf_bg.wasm" "$staging/raw/graph.json" \
    sheet marker 'files_*' __wbg_files_free 'live_*' __wbg_live_free liveStride
"$wasm_metadce" "$staging/raw/whycode_pdf_bg.wasm" --graph-file "$staging/raw/graph.json" \
    -o "$staging/raw/whycode_pdf_bg.wasm" >/dev/null
# --converge runs -Oz's passes again until the module stops shrinking: about
# 1 KB off the first load, which must stay under 2,000,000 bytes.
pids=()
for name in whycode_web whycode_pdf; do
    "$wasm_opt" -Oz --converge --strip-debug --strip-producers "$staging/raw/${name}_bg.wasm" -o "$staging/pkg/${name}_bg.wasm" &
    pids+=($!)
done
for pid in "${pids[@]}"; do wait "$pid"; done
rm -rf "$staging/raw"
cp "$here/site/index.html" "$here/site/style.css" "$staging/"
# The scripts go out without their whole-line comments (the first load's budget).
for script in app.js worker.js; do
    python3 "$here/strip_comments.py" "$here/site/$script" "$staging/$script"
done

# The offline cache: every file of the site but the PDF module (cached when
# first used), under a version that changes with any file.
all=$(cd "$staging" && find . -type f | sed 's|^\./||' | sort)
files=$(echo "$all" | grep -v '^pkg/whycode_pdf')
hash=$(cd "$staging" && cat $all "$here/site/sw.js" | sha256sum | cut -c1-16)
list=$(printf '"./",'; for f in $files; do printf '"%s",' "$f"; done)
python3 "$here/strip_comments.py" "$here/site/sw.js" "$staging/sw.js.in"
sed -e "s|__VERSION__|$hash|" -e "s|__FILES__|[${list%,}]|" "$staging/sw.js.in" >"$staging/sw.js"
rm "$staging/sw.js.in"

rm -rf "$here/dist"
mv "$staging" "$here/dist"
first=$(cd "$here/dist" && cat pkg/whycode_web* *.js *.css | wc -c)
packed=$(cd "$here/dist" && cat pkg/whycode_web* *.js *.css | gzip -9 | wc -c)
pdf=$(cd "$here/dist" && cat pkg/whycode_pdf* | wc -c)
echo "web/build.sh: built web/dist: first load (wasm + JS + CSS) $((first / 1024)) KiB ($((packed / 1024)) KiB gzipped); PDF module $((pdf / 1024)) KiB, fetched on the first PDF" >&2
