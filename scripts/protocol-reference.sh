#!/usr/bin/env bash
# Writes docs/reference/protocol.md's parameter tables from the daemon's command table (the one
# place each request key is defined: common/include/hystbench/common/run_requests.hpp and
# daemon/src/service/details/command_table.cpp). Run after changing a key; the test
# ProtocolReference.EveryParameterTableIsTheOneTheCommandTableMakes fails until the page agrees.
# Needs a build (cmake --preset default && cmake --build build --target daemon_tests).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tests="$root/build/bin/daemon_tests"
[[ -x "$tests" ]] || { echo "protocol-reference: build $tests first (cmake --build build --target daemon_tests)" >&2; exit 1; }
HYSTBENCH_UPDATE_DOCS=1 "$tests" --gtest_filter='ProtocolReference.EveryParameterTableIsTheOneTheCommandTableMakes' >/dev/null
git -C "$root" diff --stat -- docs/reference/protocol.md
