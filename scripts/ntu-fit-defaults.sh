#!/usr/bin/env bash
# Fits every model family to the NTU piezo identification record with `hystbench fit`'s defaults
# and scores each on the tracking record's three sine segments (rows 1200-2800, 7600-9200,
# 12400-14000, 0-based, segment mean removed). Prints one line per
# family: prediction rms per segment [um]. Needs ../shared/data/piezo-ntu-dbo and a build.
# Usage: scripts/ntu-fit-defaults.sh [families...]   (default: pi mpi cpi rpi preisach auto)
set -euo pipefail
cd "$(dirname "$0")/.."
data="${HYSTBENCH_SHARED_DATA_DIR:-../shared/data}/piezo-ntu-dbo"
if [[ ! -f "$data/Model_Vi_Do.dat" || ! -f "$data/Test_Vi_Do_Di.dat" ]]; then
  echo "skipped: the NTU records are not in $data (set HYSTBENCH_SHARED_DATA_DIR)" >&2
  exit 0
fi
bin=build/bin/hystbench
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
columns=(--rate 200 --u-column 1 --y-column 5)
for family in "${@:-pi mpi cpi rpi preisach auto}"; do
  for f in $family; do
    "$bin" fit "$data/Model_Vi_Do.dat" "${columns[@]}" --model "$f" -o "$work/$f.json" \
      >"$work/$f.fit.txt" 2>/dev/null
    "$bin" simulate "$work/$f.json" "$data/Test_Vi_Do_Di.dat" "${columns[@]}" \
      -o "$work/$f.csv" >/dev/null
    python3 - "$work/$f.csv" "$f" "$(head -1 "$work/$f.fit.txt")" <<'PY'
import csv, math, sys
rows = [r for r in csv.reader(l for l in open(sys.argv[1]) if not l.startswith('#'))]
head, rows = rows[0], rows[1:]
iy, im = head.index('y'), head.index('y_model')
out = []
for b, e in ((1200, 2800), (7600, 9200), (12400, 14000)):
    d = [float(r[iy]) - float(r[im]) for r in rows[b:e]]
    m = sum(d) / len(d)
    out.append(math.sqrt(sum((x - m) ** 2 for x in d) / len(d)))
print(f"{sys.argv[2]:5s} segments {out[0]:.3f} {out[1]:.3f} {out[2]:.3f} um   ({sys.argv[3]})")
PY
  done
done
