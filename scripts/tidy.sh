#!/usr/bin/env bash
# clang-tidy with the project's checks (.clang-tidy, among them no function over 80 lines) on the
# production sources of every library and app; fails on any warning. Reads the compile commands of
# build-tidy/, a tree it configures (and never builds) file by file without precompiled headers:
# build/ compiles in unity batches with GCC's precompiled headers, which clang cannot read.
# About 6-12 minutes on 2 cores.
#   scripts/tidy.sh                 every source
#   scripts/tidy.sh daemon/src      the sources under a folder
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh >&2
cmake -S . -B build-tidy -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
  -DHYSTBENCH_TESTS=OFF -DHYSTBENCH_BENCH=OFF >/dev/null
filter=${1:-'(compensation|sim|drivers|common|daemon|cli)/(src|apps)/'}
out=$(mktemp)
status=0
run-clang-tidy -p build-tidy -quiet "$filter" >"$out" 2>&1 || status=$?
# Stopped by a signal: what it checked so far says nothing about the rest.
if [ "$status" -ge 128 ]; then
  echo "clang-tidy: interrupted (status $status) before it checked every source" >&2
  exit 1
fi
# A finding of a check, or a source clang-tidy could not compile (then it checked nothing there).
if sed -E 's/\x1b\[[0-9;]*m//g' "$out" |
  grep -E "(warning: .*\[[a-z-]+(\.[a-z-]+)*\]|error: )" | sort -u; then
  echo "clang-tidy: the findings above" >&2
  exit 1
fi
echo "clang-tidy: clean"
