#!/usr/bin/env bash
# One command for the performance figures: builds the benchmark targets (build dir: $BUILD,
# default build/) and prints one table:
#   - ns per sample of every model and inverse at 10 / 50 / 200 operators (hystbench-bench)
#   - identification time on 100 000 samples, and the diagnosis of a mode and a delay on as many
#   - the learning's update for a trial of 10 000 and of 200 samples
#   - sample log writer throughput
#   - loop wake-up latency p50 / p99 / max and overruns of hystbenchd (loopback, a `hystbench
#     track --duration` run) at 1, 10 and 20 kHz, SCHED_OTHER and SCHED_FIFO, next to a bare
#     clock_nanosleep loop (hystbench-bare-loop) measured in the same run
#   - Modbus TCP loopback round trip (hystbenchd with config/modbus-tcp.toml against
#     hystbench-simdaq)
# HYSTBENCH_REPORT_SECONDS sets the length of each latency run (default 10).
# SCHED_FIFO needs CAP_SYS_NICE (or an rtprio limit); without it the "fifo" rows say "denied"
# and show SCHED_OTHER figures.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
seconds=${HYSTBENCH_REPORT_SECONDS:-10}
if [ -z "${HYSTBENCH_NO_BUILD:-}" ]; then
  bash scripts/deps.sh build >&2
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DHYSTBENCH_BENCH=ON >/dev/null
fi
[ -n "${HYSTBENCH_NO_BUILD:-}" ] || cmake --build "$build" -j2 --target hystbench-bench hystbench-bare-loop hystbench hystbenchd hystbench-simdaq >/dev/null
bin=$build/bin
bench_tmp=$(mktemp -d)
tmp=$bench_tmp
. scripts/lib/daemon.sh
trap stop_daemon_and_clean EXIT

echo "running benchmarks (models, inverses, identification, diagnosis, learning, log writer) ..." >&2
"$bin/hystbench-bench" --benchmark_filter='model_step|inverse_step|BM_IdentifyMpiFixedOrder/|BM_DiagnoseModeAndDelay|learning_update|BM_SampleLogWriterRows' \
  --benchmark_format=json >"$tmp/bench.json" 2>/dev/null

latency_rows=()
for rate in 1000 10000 20000; do
  for rt in false true; do
    echo "latency: ${rate} Hz, realtime=$rt, ${seconds} s (daemon, then bare loop) ..." >&2
    cfg=$tmp/d.toml
    write_loopback_config "$cfg" "$rate" "$rt" $'[driver.loopback]\nmax_rate_hz = 50000'
    start_daemon "$cfg"
    "$bin/hystbench" --socket "$sock" status --json >"$tmp/status.json" 2>/dev/null || true
    "$bin/hystbench" --socket "$sock" track --compensator none \
      --duration "$seconds" --wait --json >"$tmp/run.json" 2>/dev/null || true
    stop_daemon
    fifo=; [ "$rt" = true ] && fifo=--fifo
    "$bin/hystbench-bare-loop" "$rate" "$seconds" $fifo >"$tmp/bare.json"
    latency_rows+=("$rate $rt $(tail -n1 "$tmp/run.json" | tr -d ' \n' | base64 -w0) $(base64 -w0 <"$tmp/bare.json") $(tr -d '\n' <"$tmp/status.json" | base64 -w0)")
  done
done

echo "modbus: hystbenchd over Modbus TCP to hystbench-simdaq (config/modbus-tcp.toml), ${seconds} s track ..." >&2
"$bin/hystbench-simdaq" --port 0 >"$tmp/simdaq.out" 2>&1 &
simdaq_pid=$!
for _ in $(seq 100); do grep -q listening "$tmp/simdaq.out" && break; sleep 0.05; done
port=$(sed -n 's/.*:\([0-9]*\)$/\1/p' "$tmp/simdaq.out")
sed "s/^port = .*/port = $port/" config/modbus-tcp.toml >"$tmp/modbus.toml"
start_daemon "$tmp/modbus.toml"
"$bin/hystbench" --socket "$sock" track --compensator none --duration "$seconds" --wait --json \
  >"$tmp/modbus_run.json" 2>/dev/null || true
"$bin/hystbench" --socket "$sock" status --json >"$tmp/modbus_status.json" 2>/dev/null || true
stop_daemon
kill "$simdaq_pid" 2>/dev/null || true
wait "$simdaq_pid" 2>/dev/null || true

python3 - "$tmp/bench.json" "$tmp/modbus_run.json" "$tmp/modbus_status.json" "${latency_rows[@]}" <<'PY'
import base64, json, re, sys
bench = json.load(open(sys.argv[1]))["benchmarks"]
def ns_per_sample(b):
    if "items_per_second" in b: return 1e9 / b["items_per_second"]
    scale = {"ns": 1, "us": 1e3, "ms": 1e6, "s": 1e9}[b.get("time_unit", "ns")]
    return b["real_time"] * scale
table = {}
for b in bench:
    m = re.match(r"(model_step|inverse_step)/(\w+)/(\d+)$", b["name"])
    if m and b.get("run_type", "iteration") == "iteration":
        table.setdefault((m[1], m[2]), {})[int(m[3])] = ns_per_sample(b)
print("## Model and inverse step [ns per sample]\n")
print("| step | model | 10 ops | 50 ops | 200 ops |\n| --- | --- | ---: | ---: | ---: |")
for (kind, name), v in table.items():
    cells = " | ".join(f"{v[n]:.1f}" if n in v else "-" for n in (10, 50, 200))
    print(f"| {kind.split('_')[0]} | {name} | {cells} |")
print("\n## Identification, diagnosis, learning and logging\n\n| benchmark | figure |\n| --- | --- |")
for b in bench:
    if b["name"].startswith("BM_IdentifyMpiFixedOrder"):
        print(f"| {b['name']} (100 000 samples) | {b['real_time']:.0f} {b['time_unit']} |")
    if b["name"].startswith("BM_DiagnoseModeAndDelay"):
        print(f"| diagnose: a 3 kHz mode and a 2-sample delay (100 000 samples) | {b['real_time']:.0f} {b['time_unit']} |")
    if b["name"].startswith("learning_update/"):
        n = b["name"].split("/")[1]
        print(f"| learning update, a trial of {n} samples | {b['real_time']:.3f} {b['time_unit']} |")
    if b["name"].startswith("BM_SampleLogWriterRows"):
        print(f"| sample log writer (1 M rows to CSV, real time) | {b.get('items_per_second', 0)/1e6:.2f} M rows/s |")
print("\n## Loop wake-up latency [us] (daemon track run vs bare clock_nanosleep loop)\n")
print("| rate | policy | daemon p50 | p99 | max | overruns | bare p50 | p99 | max | overruns |")
print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
def load(path):
    try: text = open(path).read().strip()
    except OSError: return None
    for candidate in (text, text.splitlines()[-1] if text else ""):
        try: return json.loads(candidate)
        except ValueError: pass
    return None
modbus_run, modbus_status = load(sys.argv[2]), load(sys.argv[3])
for row in sys.argv[4:]:
    rate, rt, run64, bare64, status64 = (row.split(" ") + [""] * 5)[:5]
    dec = lambda s: json.loads(base64.b64decode(s) or b"null") if s else None
    try: run = dec(run64)
    except Exception: run = None
    bare = dec(bare64)
    try: status = dec(status64)
    except Exception: status = None
    policy = "SCHED_OTHER"
    if rt == "true":
        granted = bare.get("fifo_granted")
        policy = "SCHED_FIFO" if granted else "FIFO denied (OTHER)"
    res = (run or {}).get("result", run) or {}
    lat = res.get("loop", {}).get("wake_latency_ns", {})
    us = lambda x: f"{x/1000:.1f}" if isinstance(x, (int, float)) else "?"
    d = f"{us(lat.get('p50'))} | {us(lat.get('p99'))} | {us(lat.get('max'))} | {res.get('overruns', '?')}/{res.get('samples', '?')}"
    b = f"{us(bare['p50_ns'])} | {us(bare['p99_ns'])} | {us(bare['max_ns'])} | {bare['overruns']}/{bare['ticks']}"
    print(f"| {int(rate)//1000} kHz | {policy} | {d} | {b} |")
print("\n## Modbus TCP loopback (hystbenchd -> hystbench-simdaq, config/modbus-tcp.toml)\n")
st = ((modbus_status or {}).get("result", modbus_status) or {}).get("driver", {})
rtt = st.get("rtt_us", {})
res = (modbus_run or {}).get("result", modbus_run) or {}
if rtt:
    print("| transactions | failed | round trip p50 [us] | p99 | max | run samples | dropped | stale |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    print(f"| {st.get('transactions', '?')} | {st.get('failed_transactions', '?')} | {rtt.get('p50', '?')} | "
          f"{rtt.get('p99', '?')} | {rtt.get('max', '?')} | {res.get('samples', '?')} | "
          f"{res.get('dropped', res.get('dropped_samples', '?'))} | {res.get('stale_reads', '?')} |")
else:
    print("not measured: the Modbus run did not report (see hystbench-simdaq and hystbenchd output)")
PY
