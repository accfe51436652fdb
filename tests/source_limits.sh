#!/usr/bin/env bash
# The house's limits on the project's own sources (vendored files aside):
#   - no file over 700 lines (C++, Python, shell, JavaScript, CMake), in any library or test;
#   - every C++ file formatted as .clang-format says (Google, 100 columns), when clang-format
#     is installed (scripts/deps.sh test installs it).
# Functions over 80 lines are clang-tidy's (readability-function-size, scripts/tidy.sh).
# Usage: tests/source_limits.sh SOURCE_DIR
set -uo pipefail
cd "$1" || exit 2
fail=0
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  files=$(git ls-files -- '*.cpp' '*.hpp' '*.h' '*.py' '*.sh' '*.js' '*.cmake' 'CMakeLists.txt' \
    '*/CMakeLists.txt' | grep -v '/vendor/')
else
  files=$(find . -path ./build -prune -o -path '*/vendor' -prune -o -type f \( -name '*.cpp' \
    -o -name '*.hpp' -o -name '*.py' -o -name '*.sh' -o -name '*.js' -o -name '*.cmake' \
    -o -name CMakeLists.txt \) -print)
fi
for f in $files; do
  n=$(wc -l < "$f")
  if [ "$n" -gt 700 ]; then echo "$f: $n lines (at most 700: split it by concept)"; fail=1; fi
done
if command -v clang-format >/dev/null; then
  cpp=$(echo "$files" | grep -E '\.(cpp|hpp|h)$')
  # shellcheck disable=SC2086
  if ! out=$(clang-format --dry-run --Werror $cpp 2>&1); then
    echo "$out" | grep -E '^[^ ].*(warning|error):' | sed -E 's/: (warning|error):.*//' | sort -u |
      sed 's/$/: not formatted (clang-format -i)/'
    fail=1
  fi
else
  echo "clang-format not installed: formatting not checked (scripts/deps.sh test installs it)"
fi
[ "$fail" = 0 ] && echo "source limits hold: $(echo "$files" | wc -l) files"
exit $fail
