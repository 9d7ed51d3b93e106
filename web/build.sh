#!/usr/bin/env bash
# Builds the page into web/site: abut-web for wasm32 with Debian's rustc-web (-Zbuild-std;
# docs/BROWSER.md), bound by wasm-bindgen-cli at the lock file's version, beside index.html
# and main.js. Serve web/site statically, e.g. `python3 -m http.server -d web/site 8000`, and
# open http://localhost:8000 in a browser with WebGPU.
set -euo pipefail
cd "$(dirname "$0")/.."
PATH="/usr/bin:$PATH:${CARGO_HOME:-$HOME/.cargo}/bin" RUSTC_BOOTSTRAP=1 CARGO_TARGET_DIR=target/wasm32 \
  /usr/bin/cargo rustc -p abut-web --release --target wasm32-unknown-unknown \
  -Zbuild-std=std,panic_abort -- -D warnings
mkdir -p web/site
PATH="$PATH:${CARGO_HOME:-$HOME/.cargo}/bin" wasm-bindgen --target web --no-typescript \
  --out-dir web/site/pkg target/wasm32/wasm32-unknown-unknown/release/abut_web.wasm
cp web/index.html web/main.js web/site/
du -b web/site/pkg/abut_web_bg.wasm web/site/pkg/abut_web.js web/site/index.html web/site/main.js
