# Sourced by scripts/build.sh and scripts/demo.sh. Their presets build with Ninja, and CMake keeps
# a build folder's generator: a folder an older checkout configured for make starts again.
# Usage: ninja_tree_or_fresh DIR
ninja_tree_or_fresh() {
  if [ -f "$1/CMakeCache.txt" ] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$1/CMakeCache.txt"; then
    echo "hystbench: $1/ was configured for another generator: configuring it again for Ninja" >&2
    rm -rf "$1"
  fi
}
