#!/usr/bin/env bash
# Configures and builds hystbench into build/ (binaries in build/bin/). Installs missing packages first.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh "${1:-build}"
cmake --preset default >/dev/null
cmake --build --preset default -j "$(nproc)"
