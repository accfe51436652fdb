#!/usr/bin/env bash
# The CubeSpec fine-steering-mirror benchmark (3 piezo voltages in, 3 displacements out) through
# the commands a user types: `hystbench convert` of the .npy sets, `hystbench fit` of the three
# train sets (100, 200, 300 mV) as one model with its defaults, and of the 300 mV set alone,
# `hystbench simulate` of each test set, `hystbench diagnose` of the three train sets. The metric
# is the benchmark's: simulation rms error in um over outputs, realizations and both periods,
# each realization simulated from rest and its first 1000 samples (0.156 s, the transient
# window) not scored. Prints the table beside the published figures, then what each part buys:
# the amplitude schedule (each amplitude left out in turn), the coupling (one model per axis
# instead), the order (held-out error per order) and the play operators (with and without).
# About 100 s on 2 cores.
# Needs ../shared/data/piezo-fsm-cubespec (or HYSTBENCH_SHARED_DATA_DIR) and a build.
# Usage: scripts/cubespec-benchmark.sh   (work files in HYSTBENCH_MEASURE_DIR, else a temp dir)
set -euo pipefail
cd "$(dirname "$0")/.."
data="${HYSTBENCH_SHARED_DATA_DIR:-../shared/data}/piezo-fsm-cubespec"
if [[ ! -f "$data/u_300mV_train.npy" ]]; then
  echo "skipped: the CubeSpec data is not in $data (set HYSTBENCH_SHARED_DATA_DIR)" >&2
  exit 0
fi
scripts/deps.sh measure
bin="${HYSTBENCH_BIN:-build/bin}/hystbench"
work="${HYSTBENCH_MEASURE_DIR:-$(mktemp -d -t hystbench-cubespec.XXXXXX)}"
mkdir -p "$work"
skip=0.15625  # 1000 samples at 6400 Hz
for set in 100mV_train 200mV_train 300mV_train 100mV_test 200mV_test 300mV_test; do
  "$bin" convert "$data/u_$set.npy" "$data/y_$set.npy" --rate 6400 -o "$work/$set.csv" >/dev/null
done
u=u1_V,u2_V,u3_V
y=y1_m,y2_m,y3_m
start=$(date +%s.%N)
"$bin" fit "$work/100mV_train.csv" "$work/200mV_train.csv" "$work/300mV_train.csv" \
  --u-column $u --y-column $y --y-scale 1e6 -o "$work/every.json" --json >"$work/every.fit.json"
every_s=$(echo "$(date +%s.%N) - $start" | bc)
start=$(date +%s.%N)
"$bin" fit "$work/300mV_train.csv" --u-column $u --y-column $y --y-scale 1e6 \
  -o "$work/mimo.json" --json >"$work/mimo.fit.json"
fit_s=$(echo "$(date +%s.%N) - $start" | bc)
# One model per axis: input i to output i only, the coupling left out.
for i in 1 2 3; do
  "$bin" fit "$work/300mV_train.csv" --model hammerstein --u-column u${i}_V --y-column y${i}_m \
    --y-scale 1e6 -o "$work/axis$i.json" --json >"$work/axis$i.fit.json"
done
rmse() {  # rmse MODEL SET: on the columns the model was fitted on
  "$bin" simulate "$1" "$work/$2.csv" --y-scale 1e6 --skip $skip \
    -o "$work/$(basename "$1" .json).$2.csv" --json | jq -r '.rmse'
}
declare -A published_lfr=([100]=0.0866 [200]=0.1309 [300]=0.1686)
declare -A published_bla=([100]=0.114 [200]=0.216 [300]=0.228)
declare -A published_bla_all=([100]=0.252 [200]=0.179 [300]=0.658)
echo "### CubeSpec mirror: simulation rms error [um]"
echo
echo "| test set | hystbench, one model of every amplitude | hystbench, trained at 300 mV | one model per axis (300 mV) | published NL-LFR (all amplitudes) | published BLA, per amplitude | published BLA, all amplitudes |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for a in 100 200 300; do
  every=$(rmse "$work/every.json" ${a}mV_test)
  m=$(rmse "$work/mimo.json" ${a}mV_test)
  sq=0
  for i in 1 2 3; do
    e=$(rmse "$work/axis$i.json" ${a}mV_test)
    sq=$(echo "$sq + $e * $e" | bc -l)
  done
  axes=$(echo "sqrt($sq / 3)" | bc -l)
  printf '| %s mV | %.4f | %.4f | %.4f | %s | %s | %s |\n' "$a" "$every" "$m" "$axes" \
    "${published_lfr[$a]}" "${published_bla[$a]}" "${published_bla_all[$a]}"
done
echo
jq -r --arg s "$every_s" '"one model of every amplitude: \(.amplitudes | length) local models blended by the drive'"'"'s amplitude (\(.window_s) s window); \($s | tonumber * 10 | round / 10) s"' "$work/every.fit.json"
jq -r '.amplitudes[] | "  \(.amplitude * 10000 | round / 10000) V: order \(.order), the schedule on its train set \(.schedule_rms * 10000 | round / 10000) um; left out, the others predict it at \(.left_out_rms * 10000 | round / 10000) um"' "$work/every.fit.json"
echo
echo "diagnose of the three train sets:"
"$bin" diagnose "$work/100mV_train.csv" "$work/200mV_train.csv" "$work/300mV_train.csv" \
  --u-column $u --y-column $y --y-scale 1e6 2>/dev/null | sed 's/^/  /'
echo
echo "trained at 300 mV alone:"
jq -r --arg s "$fit_s" '"fit: order \(.order) of \(.orders | map(.order) | max) tried, \(.excited_bins) excited bins, \(.realizations) realizations x \(.periods) periods (the first dropped); \($s | tonumber * 10 | round / 10) s"' "$work/mimo.fit.json"
jq -r '"held-out rms per order [um] (\(.heldout)): " + (.orders | map("\(.order): \(.heldout_rms * 10000 | round / 10000)") | join(", "))' "$work/mimo.fit.json"
jq -r '"play operators per input: held-out \(.heldout_rms.hammerstein * 10000 | round / 10000) um against \(.heldout_rms.linear * 10000 | round / 10000) without (kept: \(.hysteresis_kept))"' "$work/mimo.fit.json"
jq -r '"coupling (share of each output'"'"'s power per input, %): " + ([.coupling[] | map(. * 1000 | round / 10 | tostring) | join("/")] | join("; "))' "$work/mimo.fit.json"
echo
echo "work files: $work"
