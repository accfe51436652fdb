#!/usr/bin/env bash
# The service's sandbox with the live view's drop-in (systemd/hystbenchd-http.conf) merged in:
# `systemd-analyze security --offline=true` must score it at most 2.5.
# Usage: tests/systemd_security.sh SOURCE_DIR. Exit 77 (skipped) without systemd-analyze.
set -euo pipefail
src=$1
command -v systemd-analyze >/dev/null || { echo "SKIP: systemd-analyze not found"; exit 77; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# The unit as systemd reads it with the drop-in: the drop-in's [Service] lines appended.
{ cat "$src/systemd/hystbenchd.service"; grep -v '^\[Service\]' "$src/systemd/hystbenchd-http.conf"; } \
  > "$dir/hystbenchd.service"
for unit in "$src/systemd/hystbenchd.service" "$dir/hystbenchd.service"; do
  out=$(systemd-analyze security --offline=true "$unit" 2>&1) || true
  score=$(sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p' <<<"$out")
  [ -n "$score" ] || { echo "no exposure level in:"; echo "$out"; exit 1; }
  echo "figure exposure=$score ($unit)"
  awk -v s="$score" 'BEGIN { exit !(s <= 2.5) }' || { echo "exposure $score > 2.5"; exit 1; }
done
grep -q '^LoadCredential=http-token:' "$dir/hystbenchd.service"
