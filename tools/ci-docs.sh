#!/usr/bin/env bash
# CI docs step: builds the API reference (cmake target docs, Doxygen over include/glint) and
# fails on any Doxygen warning, an undocumented public name among them, printing them all.
set -euo pipefail
cd "$(dirname "$0")/.."
command -v doxygen > /dev/null || { echo "ci-docs: doxygen is not installed (Debian: doxygen)"; exit 1; }
build=${1:-build}
[[ -f "$build/CMakeCache.txt" ]] || cmake -S . -B "$build" > /dev/null
cmake "$build" > /dev/null  # the docs target exists only where CMake found Doxygen
cmake --build "$build" --target docs > /dev/null
log="$build/docs/api/warnings.log"
count=$(grep -c . "$log" || true)
if [[ "$count" -ne 0 ]]; then
  cat "$log"
  echo "ci-docs: FAILED: $count Doxygen warnings (document each public name with ///, or move it into glint::detail)"
  exit 1
fi
echo "ci-docs: API reference built with no warning: every public name in include/glint documented"
