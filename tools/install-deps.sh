#!/usr/bin/env bash
# Installs the Debian packages glint's build, tests, benchmarks and examples need.
# Runs apt-get only when something is missing; needs root (or sudo) for that.
set -euo pipefail
packages=(g++ cmake make libglm-dev doctest-dev libbenchmark-dev libembree-dev libopenexr-dev
          libtinyobjloader-dev libtinygltf-dev libstb-dev gnuplot-nox clang libclang-rt-14-dev pkg-config
          doxygen pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib openexr)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
