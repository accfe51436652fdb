#!/usr/bin/env bash
# The house rules a newcomer relies on: the README stays short, every page it links exists, and
# no file of the project speaks of how it was developed (steps or issue numbers, dated journal
# headings). Usage: tests/docs_hygiene.sh SOURCE_DIR
set -uo pipefail
cd "$1" || exit 2
fail=0
lines=$(wc -l < README.md)
if [ "$lines" -gt 150 ]; then
  echo "README.md has $lines lines (at most 150: move detail to docs/guide.md)"; fail=1
fi
# Relative links of the README and the docs pages resolve.
for page in README.md docs/*.md docs/reference/*.md; do
  dir=$(dirname "$page")
  for target in $(sed -E 's/`[^`]*`//g' "$page" | grep -oE '\]\([^)#[:space:]]+' | sed 's/^](//' |
                  grep -vE '^(https?|mailto):'); do
    [ -e "$dir/$target" ] || { echo "$page: link to $target, which does not exist"; fail=1; }
  done
done
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  files=$(git ls-files -- '*.md' '*.cpp' '*.hpp' '*.h' '*.py' '*.sh' '*.toml' '*.txt' '*.gp')
else
  files=$(find . -path ./build -prune -o -type f \( -name '*.md' -o -name '*.cpp' -o -name '*.hpp' \
    -o -name '*.py' -o -name '*.sh' -o -name '*.toml' -o -name '*.txt' \) -print)
fi
# shellcheck disable=SC2086
if hits=$(grep -nEi '\b(stop|issue)s? [0-9]+\b' $files | grep -v '^tests/docs_hygiene.sh:'); then
  echo "$hits"; echo "the lines above speak of development steps or issue numbers"; fail=1
fi
# shellcheck disable=SC2086
if hits=$(grep -nE '^#+ .*\(?20[0-9]{2}-[0-9]{2}-[0-9]{2}' $(echo "$files" | grep '\.md$')); then
  echo "$hits"; echo "the headings above are dated: docs hold the current state"; fail=1
fi
exit $fail
