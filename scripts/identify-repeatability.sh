#!/usr/bin/env bash
# Is identification repeatable on a bench with a history? Starts hystbenchd on the
# loopback default and, in that one daemon, runs `identify --model M` then `track` (1 Hz
# triangle, 5 periods, inverse) for every M given (default: mpi mpi cpi mpi), printing one table
# row per pair: held-out error, verified error (when identify reports one), tracking error.
# Usage: scripts/identify-repeatability.sh [model ...]   (needs build/bin; see scripts/build.sh)
# HYSTBENCH_REPEAT_CONFIG=FILE runs another daemon config (default config/loopback.toml).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh measure
models=("$@")
[ ${#models[@]} -gt 0 ] || models=(mpi mpi cpi mpi)
bin="${HYSTBENCH_BIN:-build/bin}"
bench_tmp="${HYSTBENCH_REPEAT_DIR:-$(mktemp -d -t hystbench-repeat.XXXXXX)}"
mkdir -p "$bench_tmp"
. scripts/lib/daemon.sh
trap stop_daemon EXIT
start_daemon "${HYSTBENCH_REPEAT_CONFIG:-config/loopback.toml}"
printf '| identify | model | held-out rms %% | verified rms / max %% | tracking rms %% | tracking max %% |\n'
printf '| --- | --- | --- | --- | --- | --- |\n'
for m in "${models[@]}"; do
  id=$("$bin/hystbench" --socket "$sock" identify --model "$m" --wait --json) || true
  tr=$("$bin/hystbench" --socket "$sock" track --reference triangle --frequency 1 --periods 5 \
    --compensator inverse --wait --json) || true
  jq -rn --argjson id "$id" --argjson tr "$tr" --arg m "$m" '
    def f: if . == null then "-" else (. * 1000 | round / 1000 | tostring) end;
    "| \($m) | \($id.model.type // "?") \($id.model.operators // "?")/\($id.model.dead_zones // "?") | \($id.model.heldout.rmse_percent | f) | \(if $id.verification then "\($id.verification.rms_error_percent | f) / \($id.verification.max_error_percent | f)" else "-" end) | \($tr.rms_error_percent | f) | \($tr.max_error_percent | f) |"'
done
echo "(logs and models in $bench_tmp)"
