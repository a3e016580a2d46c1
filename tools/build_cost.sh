#!/usr/bin/env bash
# glint-render's build cost against the commit the architecture issue measured (9031300: 197
# CPU-s there, target 60, so 0.305 of it): clean builds of --target glint-render from that commit
# and from HEAD, alternating, one at a time on one core; prints each round's CPU-s (user +
# system) and the ratio. Run it on an otherwise idle machine (docs/tracer.md, "Build cost").
#
#   bash tools/build_cost.sh [ROUNDS] [CORE]     # default 2 rounds on core 0; ~6 min a round
set -euo pipefail
rounds=${1:-2}
core=${2:-0}
root=$(git -C "$(dirname "$0")/.." rev-parse --show-toplevel)
work=$(mktemp -d /tmp/glint-build-cost.XXXXXX)
trap 'git -C "$root" worktree remove --force "$work/old-src" >/dev/null 2>&1 || true;
      git -C "$root" worktree remove --force "$work/new-src" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
git -C "$root" worktree add -q --detach "$work/old-src" 9031300
git -C "$root" worktree add -q --detach "$work/new-src" HEAD
cpu_seconds() {  # build dir from source dir; prints user + system CPU-s
  rm -rf "$2"
  cmake -S "$1" -B "$2" -DCMAKE_BUILD_TYPE=Release -DGLINT_HEADER_TEST=OFF >/dev/null 2>&1
  /usr/bin/time -f "%U %S" -o "$2.time" taskset -c "$core" cmake --build "$2" -j1 --target glint-render >/dev/null
  awk '{printf "%.1f", $1 + $2}' "$2.time"
}
for r in $(seq "$rounds"); do
  old=$(cpu_seconds "$work/old-src" "$work/old")
  new=$(cpu_seconds "$work/new-src" "$work/new")
  awk -v r="$r" -v o="$old" -v n="$new" \
    'BEGIN { printf "round %d: 9031300 %.1f CPU-s, HEAD %.1f CPU-s, ratio %.3f (target 0.305)\n", r, o, n, n / o }'
done
