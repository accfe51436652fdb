# Sourced by scripts/soak.sh and scripts/bench-report.sh: a throw-away hystbenchd on the
# loopback driver in a temp folder.
#   bench_tmp=$(mktemp -d); trap stop_daemon_and_clean EXIT
#   write_loopback_config FILE RATE_HZ REALTIME [EXTRA_TOML]
#   start_daemon CONFIG      (sets daemon_pid and sock; waits for the socket)
#   stop_daemon
daemon_pid=
write_loopback_config() {
  cat >"$1" <<TOML
[daemon]
log_level = "warn"
[loop]
rate_hz = $2
realtime = $3
overrun_budget = 1000000000
[limits]
u_min = 0.0
u_max = 150.0
y_min = 0.0
y_max = 44.0
[driver]
type = "loopback"
${4:-}
TOML
}
start_daemon() {
  sock=$bench_tmp/s.sock
  "$bin/hystbenchd" --config "$1" --socket "$sock" --log-dir "$bench_tmp/logs" \
    --model-dir "$bench_tmp/models" >>"$bench_tmp/daemon.log" 2>&1 &
  daemon_pid=$!
  for _ in $(seq 200); do [ -S "$sock" ] && break; sleep 0.05; done
  sleep 0.3
}
stop_daemon() {
  if [ -n "$daemon_pid" ]; then
    kill "$daemon_pid" 2>/dev/null || true
    wait "$daemon_pid" 2>/dev/null || true
  fi
  daemon_pid=
}
stop_daemon_and_clean() {
  stop_daemon
  rm -rf "$bench_tmp"
}
