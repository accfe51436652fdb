#!/usr/bin/env bash
# Builds hystbench and runs every test (installing missing Debian packages, test peers included).
# Default run: a few minutes. Opt-in longer runs (see README, "Tests"):
#   HYSTBENCH_LONG_TESTS=1  larger randomised sweeps and the 60 s / 10 kHz logging test
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh test
ctest --preset default "$@"
