#!/usr/bin/env bash
# CI fuzz step: builds the libFuzzer targets of tests/fuzz (clang, ASan+UBSan) in build-fuzz
# and runs each for SECONDS seconds (first argument; default 30) from its committed seed
# corpus (tests/fuzz/corpus/<name>, read only: new inputs go to build-fuzz/corpus/<name>).
# Prints one line per target with libFuzzer's execs, coverage and corpus; any crash,
# sanitizer report, timeout or out-of-memory fails the step. Longer runs:
#   GLINT_FUZZ_SECONDS=600 bash .ci/run    or    bash tools/ci-fuzz.sh 600
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
jobs=${CI_JOBS:-$(nproc)}
t0=$SECONDS
mkdir -p build-fuzz
cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=None -DGLINT_FUZZ=ON \
      -DGLINT_BUILD_TESTS=OFF -DGLINT_BUILD_BENCHMARKS=OFF -DGLINT_BUILD_EXAMPLES=OFF > build-fuzz/ci.log
cmake --build build-fuzz -j"$jobs" >> build-fuzz/ci.log
echo "ci-fuzz: targets built in $((SECONDS - t0)) s"
# One target: runs it, prints its line; a failure prints the log's tail and returns 1.
fuzz_one() {
  local src=$1 name short log execs cov ft corp
  name=$(basename "$src" .cpp)
  short=${name#fuzz_}
  mkdir -p "build-fuzz/corpus/$short" "build-fuzz/artifacts"
  log="build-fuzz/$name.log"
  if ! ./build-fuzz/tests/fuzz/"$name" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -artifact_prefix="build-fuzz/artifacts/$name-" -print_final_stats=1 \
       "build-fuzz/corpus/$short" "tests/fuzz/corpus/$short" > "$log" 2>&1; then
    tail -40 "$log"
    echo "ci-fuzz: FAILED $name (reproducer in build-fuzz/artifacts/)"
    return 1
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$')
  cov=$(grep -E '^#[0-9]+.*(DONE|pulse|NEW|REDUCE)' "$log" | tail -1 | grep -o 'cov: [0-9]*' | grep -o '[0-9]*')
  ft=$(grep -E '^#[0-9]+.*(DONE|pulse|NEW|REDUCE)' "$log" | tail -1 | grep -o 'ft: [0-9]*' | grep -o '[0-9]*')
  corp=$(ls "build-fuzz/corpus/$short" | wc -l)
  echo "ci-fuzz: $name ${seconds} s: ${execs:-?} execs, cov ${cov:-?} edges, ft ${ft:-?} features, corpus +$corp inputs, 0 crashes"
}
# The targets run $jobs at a time (each is single-threaded).
export -f fuzz_one
export seconds
ls tests/fuzz/fuzz_*.cpp | xargs -P "$jobs" -I{} bash -c 'fuzz_one {}' || { echo "ci-fuzz: a target failed"; exit 1; }
