#!/usr/bin/env bash
# Opt-in soak: hystbenchd on the loopback driver at 10 kHz, one tracking run of
# HYSTBENCH_SOAK_SECONDS (default 3600) with a status request every HYSTBENCH_SOAK_POLL seconds
# (default 5) sampling the daemon's VmRSS. Prints a summary and fails (exit 1) when a sample was
# dropped, the run did not complete, or VmRSS grew by more than HYSTBENCH_SOAK_RSS_SLACK_KB
# (default 8192) from the third poll (warm-up) to its peak. Overruns are reported.
# The run log (about 110 bytes per sample, ~4 GB per hour) goes to a temp folder, deleted after.
#   BUILD=build scripts/soak.sh   (HYSTBENCH_NO_BUILD=1: use the binaries as they are)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
seconds=${HYSTBENCH_SOAK_SECONDS:-3600}
poll=${HYSTBENCH_SOAK_POLL:-5}
slack=${HYSTBENCH_SOAK_RSS_SLACK_KB:-8192}
[ -n "${HYSTBENCH_NO_BUILD:-}" ] || cmake --build "$build" -j2 --target hystbench hystbenchd >/dev/null
bench_tmp=$(mktemp -d)
tmp=$bench_tmp
# The soak runs from its own copy of the binaries: a rebuild during the hour must not pull them
# away from under the status polls.
mkdir "$tmp/bin"
cp "$build/bin/hystbench" "$build/bin/hystbenchd" "$tmp/bin/"
bin=$tmp/bin
. scripts/lib/daemon.sh
trap stop_daemon_and_clean EXIT
write_loopback_config "$tmp/soak.toml" 10000 true
start_daemon "$tmp/soak.toml"
hb() { "$bin/hystbench" --socket "$sock" "$@"; }
rss() { awk '/^VmRSS:/ {print $2}' "/proc/$daemon_pid/status"; }

echo "soak: ${seconds} s at 10 kHz (loopback), status every ${poll} s" >&2
hb track --compensator none --duration "$seconds" --json >"$tmp/start.json"
rss_samples=()
polls=0
failed_polls=0
start=$(date +%s)
while :; do
  sleep "$poll"
  if ! hb status --json >"$tmp/status.json" 2>/dev/null; then failed_polls=$((failed_polls + 1)); fi
  polls=$((polls + 1))
  rss_samples+=("$(rss)")
  state=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1])).get("state",""))' \
    "$tmp/status.json" 2>/dev/null || echo "?")
  elapsed=$(($(date +%s) - start))
  printf '\r  %5d s  state %-9s VmRSS %s kB ' "$elapsed" "$state" "${rss_samples[-1]}" >&2
  [ "$state" = running ] || break
  [ "$elapsed" -gt $((seconds + 120)) ] && break
done
echo >&2
hb status --json >"$tmp/final.json"
python3 - "$tmp/final.json" "$slack" "$polls" "$failed_polls" "${rss_samples[@]}" <<'PY'
import json, sys
status = json.load(open(sys.argv[1]))
slack, polls, failed = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
rss = [int(x) for x in sys.argv[5:] if x]
r = status.get("last_result") or {}
lat = r.get("loop", {}).get("wake_latency_ns", {})
warm = rss[min(2, len(rss) - 1)] if rss else 0
growth = (max(rss[2:] or rss) - warm) if rss else 0  # the peak after warm-up, not the idle end
print("== soak summary")
print(f"run           {r.get('run_id')}  end {r.get('end')}  {r.get('reason') or ''}")
print(f"samples       {r.get('samples')} of {r.get('planned_samples')}, logged {r.get('logged')}, dropped {r.get('dropped')}")
print(f"overruns      {r.get('overruns')}")
print(f"wake latency  p50 {lat.get('p50')} ns, p99 {lat.get('p99')} ns, max {lat.get('max')} ns")
print(f"status polls  {polls} ({failed} failed)")
print(f"VmRSS [kB]    first {rss[0] if rss else '?'}, after warm-up {warm}, min {min(rss) if rss else '?'}, max {max(rss) if rss else '?'}, last {rss[-1] if rss else '?'} (growth {growth} kB, slack {slack})")
ok = r.get("end") == "completed" and r.get("dropped") == 0 and growth <= slack and failed == 0
print("result        " + ("PASS" if ok else "FAIL"))
sys.exit(0 if ok else 1)
PY
