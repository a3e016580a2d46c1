#!/usr/bin/env bash
# Compiles every public header on its own with clang and strict warnings as errors
# (-Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Werror), two headers at a time,
# each included twice (the include guard). CI builds without the gcc twin of this check
# (GLINT_HEADER_TEST=OFF).
# Dependencies' headers are system headers (-isystem): their warnings are not glint's.
set -euo pipefail
cd "$(dirname "$0")/.."
CXX=${CXX_CLANG:-clang++}
flags=(-std=c++20 -fsyntax-only -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Werror -Iinclude
       -isystem /usr/include/OpenEXR -isystem /usr/include/Imath -isystem /usr/include/stb)
export CXX
export FLAGS="${flags[*]}"
(cd include && find glint -name '*.hpp' | sort) > /tmp/glint_headers.$$
count=$(wc -l < /tmp/glint_headers.$$)
if xargs -P2 -I{} sh -c 'printf "#include <%s>\n#include <%s>\n" "$1" "$1" | $CXX $FLAGS -x c++ - || { echo "ci-headers: FAILED $1"; exit 1; }' _ {} \
     < /tmp/glint_headers.$$; then
  echo "ci-headers: $count public headers compile with $CXX and -Wconversion -Wsign-conversion -Werror"
  rm -f /tmp/glint_headers.$$
else
  rm -f /tmp/glint_headers.$$
  exit 1
fi
