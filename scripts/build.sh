#!/usr/bin/env bash
# Configures and builds hystbench into build/ (binaries in build/bin/): everything with the tests,
# optimised with line tables (-g1), in unity batches with precompiled headers, by Ninja. Installs
# missing packages first. A file that misses an include it uses shows in the debug preset, which
# compiles file by file without precompiled headers.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh "${1:-build}"
source scripts/lib/ninja-tree.sh
ninja_tree_or_fresh build
cmake --preset default >/dev/null
cmake --build --preset default -j "$(nproc)"
