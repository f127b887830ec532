#!/usr/bin/env bash
# The layer check itself: on a copy of the tree with one include planted against the order (effects
# including a header of identify), it must fail and name the file; on the untouched copy it must pass.
# usage: check_layers_catches.sh SOURCE_ROOT SCRATCH_DIR
set -euo pipefail
root="$1"
work="$2"
rm -rf "$work"
mkdir -p "$work/model"
cp "$root/model/CMakeLists.txt" "$work/model/"
for layer in "$root"/model/*/; do
  name="$(basename "$layer")"
  mkdir -p "$work/model/$name"
  find "$layer" -maxdepth 1 -type f \( -name '*.cpp' -o -name '*.hpp' \) -exec cp {} "$work/model/$name/" \;
done
bash "$root/tests/layers/check_layers.sh" "$work" >/dev/null || { echo "the untouched copy failed the check" >&2; exit 1; }
printf '#include "model/identify/discovery.hpp"\n' >>"$work/model/effects/backlash.cpp"
if bash "$root/tests/layers/check_layers.sh" "$work" 2>"$work/message"; then
  echo "a planted upward include passed the check" >&2
  exit 1
fi
grep -q "model/effects/backlash.cpp:.*'effects' includes a header of the higher layer 'identify'" "$work/message" || {
  echo "the message does not name the file and the layers:" >&2; cat "$work/message" >&2; exit 1; }
printf '#include "capi/src/api_support.hpp"\n' >"$work/model/common/planted.hpp"
sed -i '$d' "$work/model/effects/backlash.cpp"
if bash "$root/tests/layers/check_layers.sh" "$work" 2>/dev/null; then
  echo "a model file including the C API passed the check" >&2
  exit 1
fi
echo "check_layers_catches: upward includes are refused and named"
