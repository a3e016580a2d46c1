#!/usr/bin/env bash
# Architecture checks that a compiler cannot make, run by .ci/run:
#   1. no `if constexpr` in include/ on a policy's identity or on a flag it publishes:
#      a type parameter's member (`D::collects_emission`, `P::uses_frame`), a comparison of a
#      template enum with one of its values (`C == BrdfSelection::mis`), or a type identity
#      (`std::same_as<L, X>`) other than the scalar type's (`std::is_same_v<T, float>`);
#   2. no header in include/glint/trees/ over 400 lines (one idea per header);
#   3. sources cited by the bibliography (docs/references.md), never as "000" ... "004".
# Each violation is printed with its file and line; the exit status is the number of checks
# that failed.
set -uo pipefail
cd "$(dirname "$0")/.."
failed=0

flags=$(grep -rnE 'if constexpr \(!?\(?[A-Z][A-Za-z0-9_]*::[a-z_]+|if constexpr \(.*\b[A-Z][A-Za-z0-9_]* *[!=]= *[A-Z][A-Za-z0-9_]*::|if constexpr \(.*(same_as|is_same_v)<' include \
        | grep -vE '(same_as|is_same_v)<[A-Za-z_]+, *(float|double)>' || true)
if [ -n "$flags" ]; then
  echo "ci-lint: if constexpr on a policy's identity or published flag (let the policy act instead):"
  echo "$flags"
  failed=$((failed + 1))
fi

long=$(find include/glint/trees -name '*.hpp' -exec wc -l {} + | awk '$2 != "total" && $1 > 400 {print $2 ": " $1 " lines"}')
if [ -n "$long" ]; then
  echo "ci-lint: trees/ headers over 400 lines:"
  echo "$long"
  failed=$((failed + 1))
fi

cites=$(grep -rnE '(^|[^0-9.,])00[0-4]\b( ?§| section| sections| ch\.| chapter|:|,|\x27s| Fig| Table| eq)|\("00[0-4]"\)|"00[0-4]" in' include README.md docs --include='*.hpp' --include='*.md' || true)
if [ -n "$cites" ]; then
  echo "ci-lint: sources cited as 000-004 instead of by the bibliography (Szécsi 2009, §2.2):"
  echo "$cites"
  failed=$((failed + 1))
fi

[ $failed -eq 0 ] && echo "ci-lint: policies act, trees/ headers <= 400 lines, citations by the bibliography"
exit $failed
