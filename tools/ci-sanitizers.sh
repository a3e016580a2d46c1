#!/usr/bin/env bash
# CI sanitizer step. (1) The doctest suites built with clang, ASan and UBSan's arithmetic
# checks at -O1 (any report is fatal) and run; the heavy agreement and statistics cases run
# in their quick form (GLINT_SANITIZER_TESTS: test_trees' agreement cases on 4000 rays per
# scene; ASan is there for memory errors, the portable build's suites for rare edge cases).
# (2) glint-render built with TSan and all of UBSan at -O0 (the renders are tiny: compile
# time is what counts), short multithreaded renders (the path tracer; the LIE, whose
# construction is threaded); tools/tsan.supp names the one report TSan makes of UBSan's own
# vptr probe. Build folders: build-asan, build-tsan.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${CI_JOBS:-$(nproc)}
# Every doctest suite, tests/test_<name>.cpp (as tests/CMakeLists.txt finds them), largest
# source first: the longest runs start first when they run $jobs at a time.
mapfile -t suites < <(cd tests && ls -S test_*.cpp | sed 's/^test_//; s/\.cpp$//')

# ASan with the UBSan checks that find arithmetic errors (overflow, shifts, float-to-int
# conversions out of range, division by zero, bounds of fixed arrays, bad bool and enum
# values, a missing return); left out: null, alignment, object-size, pointer-overflow, vptr
# and function, which ASan's own checks or a crash would show and which cost this build a
# third more compile time and doubled the suites' run time (test_lights: 129 s to compile and
# 39 s to run with all of UBSan, 98 s and 22 s with this set). The use-after-return
# instrumentation is off: its run-time switch is off by default anyway. The fuzz targets
# and the TSan render keep all of UBSan.
# No debug information by default: a report names the functions of its stack, and line
# tables cost this build 14% more time (test_lights 95 s against 82 s); for file and line,
# GLINT_SANITIZER_DEBUG=-gline-tables-only bash tools/ci-sanitizers.sh.
debug=${GLINT_SANITIZER_DEBUG:--g0}
san=(-fsanitize=address,signed-integer-overflow,shift,float-cast-overflow,integer-divide-by-zero,bounds,return,unreachable,bool,enum,vla-bound,builtin
     -fno-sanitize-recover=all -fsanitize-address-use-after-return=never)
t0=$SECONDS
mkdir -p build-asan build-tsan
cmake -S . -B build-asan -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None -DGLINT_NATIVE=OFF \
      -DGLINT_BUILD_BENCHMARKS=OFF -DGLINT_BUILD_EXAMPLES=OFF -DGLINT_HEADER_TEST=OFF -DGLINT_PYTHON=OFF \
      -DCMAKE_CXX_FLAGS="-O1 $debug -fno-omit-frame-pointer ${san[*]} -DGLINT_SANITIZER_TESTS" \
      -DCMAKE_EXE_LINKER_FLAGS="${san[*]}" > build-asan/ci.log
# The whole configuration (the suites, exr_stats and glint_instances), not one --target per
# suite: CMake's Makefiles are .NOTPARALLEL across the targets named on one command line, so
# that built the suites one after another, one translation unit each, on one core (765 s).
cmake --build build-asan -j"$jobs" >> build-asan/ci.log || { grep -E "error" build-asan/ci.log | head -20; exit 1; }
echo "ci-sanitizers: ASan+UBSan suites built in $((SECONDS - t0)) s"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# One suite: runs it, prints its line; a failure prints its log and returns 1. The suites run
# $jobs at a time.
run_suite() {
  local s=$1 t=$SECONDS
  ./build-asan/tests/test_"$s" --minimal > "build-asan/test_$s.log" 2>&1 || { cat "build-asan/test_$s.log"; echo "ci-sanitizers: FAILED test_$s under ASan+UBSan"; return 1; }
  echo "ci-sanitizers: test_$s passed under ASan+UBSan ($((SECONDS - t)) s)"
}
export -f run_suite
t=$SECONDS
printf '%s\n' "${suites[@]}" | xargs -P "$jobs" -I{} bash -c 'run_suite {}' || { echo "ci-sanitizers: a suite failed"; exit 1; }
echo "ci-sanitizers: suites ran in $((SECONDS - t)) s"

t0=$SECONDS
cmake -S . -B build-tsan -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None -DGLINT_NATIVE=OFF \
      -DGLINT_BUILD_TESTS=OFF -DGLINT_BUILD_BENCHMARKS=OFF -DGLINT_BUILD_EXAMPLES=ON \
      -DCMAKE_CXX_FLAGS="-O0 -gline-tables-only -fsanitize=thread,undefined -fno-sanitize-recover=undefined" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread,undefined" > build-tsan/ci.log
cmake --build build-tsan -j"$jobs" --target glint-render >> build-tsan/ci.log
export TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tools/tsan.supp" UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
./build-tsan/examples/glint-render --scene cornell --size 32 --spp 4 --threads 4 --direct combined \
    --out build-tsan/tsan_cornell.exr > build-tsan/render.log 2>&1 || { cat build-tsan/render.log; echo "ci-sanitizers: FAILED TSan render"; exit 1; }
# The LIE's construction traces its sample rays on every hardware thread.
./build-tsan/examples/glint-render --scene lie-hall --size 16 --spp 1 --threads 4 --direct lie \
    --out build-tsan/tsan_lie.exr > build-tsan/render_lie.log 2>&1 || { cat build-tsan/render_lie.log; echo "ci-sanitizers: FAILED TSan LIE render"; exit 1; }
echo "ci-sanitizers: 4-thread renders under TSan passed (built and run in $((SECONDS - t0)) s)"
