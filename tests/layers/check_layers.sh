#!/usr/bin/env bash
# Fails when a file of a model layer includes a header of a higher layer, or of the tools on top (capi, fmu,
# cli), naming the file, the line and both layers. The order is read from model/CMakeLists.txt
# (JOINTCOMP_LAYERS), the one place it is written in code.
# usage: check_layers.sh SOURCE_ROOT
set -euo pipefail
root="$1"
order_line="$(grep -m1 '^set(JOINTCOMP_LAYERS ' "$root/model/CMakeLists.txt")" || {
  echo "check_layers: no 'set(JOINTCOMP_LAYERS ...)' in $root/model/CMakeLists.txt" >&2; exit 2; }
read -r -a layers <<<"$(sed -e 's/^set(JOINTCOMP_LAYERS //' -e 's/)$//' <<<"$order_line")"
declare -A rank
for i in "${!layers[@]}"; do rank[${layers[$i]}]=$i; done
violations=0
checked=0
for layer in "${layers[@]}"; do
  [ -d "$root/model/$layer" ] || continue
  while IFS= read -r -d '' file; do
    checked=$((checked + 1))
    line_number=0
    while IFS= read -r line; do
      line_number=$((line_number + 1))
      [[ "$line" =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*\"([a-z_]+)/([a-z_]+)/ ]] || \
        [[ "$line" =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*\"([a-z_]+)/ ]] || continue
      top="${BASH_REMATCH[1]}"
      if [ "$top" = model ] && [ -n "${BASH_REMATCH[2]:-}" ]; then
        target="${BASH_REMATCH[2]}"
        if [ -z "${rank[$target]+x}" ]; then
          echo "${file#"$root"/}:$line_number: includes model/$target, which is no layer of JOINTCOMP_LAYERS" >&2
          violations=$((violations + 1))
        elif [ "${rank[$target]}" -gt "${rank[$layer]}" ]; then
          echo "${file#"$root"/}:$line_number: layer '$layer' includes a header of the higher layer '$target'" >&2
          violations=$((violations + 1))
        fi
      elif [ "$top" = capi ] || [ "$top" = fmu ] || [ "$top" = cli ]; then
        echo "${file#"$root"/}:$line_number: layer '$layer' includes '$top', a tool on top of the model" >&2
        violations=$((violations + 1))
      fi
    done <"$file"
  done < <(find "$root/model/$layer" -maxdepth 1 -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0)
done
if [ "$checked" -eq 0 ]; then
  echo "check_layers: no source file found under $root/model" >&2
  exit 2
fi
if [ "$violations" -gt 0 ]; then
  echo "check_layers: $violations include(s) against the layer order ${layers[*]}" >&2
  exit 1
fi
echo "check_layers: $checked files follow the layer order ${layers[*]}"
