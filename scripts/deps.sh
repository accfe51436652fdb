#!/usr/bin/env bash
# Installs the Debian 12 packages hystbench needs, only those that are missing.
# Usage: scripts/deps.sh [build|demo|test|fuzz|measure|all]   (default: build)
# Sourced by scripts/demo.sh and scripts/test.sh; safe to run again (no-op when all present).
set -euo pipefail

BUILD_PKGS=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libspdlog-dev libfmt-dev libtomlplusplus-dev nlohmann-json3-dev libcli11-dev
  libsystemd-dev libmodbus-dev libgpiod-dev libsocketcan-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox libcpp-httplib-dev
)
# Peers and tools used only by the test suite (independent implementations to test against).
# chromium and python3-websocket: the live view's test in a real browser (headless).
# clang-format: tests/source_limits.sh checks the C++ is formatted as .clang-format says.
TEST_PKGS=(python3 python3-pip python3-setuptools python3-wheel socat python3-pymodbus python3-serial python3-serial-asyncio mbpoll can-utils chromium python3-websocket clang-format)
# clang with the libFuzzer and sanitizer runtimes, for scripts/fuzz.sh only.
FUZZ_PKGS=(clang libclang-rt-14-dev)
# JSON and arithmetic on the command line, for the measurement scripts only.
MEASURE_PKGS=(jq bc)
# JSON on the command line, for scripts/demo.sh (the run logs from the results).
DEMO_PKGS=(jq)

want=("${BUILD_PKGS[@]}")
case "${1:-build}" in
  build) ;;
  demo) want+=("${DEMO_PKGS[@]}") ;;
  test) want+=("${TEST_PKGS[@]}") ;;
  fuzz) want+=("${FUZZ_PKGS[@]}") ;;
  measure) want+=("${MEASURE_PKGS[@]}") ;;
  all) want+=("${TEST_PKGS[@]}" "${FUZZ_PKGS[@]}" "${MEASURE_PKGS[@]}") ;;
  *) echo "usage: $0 [build|demo|test|fuzz|measure|all]" >&2; exit 2 ;;
esac

missing=()
for p in "${want[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "hystbench: installing missing Debian packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "hystbench: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
