#!/usr/bin/env bash
# Formats jointcomp's own C and C++ sources with clang-format (.clang-format at the root): model, capi, fmu,
# cli, tests, bench, examples; not build output, nor the fuzz corpora.
# usage: packaging/format.sh [--check]   (--check: change nothing, list the files that would change, exit 1
# when there is one)
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
if [ $# -gt 0 ]; then
  [ "$1" = --check ] && [ $# -eq 1 ] || { echo "usage: packaging/format.sh [--check]" >&2; exit 2; }
  check=1
fi
command -v clang-format >/dev/null || { echo "format.sh: clang-format is missing (bash packaging/install-deps.sh)" >&2; exit 2; }
mapfile -t files < <(git ls-files -- 'model/*' 'capi/*' 'fmu/*' 'cli/*' 'tests/*' 'bench/*' 'examples/*' |
                     grep -E '\.(c|h|cpp|hpp)$' | grep -vE '^tests/fuzz/(corpus|regressions)/')
if [ "$check" = 0 ]; then
  clang-format -i --style=file "${files[@]}"
  echo "format.sh: formatted ${#files[@]} files"
  exit 0
fi
unformatted=0
for f in "${files[@]}"; do
  if ! clang-format --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "needs formatting: $f"
    unformatted=$((unformatted + 1))
  fi
done
echo "format.sh: ${#files[@]} files checked, $unformatted need formatting"
[ "$unformatted" = 0 ]
