#!/usr/bin/env bash
# Refreshes daemon/web/vendor/ (the page's plotting library, compiled into hystbenchd) from the
# versions pinned in daemon/web/package.json and package-lock.json.
# Usage: scripts/vendor-web.sh
# Needs node and npm (npm ci talks to the registry). node_modules is made in a temporary copy of
# daemon/web and removed again; nothing else in the tree changes. Prints each file's sha256.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
web="$root/daemon/web"
vendor="$web/vendor"

command -v npm >/dev/null || { echo "vendor-web.sh: npm not found (apt install npm)" >&2; exit 1; }

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cp "$web/package.json" "$web/package-lock.json" "$work/"
(cd "$work" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error >/dev/null)

pkg="$work/node_modules/uplot"
version="$(node -p "require('$pkg/package.json').version")"
for f in dist/uPlot.iife.min.js dist/uPlot.min.css LICENSE; do
  [[ -f "$pkg/$f" ]] || { echo "vendor-web.sh: uplot $version has no $f" >&2; exit 1; }
done

mkdir -p "$vendor"
cp "$pkg/dist/uPlot.iife.min.js" "$vendor/uPlot.iife.min.js"
cp "$pkg/dist/uPlot.min.css" "$vendor/uPlot.min.css"
cp "$pkg/LICENSE" "$vendor/uPlot.LICENSE"

echo "uplot $version -> ${vendor#"$root"/}/"
(cd "$vendor" && sha256sum uPlot.iife.min.js uPlot.min.css uPlot.LICENSE)
