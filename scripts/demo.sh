#!/usr/bin/env bash
# The main job on the loopback default: builds hystbench and hystbenchd (installing missing
# Debian packages), starts hystbenchd on the simulated actuator, tracks a 1 Hz triangle over
# 80 % of its range without compensation (the first result, before identify's minute on the
# wall clock), identifies it, tracks the triangle with the inverse model and with inverse + PID,
# and prints the results. Everything it writes goes to a temporary folder (printed at the end) unless
# HYSTBENCH_DEMO_DIR is set. No hardware, no root needed (real-time scheduling is used when
# permitted, otherwise the daemon says so and runs degraded).
set -euo pipefail
cd "$(dirname "$0")/.."
# Only what the demo runs (the CLI and the daemon, optimised without debug info, nlohmann/json and
# Eigen precompiled once for every library, each library compiled in unity batches of 8 files, by
# Ninja, which compiles the libraries side by side, none waiting for another's archive
# (CMAKE_OPTIMIZE_DEPENDENCIES), in build-demo/): the first output comes minutes sooner on a fresh
# machine than after building everything. scripts/build.sh builds everything, the tests too, the
# same way with line tables, in build/.
bash scripts/deps.sh demo >&2
source scripts/lib/ninja-tree.sh
ninja_tree_or_fresh build-demo
cmake --preset demo >/dev/null
echo "hystbench: building hystbench and hystbenchd in build-demo/ (the tests: scripts/test.sh)" >&2
cmake --build --preset demo -j "$(nproc)" >&2

work="${HYSTBENCH_DEMO_DIR:-$(mktemp -d -t hystbench-demo.XXXXXX)}"
mkdir -p "$work"
sock="$work/hystbench.sock"
export HYSTBENCH_SOCKET="$sock"
bin=build-demo/bin

"$bin/hystbenchd" --config config/loopback.toml --socket "$sock" \
  --log-dir "$work/logs" --model-dir "$work/models" >"$work/hystbenchd.log" 2>&1 &
daemon=$!
cleanup() {
  kill -TERM "$daemon" 2>/dev/null || true
  wait "$daemon" 2>/dev/null || true
}
trap cleanup EXIT

for _ in $(seq 100); do
  [ -S "$sock" ] && "$bin/hystbench" status >/dev/null 2>&1 && break
  kill -0 "$daemon" 2>/dev/null || { cat "$work/hystbenchd.log" >&2; exit 1; }
  sleep 0.1
done

echo "== hystbenchd on the loopback driver (simulated 150 V / 45 um piezo stack)"
grep -m1 "real-time" "$work/hystbenchd.log" || true
declare -A logs
# One track run with compensator $1: its result, and its log in logs[$1].
track() {
  "$bin/hystbench" track --reference triangle --frequency 1 --periods 5 --compensator "$1" \
    --wait --plot "$work/plots/$1"
  # The run's log, from its result: `status --json` keeps the result of the run just finished as
  # last_result (track --json would print that object instead of the human result above).
  logs[$1]=$("$bin/hystbench" status --json | jq -r '.last_result.log')
}
echo
echo "== track: 1 Hz triangle over 80 % of the range, 5 periods, no compensation (no model yet:"
echo "   the range is the configuration's, limits.y_min to limits.y_max)"
track none
echo
echo "== identify: play the identification excitation, fit, verify and extend the model"
"$bin/hystbench" identify --wait
for comp in inverse inverse+pid; do
  echo
  echo "== track: 1 Hz triangle over 80 % of the model's range, 5 periods, compensator '$comp'"
  track "$comp"
done
# One picture of the loop before and after compensation: output against reference, the scored
# periods of the runs without compensation and with the inverse (the README shows it).
gnuplot -e "none='${logs[none]}'; inverse='${logs[inverse]}'; out='$work/tracking.png'" \
  scripts/lib/demo-tracking.gp 2>/dev/null && echo && echo "picture: $work/tracking.png" || true
echo
echo "logs, models and plots: $work"
