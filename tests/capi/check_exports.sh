#!/usr/bin/env bash
# The shared library exports exactly the functions of the public header, all with the jc_ prefix.
# usage: check_exports.sh <libjointcomp.so> <jointcomp.h>
set -euo pipefail
library="$1"
header="$2"
exported=$(nm -D --defined-only "$library" | awk '{print $NF}' | sed 's/@.*//' | sort -u)
declared=$(grep -oE '^JOINTCOMP_API [^(]*\bjc_[a-z0-9_]+\(' "$header" | grep -oE 'jc_[a-z0-9_]+\($' | tr -d '(' | sort -u)
status=0
foreign=$(echo "$exported" | grep -v '^jc_' || true)
if [ -n "$foreign" ]; then
  echo "exported symbols without the jc_ prefix:"; echo "$foreign"; status=1
fi
missing=$(comm -23 <(echo "$declared") <(echo "$exported"))
if [ -n "$missing" ]; then
  echo "declared in the header but not exported:"; echo "$missing"; status=1
fi
extra=$(comm -13 <(echo "$declared") <(echo "$exported"))
if [ -n "$extra" ]; then
  echo "exported but not declared in the header:"; echo "$extra"; status=1
fi
echo "check_exports: $(echo "$exported" | wc -l) exported symbols, $(echo "$declared" | wc -l) declared"
exit $status
