#!/usr/bin/env bash
# Quick start, part 1: install what is missing, build the path tracer, and render the
# reference scene: the Cornell box, 512 x 512 pixels, 256 samples per pixel, written to
# cornell.exr (with a variance layer) and a cornell.png preview; it prints time and Mrays/s.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target glint-render
./build/examples/glint-render --scene cornell --size 512 --spp 256 --out cornell.exr
