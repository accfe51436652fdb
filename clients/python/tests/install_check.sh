#!/bin/sh
# The package installs as the README says (pip, no build isolation: the package index is not
# reachable) and imports from where it was installed, not from the source tree.
# Usage: install_check.sh PYTHON SOURCE_DIR
set -eu
python=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# A copy: pip's in-tree build leaves build/ and *.egg-info behind.
cp -r "$src" "$tmp/pkg"
"$python" -m pip install --quiet --disable-pip-version-check --root-user-action=ignore \
  --no-build-isolation --no-deps \
  --target "$tmp/site" "$tmp/pkg"
cd "$tmp"
PYTHONPATH="$tmp/site" "$python" -c '
import hystbench, sys
assert hystbench.__file__.startswith(sys.argv[1]), hystbench.__file__
print("installed", hystbench.__version__, "at", hystbench.__file__)
' "$tmp/site"
