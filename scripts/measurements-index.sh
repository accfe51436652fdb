#!/usr/bin/env bash
# The commands that measure the figures of docs/measurements.md again, section by section: the
# backticked commands in the last column ("Command") of its tables, each printed once, in the
# order the page gives them. Cells that name an option, a config key or a result field beside a
# command are left out; "the same" rows add nothing.
# Usage: scripts/measurements-index.sh [docs/measurements.md]
set -euo pipefail
cd "$(dirname "$0")/.."
page="${1:-docs/measurements.md}"
awk '
  # A command starts with a program, a script, an environment assignment or a bench subcommand.
  function is_command(s) {
    return s ~ /^(build\/bin\/|scripts\/|tests\/|hystbench|ctest |time |d=|git |python3 |bash |HYSTBENCH_[A-Z_]+=|track |sweep |strace |systemd-analyze |sed |export )/
  }
  /^#+ / { heading = $0; sub(/^#+ /, "", heading); next }
  /^\| / {
    line = $0
    gsub(/\\\|/, "\001", line)            # an escaped pipe belongs to the cell
    n = split(line, cell, "|")
    if (cell[n - 1] ~ /^ *Command *$/) { in_table = 1; next }
    if (!in_table || cell[2] ~ /^ *---/) next
    rest = cell[n - 1]
    while (match(rest, /`[^`]+`/)) {
      cmd = substr(rest, RSTART + 1, RLENGTH - 2)
      rest = substr(rest, RSTART + RLENGTH)
      gsub(/\001/, "|", cmd)
      if (!is_command(cmd) || seen[cmd]++) continue
      if (heading != printed) { printf "%s# %s\n", (printed == "" ? "" : "\n"), heading; printed = heading }
      print cmd
    }
    next
  }
  { in_table = 0 }
' "$page"
