#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in build-fuzz/ and runs each one.
#   scripts/fuzz.sh [seconds per target, default 60] [target ...]   (targets: request config
#   model_file csv; default all)
# Corpora live in build-fuzz/corpus/<target>/ (seeded from config/ and the tests); a crash,
# hang (-timeout) or sanitizer report is copied to fuzz/regressions/<target>/ -- commit it: the
# normal test suite replays every file there (tests/daemon/service/fuzz_regressions_test.cpp).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(request config model_file csv)
build=build-fuzz
jobs=${HYSTBENCH_FUZZ_JOBS:-2}
bash scripts/deps.sh fuzz

flags="-O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined"
flags+=" -fno-sanitize-recover=undefined"
cmake -S . -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DHYSTBENCH_FUZZ=ON -DHYSTBENCH_TESTS=OFF -DHYSTBENCH_BENCH=OFF >/dev/null
cmake --build "$build" -j"$jobs" --target $(printf '%s_fuzz ' "${targets[@]}")

seed() {  # seed corpora once from files in the repository
  local target=$1 dir=$build/corpus/$1
  mkdir -p "$dir"
  [ -n "$(ls -A "$dir")" ] && return
  case $target in
    config) cp config/*.toml "$dir"/ ;;
    model_file) find tests -name '*.json' -size -64k -exec cp {} "$dir"/ \; 2>/dev/null || true
      printf '%s' '{"schema":"hystbench.model/1","type":"pi","input_range":[0,150],"play":{"thresholds":[0,10,20],"weights":[0.5,0.2,0.1],"offset":0}}' >"$dir/pi.json"
      printf '%s' '{"schema":"hystbench.model/1","type":"mpi","input_range":[0,150],"play":{"thresholds":[0,10],"weights":[0.5,0.2],"offset":0},"deadzone":{"thresholds":[-5,0,5],"weights":[0.1,1,0.1],"center":0}}' >"$dir/mpi.json" ;;
    csv) printf '# {"run":1}\nt,u,y\n0,1,2\n0.001,1.5,2.5\n' >"$dir/log.csv"
      printf 'a,b\n1e3,-2\nnan,inf\n' >"$dir/odd.csv" ;;
    request)
      local i=0
      for l in '{"id":1,"cmd":"status"}' '{"cmd":"track","params":{"compensator":"none","periods":2,"frequency_hz":2}}' \
        '{"id":"x","cmd":"identify","params":{"model":"mpi","operators":10,"u_min":0,"u_max":100}}' \
        '{"cmd":"stop"}' '{"cmd":"abort"}' '{"cmd":"reset"}' '{"cmd":"model.get"}' '{"cmd":"config.get"}' \
        '{"cmd":"track","params":{"min_um":-5,"max_um":10,"waveform":"triangle"}}' \
        '{"cmd":"model.load","params":{"name":"m.json","model":{"schema":"hystbench.model/1","type":"pi","input_range":[0,150],"play":{"thresholds":[0,10,20],"weights":[0.5,0.2,0.1],"offset":0}}}}' \
        '{"cmd":"model.load","params":{"stored":"m"}}' '{"cmd":"model.list"}' \
        '{"cmd":"model.load","params":{"path":"/etc/passwd"}}'; do
        printf '%s' "$l" >"$dir/seed$((i++))"
      done
      # Multi-line inputs are one connection's requests in order: upload sequences.
      cp fuzz/regressions/request/* "$dir"/ ;;
  esac
}

summary=()
failed=0
for t in "${targets[@]}"; do
  seed "$t"
  mkdir -p "fuzz/regressions/$t" "$build/artifacts/$t"
  log=$build/$t.log
  echo "== $t: ${seconds}s"
  set +e
  "$build/bin/${t}_fuzz" "$build/corpus/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=8192 -print_final_stats=1 -artifact_prefix="$build/artifacts/$t/" >"$log" 2>&1
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  found=0
  for f in "$build/artifacts/$t"/*; do
    [ -e "$f" ] || continue
    cp "$f" "fuzz/regressions/$t/" && found=$((found + 1))
    rm -f "$f"
  done
  summary+=("$(printf '%-11s execs %-10s exit %-3s new crashers %s' "$t" "$execs" "$rc" "$found")")
  [ $rc -eq 0 ] || { tail -40 "$log"; failed=1; }
  [ $found -eq 0 ] || failed=1
done
echo
echo "== fuzz summary (${seconds}s per target; logs in $build/<target>.log)"
printf '%s\n' "${summary[@]}"
[ $failed -eq 0 ] || { echo "fuzz: a target crashed, hung or tripped a sanitizer: fix it, then commit its input in fuzz/regressions/" >&2; exit 1; }
