#!/usr/bin/env bash
# Fails when a function of the model, the C API, the FMU or the command-line tool is longer than 80 lines, as
# clang-tidy's readability-function-size counts them (its LineThreshold), naming the file, the line and the
# length. A function may stand over the limit only while the exceptions file names its file and function with
# the issue that splits it; an entry that no longer matches a long function fails the check (drop it), so
# that the list only gets shorter.
# usage: check_function_sizes.sh SOURCE_ROOT BUILD_DIR EXCEPTIONS_FILE
set -euo pipefail
root="$(cd "$1" && pwd)"
build="$2"
exceptions="$3"
tidy="${CLANG_TIDY:-clang-tidy-14}"
command -v "$tidy" >/dev/null || { echo "check_function_sizes: $tidy not found (apt: clang-tidy-14)" >&2; exit 2; }
[ -f "$build/compile_commands.json" ] || { echo "check_function_sizes: no $build/compile_commands.json" >&2; exit 2; }
mapfile -t sources < <(/usr/bin/python3 - "$root" "$build/compile_commands.json" <<'PY'
import json, os, sys
root, db = sys.argv[1], sys.argv[2]
for e in json.load(open(db)):
    path = os.path.realpath(os.path.join(e["directory"], e["file"]))
    rel = os.path.relpath(path, root)
    if rel.split(os.sep)[0] in ("model", "capi", "fmu", "cli") and path.endswith((".cpp", ".c")):
        print(path)
PY
)
[ "${#sources[@]}" -gt 0 ] || { echo "check_function_sizes: no source in the compile database" >&2; exit 2; }
config='{Checks: "-*,readability-function-size", CheckOptions: [{key: readability-function-size.LineThreshold, value: 80}]}'
report="$(mktemp)"
trap 'rm -f "$report"' EXIT
printf '%s\0' "${sources[@]}" |
  xargs -0 -n 4 -P "${JOBS:-2}" "$tidy" -p "$build" --quiet --config="$config" --header-filter="^$root/(model|capi|fmu|cli)/" \
    2>/dev/null | grep -E "warning: function '.*' exceeds recommended size" >"$report" || true
failures=0
declare -A used
while IFS= read -r line; do
  file="${line%%:*}"
  relative="${file#"$root"/}"
  function="$(sed -E "s/.*function '([^']*)'.*/\1/" <<<"$line")"
  key="$relative $function"
  if grep -qxF -- "$key" <(grep -v '^#' "$exceptions" | sed -E 's/[[:space:]]+issue-[0-9]+$//'); then
    used[$key]=1
    continue
  fi
  echo "${line%%: warning*}: function '$function' is over 80 lines: split it" >&2
  failures=$((failures + 1))
done < <(sort -u "$report")
while IFS= read -r entry; do
  [[ -z "$entry" || "$entry" == \#* ]] && continue
  key="$(sed -E 's/[[:space:]]+issue-[0-9]+$//' <<<"$entry")"
  [ -n "${used[$key]+x}" ] && continue
  echo "$exceptions: '$key' is no longer over 80 lines: drop its entry" >&2
  failures=$((failures + 1))
done <"$exceptions"
if [ "$failures" -gt 0 ]; then
  echo "check_function_sizes: $failures function(s) against the limit of 80 lines" >&2
  exit 1
fi
echo "check_function_sizes: the functions of ${#sources[@]} files are within 80 lines" \
     "(exceptions: $(grep -c '^[^#[:space:]]' "$exceptions" || true))"
