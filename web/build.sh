#!/usr/bin/env bash
# build.sh [OUT_DIR]: installs web/'s npm packages exactly as package-lock.json pins them (npm ci,
# again only when the lock file changed) and bundles the browser viewer into OUT_DIR (default
# web/dist) with esbuild. Nothing the page needs is fetched at run time.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here/dist}
stamp="$here/node_modules/.package-lock.json"
if [ ! -f "$stamp" ] || [ "$here/package-lock.json" -nt "$stamp" ]; then
  (cd "$here" && npm ci --no-audit --no-fund --loglevel=error)
fi
node "$here/build.mjs" "$out"
