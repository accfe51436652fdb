#!/usr/bin/env bash
# Builds hystbench and runs every test (installing missing Debian packages, test peers included).
# Default run: a few minutes. Opt-in longer runs (see README, "Tests"):
#   HYSTBENCH_LONG_TESTS=1  larger randomised sweeps, the 60 s / 10 kHz logging test, then a
#                           60 s libFuzzer run per target (scripts/fuzz.sh; fails on a new crasher)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh test
ctest --preset default "$@"
if [ -n "${HYSTBENCH_LONG_TESTS:-}" ]; then
  bash scripts/fuzz.sh "${HYSTBENCH_FUZZ_SECONDS:-60}"
fi
