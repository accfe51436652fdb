#!/usr/bin/env bash
# The loopback figures of docs/measurements.md, through the commands a user types with their
# defaults, on the simulated clock (the actuator sees the same samples as on the wall clock):
#   default    identify (held-out, verified), then a 1 Hz triangle over 80 % of the range with
#              none / inverse / inverse+pid (5 periods, the first unscored)
#   repeat     identify three times in one daemon, each followed by the 1 Hz triangle (inverse)
#   rate       rate dependence on (config/loopback-rate-dependent.toml): identify --model mpi,
#              rpi, preisach and auto, each followed by a sweep 1-200 Hz with inverse and
#              inverse+pid
#   thresholds rate dependence by widening thresholds (the rate-dependent loopback with
#              mechanism "switching_thresholds"): identify --model mpi, rpi and auto, each
#              followed by a sweep 1-19 Hz with inverse
#   delay      the delay on (default and modified-PI truths) and one mode at 800 Hz:
#              identify --no-extend and identify, each followed by 200 / 500 Hz sines (inverse)
#   campaign   wall time of identify + a 7-frequency sweep (inverse)
#   identify-time  on the wall clock, the delay on: identify --no-extend and identify, three
#              times each in one daemon; the wall time of each and how its diagnosis ran
#   learning   rate dependence, the delay and thermal drift on: identify, a sweep 1-500 Hz with
#              none / inverse / inverse+pid, then track --learn 10 at each frequency, each drive
#              replayed, and a raster line (--reference-file) learned over 10 passes
#   learning-delay  the same effects, the model identified with the delay off: track --learn 20
#              at each frequency; then 500 Hz alone on a fresh daemon, with its delay and without
#   learning-raster  the same effects: identify, the raster line learned over 10 passes and
#              replayed twice; then all of it again in the same daemon (a second identify)
#   learning-restart  the same effects: identify, track --learn 10 at 50 / 200 / 500 Hz, each
#              drive replayed; then a restarted daemon (its model loaded) replays them again
#   learning-scaled  the same effects: identify, its model's dead-zone weights x1.3 loaded,
#              track --learn 20 at each frequency over the identified model's reference range
#   feedback   the loop designed from the measured responses, on the default truth: identify
#              (the design, the frf's bench time), a 1 Hz triangle with none / inverse /
#              inverse+pid, sines of 10 / 50 / 100 Hz with inverse and inverse+pid, a 20 % step,
#              an AFM-like raster line (ramps and plateaus, 1.5 s period, --reference-file);
#              then identify again and the triangle with inverse+pid
#   feedback-variants  every truth variant on both loop rates (10 kHz; 1 kHz with a 190 Hz
#              mode): identify, the design, then a sweep below its crossover with inverse and
#              inverse+pid (rate dependence, the delay, one mode at 800 Hz, the modified-PI truth)
#   feedback-learning  a 1 kHz loop with a 190 Hz mode (zeta 0.07), rate dependence and creep
#              on: identify, then track --learn 10 at 20 and 50 Hz with inverse+pid
#   feedback-modbus  on the wall clock over Modbus TCP (io = "thread") to hystbench-simdaq at
#              1 kHz: identify, then two sweeps 1-20 Hz with inverse and inverse+pid; each run's
#              rms over every scored tick and over those 30 ticks or more after a stale reading;
#              then 20 and 10 Hz learned from inverse+pid (the floor a DAQ's clock sets)
# Usage: scripts/measure-loopback.sh [section ...]   (default: all; needs build/bin)
# Prints markdown tables; logs and models stay in the folder it names at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${HYSTBENCH_BIN:-build/bin}"
sections=("$@")
[ ${#sections[@]} -gt 0 ] || sections=(default repeat rate thresholds delay campaign identify-time learning learning-delay learning-raster learning-restart learning-scaled feedback feedback-variants feedback-learning feedback-modbus)
work="${HYSTBENCH_MEASURE_DIR:-$(mktemp -d -t hystbench-measure.XXXXXX)}"
mkdir -p "$work"
scripts/deps.sh measure

# stop PID: stops a process this script started (nothing for an empty PID).
stop() {
  [ -n "$1" ] || return 0
  kill "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}
daemon_pid=
stop_daemon() { stop "$daemon_pid"; daemon_pid=; }
# feedback-modbus's hystbench-simdaq, stopped with the daemon on the way out.
simdaq_pid=
stop_simdaq() { stop "$simdaq_pid"; simdaq_pid=; }
trap 'stop_daemon; stop_simdaq' EXIT
# start_daemon NAME CONFIG [EXTRA_TOML]: a daemon of its own folder on the simulated clock
# (on the wall clock with clock=wall).
clock=simulated
start_daemon() {
  local dir="$work/$1"
  mkdir -p "$dir"
  cp "$2" "$dir/config.toml"
  [ -z "${3:-}" ] || printf '%s\n' "$3" >>"$dir/config.toml"
  sock="$dir/s.sock"
  local clock_args=(--clock simulated)
  [ "$clock" = simulated ] || clock_args=()
  "$bin/hystbenchd" --config "$dir/config.toml" "${clock_args[@]}" --socket "$sock" \
    --log-dir "$dir/logs" --model-dir "$dir/models" >"$dir/daemon.log" 2>&1 &
  daemon_pid=$!
  for _ in $(seq 200); do
    [ -S "$sock" ] && "$bin/hystbench" --socket "$sock" status >/dev/null 2>&1 && return 0
    sleep 0.05
  done
  cat "$dir/daemon.log" >&2
  exit 1
}
hb() { "$bin/hystbench" --socket "$sock" "$@"; }
f3='def f: if . == null then "-" else (. * 1000 | round / 1000 | tostring) end;'
# The rate law a model file holds, with the thresholds law's power of the rate.
rate_law='(.model.rate // .model.preisach.rate) | if . == null then "-" elif .law == "thresholds" then "thresholds, |du/dt|^\(.threshold_exponent // 1)" else .law end'
# A learning run's row cells: every trial's rms, the last trial's rms and max (jq, after $f3).
trials_cells='\([.learning.trials[].rms_error_percent | f] | join(" ")) | \(.rms_error_percent | f) | \(.max_error_percent | f)'
# Rate dependence, the delay and thermal drift on: the learning sections' truth.
every_effect=$'[actuator.rate_dependence]\nenabled = true\n[actuator.delay]\nenabled = true\n[actuator.thermal_drift]\nenabled = true'

identify_row() {  # identify_row LABEL JSON
  jq -rn --argjson id "$2" --arg l "$1" "$f3"'
    "| \($l) | \($id.model.type // "?") \($id.model.operators // "?")/\($id.model.dead_zones // "?") | \($id.model.heldout.rmse_percent | f) | \(if $id.verification then "\($id.verification.rms_error_percent | f) / \($id.verification.max_error_percent | f)" else "-" end) |"'
}
track_row() {  # track_row LABEL JSON
  jq -rn --argjson t "$2" --arg l "$1" "$f3"'
    "| \($l) | \($t.rms_error_percent | f) | \($t.max_error_percent | f) | \($t.end) |"'
}
triangle() { hb track --reference triangle --frequency 1 --periods 5 --compensator "$1" --wait --json; }
# The design a result states (jq filter on its `feedback`), and the frf's bench time.
design='"\(.structure // .gains); crossover \(.crossover_hz | f) Hz, bandwidth \(.bandwidth_hz | f) Hz, |S| -20 dB from \(.tenfold_rejection_hz | f) Hz; GM >= \([.margins[].gain_margin_db] | min | f) dB, PM >= \([.margins[].phase_margin_deg] | min | f) deg, peak |S| <= \([.margins[].peak_sensitivity_db] | max | f) dB; limited by \(.limited_by // "-")"'
# identify, then one line: the model kept, the parts its extension adopted and the loop's design.
identify_design() {
  local id
  id=$(hb identify --wait --json || true)
  jq -r "$f3"'"\(.model.type) [\([.model.extension.parts[]?.cause] | join("+"))]: \(.feedback | '"$design"')"' <<<"$id" || true
}
# A 1 kHz bench with a 190 Hz mode (zeta 0.07): the loopback at 1 kHz with one mode.
slow_bench() {
  sed 's/^rate_hz = 10000/rate_hz = 1000/' config/loopback.toml >"$work/slow.toml"
  printf '[actuator.dynamics]\nnatural_frequencies_hz = [190.0]\ndamping_ratios = [0.07]\nmode_gains = [1.0]\n' >>"$work/slow.toml"
  echo "$work/slow.toml"
}
# AFM-like raster line: 8 -> 36 um in 0.6 s, 0.15 s plateau, back in 0.6 s, 0.15 s plateau;
# two periods at 5 kHz.
afm_line() {
  awk 'BEGIN { print "t,yr"; T = 1.5; for (k = 0; k <= 15000; k++) { t = k / 5000;
    p = (t - T * int(t / T)) / T;
    if (p < 0.4) y = 8 + 28 * p / 0.4; else if (p < 0.5) y = 36;
    else if (p < 0.9) y = 36 - 28 * (p - 0.5) / 0.4; else y = 8;
    printf "%.6f,%.6f\n", t, y } }' >"$1"
}

for section in "${sections[@]}"; do
  case "$section" in
    default)
      start_daemon default config/loopback.toml
      echo "### Default loopback: identify, then a 1 Hz triangle over 80 % of the range"
      echo "| identify | model | held-out rms % | verified rms / max % |"
      echo "| --- | --- | --- | --- |"
      identify_row mpi "$(hb identify --wait --json || true)"
      echo
      echo "| compensator | rms % | max % | end |"
      echo "| --- | --- | --- | --- |"
      for c in none inverse inverse+pid; do track_row "$c" "$(triangle "$c" || true)"; done
      echo
      stop_daemon
      ;;
    repeat)
      start_daemon repeat config/loopback.toml
      echo "### Identify three times in one daemon, each followed by the 1 Hz triangle (inverse)"
      echo "| identify | model | held-out rms % | verified rms / max % | tracking rms % | tracking max % |"
      echo "| --- | --- | --- | --- | --- | --- |"
      for i in 1 2 3; do
        id=$(hb identify --wait --json || true)
        tr=$(triangle inverse || true)
        echo "$(identify_row "$i" "$id" | sed 's/ |$//') | $(jq -rn --argjson t "$tr" "$f3"'"\($t.rms_error_percent | f) | \($t.max_error_percent | f) |"')"
      done
      echo
      stop_daemon
      ;;
    rate)
      start_daemon rate config/loopback-rate-dependent.toml
      echo "### Rate dependence on: identify --model M, then a sweep (rms % of range)"
      for m in mpi rpi preisach auto; do
        id=$(hb identify --model "$m" --wait --json || true)
        law=$(hb model get --json | jq -r "$rate_law" || true)
        echo
        echo "identify --model $m (rate law $law): $(identify_row "$m" "$id")"
        echo
        hb sweep --frequencies 1,5,10,19,50,100,200 --compensators inverse,inverse+pid || true
      done
      echo
      stop_daemon
      ;;
    thresholds)
      start_daemon thresholds config/loopback-rate-dependent.toml \
        'mechanism = "switching_thresholds"'
      echo "### Widening thresholds: identify --model M, then a sweep (rms % of range)"
      for m in mpi rpi auto; do
        id=$(hb identify --model "$m" --wait --json || true)
        law=$(hb model get --json | jq -r "$rate_law" || true)
        echo
        echo "identify --model $m (rate law $law): $(identify_row "$m" "$id")"
        echo
        hb sweep --frequencies 1,5,10,19 --compensators inverse || true
      done
      echo
      stop_daemon
      ;;
    learning)
      start_daemon learning config/loopback.toml "$every_effect"
      echo "### Every effect on: identify, then sines without and with learning (rms % of range)"
      echo
      echo "identify: $(identify_row default "$(hb identify --wait --json || true)")"
      echo
      hb sweep --frequencies 1,10,50,200,500 --compensators none,inverse,inverse+pid || true
      echo
      echo "| f [Hz] | trials (rms %, the first the inverse's) | last rms % | last max % | update ms |"
      echo "| --- | --- | --- | --- | --- |"
      declare -A drives=()
      for f in 1 10 50 200 500; do
        out=$(hb track --reference sine --frequency "$f" --learn 10 --wait --json || true)
        drives[$f]=$(jq -r '.learning.drive // empty' <<<"$out")
        jq -r --arg f "$f" "$f3"'
          "| \($f) | '"$trials_cells"' | \(.learning.update_ms.mean | f) |"' <<<"$out" || true
      done
      echo
      echo "Each learned drive replayed (track --learned NAME, no new trial):"
      echo
      echo "| f [Hz] | replay rms % | replay max % |"
      echo "| --- | --- | --- |"
      for f in 1 10 50 200 500; do
        [ -n "${drives[$f]:-}" ] || continue
        hb track --reference sine --frequency "$f" --learned "${drives[$f]}" --wait --json |
          jq -r --arg f "$f" "$f3"'"| \($f) | \(.rms_error_percent | f) | \(.max_error_percent | f) |"' || true
      done
      echo
      # The raster line of the upload figures: an 8-36 um triangle at 2.5 Hz, 2 s in a 5 kHz file.
      raster="$work/learning/raster.csv"
      awk 'BEGIN { print "t,yr"; for (k = 0; k <= 10000; k++) { t = k / 5000; p = 2.5 * t - int(2.5 * t);
        printf "%.6f,%.6f\n", t, 8 + 28 * (p < 0.5 ? 2 * p : 2 - 2 * p) } }' >"$raster"
      echo "A raster line learned over 10 passes (track --reference-file raster.csv --learn 10):"
      echo
      out=$(hb track --reference-file "$raster" --learn 10 --wait --json || true)
      jq -r "$f3"'"passes (rms %): \([.learning.trials[].rms_error_percent | f] | join(" ")); last max \(.max_error_percent | f) %; cut-off \(.learning.cutoff_hz | f) Hz"' <<<"$out" || true
      name=$(jq -r '.learning.drive // empty' <<<"$out")
      [ -z "$name" ] || hb track --reference-file "$raster" --learned "$name" --wait --json |
        jq -r "$f3"'"replayed: \(.rms_error_percent | f) % rms"' || true
      echo
      stop_daemon
      ;;
    learning-raster)
      start_daemon learning-raster config/loopback.toml "$every_effect"
      raster="$work/learning-raster/raster.csv"
      awk 'BEGIN { print "t,yr"; for (k = 0; k <= 10000; k++) { t = k / 5000; p = 2.5 * t - int(2.5 * t);
        printf "%.6f,%.6f\n", t, 8 + 28 * (p < 0.5 ? 2 * p : 2 - 2 * p) } }' >"$raster"
      echo "### A raster line learned over 10 passes after identify, replayed twice; twice in one daemon"
      echo "| identify | passes (rms %) | replays (rms %) |"
      echo "| --- | --- | --- |"
      for round in first second; do
        hb identify --wait --json >/dev/null || true
        out=$(hb track --reference-file "$raster" --learn 10 --wait --json || true)
        name=$(jq -r '.learning.drive // empty' <<<"$out")
        replays=""
        for _ in 1 2; do
          [ -z "$name" ] || replays="$replays $(hb track --reference-file "$raster" --learned "$name" \
            --wait --json | jq -r "$f3"' .rms_error_percent | f' || true)"
        done
        jq -r --arg r "$round" --arg p "$replays" "$f3"'"| \($r) | \([.learning.trials[].rms_error_percent | f] | join(" ")) | \($p) |"' <<<"$out" || true
      done
      echo
      stop_daemon
      ;;
    learning-restart)
      start_daemon learning-restart config/loopback.toml "$every_effect"
      model=$(hb identify --wait --json | jq -r '.model.path')
      echo "### Learned drives replayed on the same bench and after a restart (rms % of range)"
      echo
      echo "| f [Hz] | last trial | same bench | after a restart | its lead-in |"
      echo "| --- | --- | --- | --- | --- |"
      declare -A last=() same=() names=()
      for f in 50 200 500; do
        out=$(hb track --reference sine --frequency "$f" --learn 10 --wait --json || true)
        names[$f]=$(jq -r '.learning.drive // empty' <<<"$out")
        last[$f]=$(jq -r "$f3"' .rms_error_percent | f' <<<"$out" || true)
        [ -z "${names[$f]}" ] || same[$f]=$(hb track --reference sine --frequency "$f" \
          --learned "${names[$f]}" --wait --json | jq -r "$f3"' .rms_error_percent | f' || true)
      done
      stop_daemon
      start_daemon learning-restart config/loopback.toml "$every_effect"
      hb model load --stored "$(basename "$model")" >/dev/null
      for f in 50 200 500; do
        [ -n "${names[$f]:-}" ] || continue
        hb track --reference sine --frequency "$f" --learned "${names[$f]}" --wait --json |
          jq -r --arg f "$f" --arg l "${last[$f]}" --arg s "${same[$f]:-}" "$f3"'
          "| \($f) | \($l) | \($s) | \(.rms_error_percent | f) | \(.learning.lead_in_periods / .learning.frequency_hz | f) s: \(.learning.lead_in_end) |"' || true
      done
      echo
      stop_daemon
      ;;
    learning-scaled)
      start_daemon learning-scaled config/loopback.toml "$every_effect"
      model=$(hb identify --wait --json | jq -r '.model.path')
      # The identified model's reference range: the scaled model's own range is 1.3x wider.
      log=$(hb track --reference sine --frequency 10 --periods 2 --wait --json | jq -r '.log')
      range=$(grep -m1 '^# {"run"' "$log" | cut -c3- | jq -r '.run | "\(.min_um) \(.max_um)"')
      read -r ymin ymax <<<"$range"
      # The output map the identified family holds: an mpi's dead zones, a plane's output map.
      jq 'if .deadzone then .deadzone.weights |= map(. * 1.3)
          else .preisach.output_map.weights |= map(. * 1.3) end' "$model" \
        >"$work/learning-scaled/scaled.json"
      hb model load "$work/learning-scaled/scaled.json" >/dev/null
      echo "### The model's output map 1.3x too steep, learning over the identified model's range"
      echo
      echo "| f [Hz] | trials (rms %, the first the inverse's) | last rms % | last max % |"
      echo "| --- | --- | --- | --- |"
      for f in 1 10 50 200 500; do
        hb track --reference sine --frequency "$f" --min "$ymin" --max "$ymax" --learn 20 \
          --wait --json | jq -r --arg f "$f" "$f3"'
          "| \($f) | '"$trials_cells"' |"' || true
      done
      echo
      stop_daemon
      ;;
    learning-delay)
      start_daemon learning-delay-off config/loopback.toml $'[actuator.rate_dependence]\nenabled = true\n[actuator.thermal_drift]\nenabled = true'
      model=$(hb identify --wait --json | jq -r '.model.path')
      stop_daemon
      start_daemon learning-delay-on config/loopback.toml "$every_effect"
      hb model load "$model" >/dev/null
      echo "### The model identified with the delay off, learning with it on (rms % of range)"
      echo
      echo "| f [Hz] | trials (rms %, the first the inverse's) | last rms % | last max % | delay ticks: model, used |"
      echo "| --- | --- | --- | --- | --- |"
      for f in 1 10 50 200 500; do
        hb track --reference sine --frequency "$f" --learn 20 --wait --json |
          jq -r --arg f "$f" "$f3"'
          "| \($f) | '"$trials_cells"' | \(.learning.delay_ticks.model | f), \(.learning.delay_ticks.used | f) |"' || true
      done
      echo
      stop_daemon
      # 500 Hz alone on a fresh daemon, with the model as identify kept it and without any tick
      # of delay (an identify with the delay off keeps one or none).
      echo "500 Hz alone, 20 trials (the model's delay: trials rms %, last rms / max %, above Q):"
      for ticks in kept none; do
        start_daemon "learning-delay-alone-$ticks" config/loopback.toml "$every_effect"
        if [ "$ticks" = none ]; then
          jq '.delay_s = 0' "$model" >"$work/learning-delay-alone-none/no-delay.json"
          hb model load "$work/learning-delay-alone-none/no-delay.json" >/dev/null
        else
          hb model load "$model" >/dev/null
        fi
        hb track --reference sine --frequency 500 --learn 20 --wait --json |
          jq -r --arg t "$ticks" "$f3"'"- \($t) (\(.learning.delay_ticks.model | f) ticks): '"$trials_cells"' | \(.learning.above_cutoff.updates) updates through \(.learning.above_cutoff.mode_hz // 0 | round) Hz"' || true
        stop_daemon
      done
      echo
      ;;
    delay)
      # identify extends its model itself; --no-extend is the model without it. Three truths:
      # the default with the delay on, the modified-PI truth with it, one mode at 800 Hz.
      for truth in default-delay mpi-delay mode-800; do
        case "$truth" in
          default-delay) extra=$'[actuator.delay]\nenabled = true' ;;
          mpi-delay) extra=$'[actuator.hysteresis]\nkind = "modified_pi"\n[actuator.delay]\nenabled = true' ;;
          mode-800) extra=$'[actuator.dynamics]\nnatural_frequencies_hz = [800.0]\ndamping_ratios = [0.06]\nmode_gains = [1.0]\nenabled = true' ;;
        esac
        start_daemon "delay-$truth" config/loopback.toml "$extra"
        echo "### $truth: identify --no-extend, then identify (extended), sines of 20 periods"
        echo "| identify | parts | adopted | diagnosis s | 200 Hz rms % | 500 Hz rms % |"
        echo "| --- | --- | --- | --- | --- | --- |"
        for how in --no-extend ""; do
          start=$(date +%s.%N)
          id=$(hb identify $how --wait --json || true)
          end=$(date +%s.%N)
          r200=$(hb track --reference sine --frequency 200 --periods 20 --compensator inverse \
            --wait --json | jq -r "$f3"' .rms_error_percent | f' || true)
          r500=$(hb track --reference sine --frequency 500 --periods 20 --compensator inverse \
            --wait --json | jq -r "$f3"' .rms_error_percent | f' || true)
          jq -rn --argjson id "$id" --arg how "${how:-extend}" --arg r200 "$r200" \
            --arg r500 "$r500" --arg s "$(echo "$end - $start" | bc -l)" "$f3"'
            "| \($how) (\($s | tonumber | f) s) | \([$id.model.extension.parts[]?.cause] | join("+"))\($id.model.extension.timing // null | if . then "; timed \(.natural_frequency_hz | f) Hz, ζ \(.damping_ratio | f), \(.delay_samples | f) samples" else "" end) | \($id.model.extension.adopted) | \($id.model.extension.diagnosis_s | f) | \($r200) | \($r500) |"'
        done
        echo
        stop_daemon
      done
      ;;
    campaign)
      start_daemon campaign config/loopback.toml
      echo "### Wall time of identify + a 7-frequency sweep on the simulated clock"
      start=$(date +%s.%N)
      hb identify --wait --json >/dev/null || true
      hb sweep --frequencies 1,5,10,19,50,100,200 --compensators inverse >/dev/null || true
      end=$(date +%s.%N)
      printf 'identify + sweep: %.1f s of wall time\n\n' "$(echo "$end - $start" | bc -l)"
      stop_daemon
      ;;
    identify-time)
      clock=wall
      start_daemon identify-time config/loopback.toml $'[actuator.delay]\nenabled = true'
      clock=simulated
      echo "### Wall time of identify on the wall clock, the delay on"
      echo "| identify | wall s | parts | adopted | diagnosis ran | diagnosis s after the verification |"
      echo "| --- | --- | --- | --- | --- | --- |"
      for _ in 1 2 3; do
        for how in --no-extend ""; do
          start=$(date +%s.%N)
          id=$(hb identify $how --wait --json || true)
          end=$(date +%s.%N)
          jq -rn --argjson id "$id" --arg how "${how:-extend}" \
            --arg s "$(echo "$end - $start" | bc -l)" "$f3"'
            "| \($how) | \($s | tonumber | f) | \([$id.model.extension.parts[]?.cause] | join("+")) | \($id.model.extension.adopted // "-") | \($id.model.extension.diagnosis_ran // "-") | \($id.model.extension.diagnosis_s | f) |"'
        done
      done
      echo
      stop_daemon
      ;;
    feedback)
      start_daemon feedback config/loopback.toml
      echo "### The loop designed from the measured responses (default truth, 10 kHz)"
      id=$(hb identify --wait --json || true)
      frf_log=$(jq -r '.frequency_response.log // empty' <<<"$id")
      echo
      echo "identify: $(identify_row default "$id")"
      jq -r "$f3"'"- design: \(.feedback | '"$design"')"' <<<"$id" || true
      jq -r "$f3"'"- while moving: \(.frequency_response.moving | "the \(.lagging) ramps lag by \(.lag_deg | f) +/- \(.lag_noise_deg | f) deg at \(.frequency_hz | f) Hz, zero \(.zero_hz | f) Hz")"' <<<"$id" || true
      [ -z "$frf_log" ] || echo "- frf: $(grep -vc '^#' "$frf_log") samples ($(grep -vc '^#' "$frf_log" | awk '{ printf "%.1f", ($1 - 1) / 10000 }') s of bench time)"
      echo
      echo "| run | compensator | rms % | max % | end |"
      echo "| --- | --- | --- | --- | --- |"
      for c in none inverse inverse+pid; do track_row "1 Hz triangle | $c" "$(triangle "$c" || true)"; done
      for f in 10 50 100; do
        for c in inverse inverse+pid; do
          track_row "$f Hz sine | $c" "$(hb track --reference sine --frequency "$f" --compensator "$c" --wait --json || true)"
        done
      done
      afm_line "$work/feedback/afm.csv"
      for c in none inverse inverse+pid; do
        track_row "raster line | $c" "$(hb track --reference-file "$work/feedback/afm.csv" --compensator "$c" --wait --json || true)"
      done
      echo
      hb track --reference step --frequency 10 --periods 6 --compensator inverse+pid --wait --json |
        jq -r "$f3"'"20 % step (10 moves): settled \(.step.settled), settling max \(.step.settling_ms.max | f) ms, overshoot max \(.step.overshoot_percent.max | f) %"' || true
      id=$(hb identify --wait --json || true)
      jq -r "$f3"'"second identify: \(.feedback | '"$design"')"' <<<"$id" || true
      track_row "second identify, 1 Hz triangle | inverse+pid" "$(triangle inverse+pid || true)"
      echo
      stop_daemon
      ;;
    feedback-variants)
      slow=$(slow_bench)
      for truth in rate delay mode-800 mpi; do
        case "$truth" in
          rate) extra=$'[actuator.rate_dependence]\nenabled = true' ;;
          delay) extra=$'[actuator.delay]\nenabled = true' ;;
          mode-800) extra=$'[actuator.dynamics]\nnatural_frequencies_hz = [800.0]\ndamping_ratios = [0.06]\nmode_gains = [1.0]\nenabled = true' ;;
          mpi) extra=$'[actuator.hysteresis]\nkind = "modified_pi"' ;;
        esac
        for bench in 10k 1k; do
          config=config/loopback.toml
          freqs=1,5,10,20,50,100
          if [ "$bench" = 1k ]; then
            config=$slow
            freqs=1,5,10,20
            # One mode only: the 190 Hz one, or the variant's own.
            [ "$truth" = mode-800 ] && continue
          fi
          start_daemon "variant-$truth-$bench" "$config" "$extra"
          echo "### $truth truth, $bench loop"
          identify_design
          echo
          hb sweep --frequencies "$freqs" --compensators inverse,inverse+pid || true
          echo
          stop_daemon
        done
      done
      ;;
    feedback-learning)
      slow=$(slow_bench)
      start_daemon feedback-learning "$slow" $'[actuator.rate_dependence]\nenabled = true'
      echo "### 1 kHz loop, a 190 Hz mode, rate dependence and creep on: learning with the default compensator (inverse) and with inverse+pid"
      identify_design
      echo
      echo "| compensator | f [Hz] | trials (rms %, the first the compensator's) | last rms % | last max % | floor % | why it ended |"
      echo "| --- | --- | --- | --- | --- | --- | --- |"
      for c in inverse+pid default; do
        for f in 20 50; do
          compensator=()
          [ "$c" = default ] || compensator=(--compensator "$c")
          hb track --reference sine --frequency "$f" "${compensator[@]}" --learn 10 --wait --json |
            jq -r --arg c "$c" --arg f "$f" "$f3"'"| \($c) | \($f) | '"$trials_cells"' | \(.learning.floor.rms_error_percent | f) | \(.learning.why // "-") |"' || true
        done
      done
      echo
      stop_daemon
      ;;
    feedback-modbus)
      port=15502
      "$bin/hystbench-simdaq" --port "$port" >"$work/simdaq.log" 2>&1 &
      simdaq_pid=$!
      sed "s/^rate_hz = 5000/rate_hz = 1000/; s/^port = 1502/port = $port/" config/modbus-tcp.toml \
        >"$work/modbus-1k.toml"
      clock=wall
      start_daemon feedback-modbus "$work/modbus-1k.toml"
      clock=simulated
      echo "### Modbus TCP to hystbench-simdaq, 1 kHz, wall clock"
      identify_design
      echo
      echo "| sweep | f [Hz] | compensator | rms % | max % | rms % 30 ticks or more after a stale reading (share of the scored ticks) |"
      echo "| --- | --- | --- | --- | --- | --- |"
      for sweep in 1 2; do
        hb sweep --frequencies 1,5,10,20 --compensators inverse,inverse+pid --json >"$work/modbus-sweep$sweep.json" || true
        python3 - "$work/modbus-sweep$sweep.json" "$sweep" <<'PY'
import csv, json, math, sys
for r in json.load(open(sys.argv[1]))["rows"]:
    lines = open(r["log"]).read().splitlines()
    header = [json.loads(l[2:]) for l in lines if l.startswith("# {")]
    run = next(h["run"] for h in header if "run" in h)
    stale = next(h["flags"]["stale"] for h in header if "flags" in h)
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    clear, last_stale = [], -10**9
    for k, row in enumerate(rows):
        if int(row["flags"]) & stale:
            last_stale = k
        if k >= run["metrics_from"] and k - last_stale >= 30:
            clear.append(float(row["y"]) - float(row["yr"]))
    rms = math.sqrt(sum(e * e for e in clear) / len(clear)) * 100 / r["range_um"] if clear else float("nan")
    share = len(clear) / max(1, len(rows) - run["metrics_from"])
    print(f"| {sys.argv[2]} | {r['frequency_hz']:g} | {r['compensator']} | {r['rms_error_percent']:.3f} | "
          f"{r['max_error_percent']:.2f} | {rms:.3f} ({share:.0%}) |")
PY
      done
      echo
      # Learning where a repeated drive does not give a repeated output (the exchange's clock):
      # the floor, measured again where a trial reaches it, and where the learning ended.
      echo "| f [Hz] | trials (rms %, the first the compensator's), drives | floor % (trials 0 and 1) | floor % (the pair) | why it ended |"
      echo "| --- | --- | --- | --- | --- |"
      for f in 20 10; do
        hb track --reference sine --frequency "$f" --compensator inverse+pid --learn 10 --wait --json |
          jq -r --arg f "$f" "$f3"'"| \($f) | \([.learning.trials[] | "\(.rms_error_percent | f) \(.drive)"] | join(", ")) | \(.learning.floor.first_rms_error_percent | f) | \(.learning.floor.rms_error_percent | f) (trials \(.learning.floor.trials | map(tostring) | join(" and "))) | \(.learning.why) |"' || true
      done
      echo
      stop_daemon
      stop_simdaq
      ;;
    *)
      echo "measure-loopback: unknown section '$section' (default repeat rate thresholds delay campaign identify-time learning learning-delay learning-raster learning-restart learning-scaled feedback feedback-variants feedback-learning feedback-modbus)" >&2
      exit 2
      ;;
  esac
done
echo "(logs and models in $work)"
