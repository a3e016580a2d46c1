#!/usr/bin/env bash
# README's results table as code: builds what the rows need, re-measures every row on this
# machine (single thread, pinned), prints each measured number next to README's, flags rows
# outside the run-to-run spread, and (full run only) writes docs/results.md and README's table
# between <!-- results:begin --> and <!-- results:end -->.
#
#   bash tools/results.sh                    # full run: over an hour on the shared 2-core machine (rows timed
#                                            # there: cones 3-4 min a run, occluders 4-10, trees 5-8, intersection
#                                            # 4-5, bench_convergence 0.5-2; lambda ~10; Cycles ~30 more)
#   bash tools/results.sh --quick            # CI smoke run: tiny sizes, rewrites nothing (15-30 s)
#   bash tools/results.sh --resume ...       # an interrupted run: reuse the logs of finished benchmark runs
#   bash tools/results.sh --rows cones,trees # some rows; --list names them; --skip ROWS leaves some out
#   GLINT_RESULTS_NO_BUILD=1 bash tools/results.sh ...   # use the binaries already in --build-dir
#   cmake --build build --target results     # the same full run as a CMake target
#
# Options are tools/results.py's (--build-dir DIR, default build; --core N, default 1; --reps N).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  case "${args[i]}" in
    --build-dir) build=${args[i + 1]} ;;
    --build-dir=*) build=${args[i]#--build-dir=} ;;
  esac
done
python=/usr/bin/python3
[[ -x $python ]] || python=python3
if [[ " $* " != *" --list "* && -z "${GLINT_RESULTS_NO_BUILD:-}" ]]; then
  [[ -f $build/CMakeCache.txt ]] || cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release
  # One target (benchmarks/CMakeLists.txt): make builds its programs two at a time, where several
  # --target on one command line would build them one after another.
  target=results_programs
  [[ " $* " == *" --quick "* ]] && target=results_benchmarks
  cmake --build "$build" -j"${GLINT_RESULTS_JOBS:-2}" --target "$target"
fi
exec "$python" tools/results.py "$@"
