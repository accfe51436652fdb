#!/usr/bin/env bash
# The daemon's folders are layers, each a library of its own (daemon/CMakeLists.txt):
#   loop < config < runs < service < http
# A folder includes its own headers and those of the folders below it, never one above: the
# loop knows the program it plays (loop/run_program.hpp), not who built it; the run builders
# know the settings, not the Bench. Usage: tests/daemon_layers.sh SOURCE_DIR
set -uo pipefail
cd "$1/daemon" || exit 2
layers=(loop config runs service http)
rank() { local i; for i in "${!layers[@]}"; do [ "${layers[$i]}" = "$1" ] && echo "$i"; done; }
fail=0
for from in "${layers[@]}"; do
  r_from=$(rank "$from")
  for file in $(find "src/$from" "include/hystbench/daemon/$from" -name '*.[ch]pp' 2>/dev/null); do
    while IFS= read -r target; do
      r_to=$(rank "$target")
      if [ -n "$r_to" ] && [ "$r_to" -gt "$r_from" ]; then
        echo "daemon/$file includes $target/ (a layer above $from/)"; fail=1
      fi
    done < <(sed -nE 's@^#include "(hystbench/daemon/)?([a-z_]+)/.*@\2@p' "$file" | sort -u)
  done
done
[ "$fail" = 0 ] && echo "daemon layers hold: ${layers[*]}"
exit $fail
