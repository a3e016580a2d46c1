#!/usr/bin/env bash
# Quick start, part 1: install what is missing, build, and run the main job.
# For now the main job is the intersection example and the comparison of the four
# ray-triangle tests (time per test, ratio to Moller-Trumbore, measured in this run).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
./build/examples/intersect_triangles
echo
./build/benchmarks/bench_intersection --benchmark_filter='Scalar/(Ivm|MollerTrumbore)$|Batch/(Ivm|MollerTrumbore)$' \
  --benchmark_min_time=0.2 2>&1 | sed -n '/ns per ray-triangle test/,$p'
