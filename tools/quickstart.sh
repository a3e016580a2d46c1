#!/usr/bin/env bash
# Quick start, part 1: install what is missing, build the path tracer, and render the
# reference scene: the Cornell box, 512 x 512 pixels, 256 samples per pixel, written to
# cornell.exr (with a variance layer) and a cornell.png preview; it prints time and Mrays/s.
# It also builds and installs the Python module (python3 -c "import glint" works after it).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
python=()
[[ -x /usr/bin/python3 ]] && python=(-DPython3_EXECUTABLE=/usr/bin/python3)  # Debian's, with numpy
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DGLINT_PYTHON=ON "${python[@]}"
cmake --build build -j"$(nproc)" --target glint-render glint_python
cmake --install build --component python  # import glint, from any folder
./build/examples/glint-render --scene cornell --size 512 --spp 256 --out cornell.exr
