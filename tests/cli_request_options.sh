#!/usr/bin/env bash
# The CLI's options that set a request key take the key's range and default from the daemon's
# table (hystbench/common/run_requests.hpp), the one docs/reference/protocol.md's tables are made
# from: for each option below, a value above the page's range is refused by the CLI itself (no
# daemon is asked: the socket does not exist), and --help gives the page's default.
# Usage: cli_request_options.sh SOURCE_DIR HYSTBENCH
set -euo pipefail
root=$1
cli=$2
page="$root/docs/reference/protocol.md"
export HYSTBENCH_SOCKET=/nonexistent/hystbench.sock
failed=0

# The page's row of `key` in the table of `command`: "type | range | default".
row() {
  awk -v cmd="$1" -v key="$2" '
    index($0, "<!-- the parameters of `" cmd "`") == 1 { inside = 1; next }
    inside && index($0, "<!-- end of the generated table") == 1 { exit }
    inside && index($0, "| `" key "` |") == 1 {
      n = split($0, cells, "|"); print cells[3] "|" cells[4] "|" cells[5]; exit
    }' "$page"
}

check() {  # command flag key
  local command=$1 flag=$2 key=$3 cells range hi default out
  cells=$(row "$command" "$key")
  [[ -n "$cells" ]] || { echo "FAIL: no row for $command.$key on the page"; failed=1; return; }
  range=$(cut -d'|' -f2 <<<"$cells" | xargs)
  default=$(cut -d'|' -f3 <<<"$cells" | xargs)
  hi=${range##* to }
  above=$(awk -v h="$hi" 'BEGIN { print (h < 0 ? h / 2 : h * 2 + 1) }')
  if out=$("$cli" "$command" "$flag" "$above" 2>&1); then
    echo "FAIL: $command $flag $above (above the page's $range) was accepted"; failed=1
  elif ! grep -q -- "$flag" <<<"$out" || grep -qi "socket\|connect" <<<"$out"; then
    echo "FAIL: $command $flag $above: not refused by the CLI naming $flag:"; echo "$out"; failed=1
  fi
  if [[ -n "$default" ]]; then
    local words=${default//\`/}
    "$cli" "$command" --help |
      awk -v flag="$flag" '/^  -/ { inside = index($0, "  " flag " ") == 1 } inside' |
      tr -s ' \n' ' ' | grep -qF -- "(default: $words)" ||
      { echo "FAIL: $command --help: $flag does not give the page's default ($words)"; failed=1; }
  fi
}

check frf --amplitude amplitude
check frf --periods periods
check track --range-fraction range_fraction
check track --lead-in-max lead_in_max_s
check tune --kd kd
check identify --operators operators
[[ $failed == 0 ]] && echo "the CLI's options hold the daemon's ranges and defaults"
exit $failed
