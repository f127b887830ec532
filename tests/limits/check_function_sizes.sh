#!/usr/bin/env bash
# Fails when a function of the model, the C API, the FMU or the command-line tool is longer than 80 lines, as
# clang-tidy's readability-function-size counts them (its LineThreshold), naming the file, the line and the
# length. A function may stand over the limit only while the exceptions file names its file and function with
# the issue that splits it; an entry that no longer matches a long function fails the check (drop it), so
# that the list only gets shorter. A translation unit clang-tidy cannot parse fails the check too (no silent
# pass).
# usage: check_function_sizes.sh SOURCE_ROOT BUILD_DIR EXCEPTIONS_FILE
#   JOBS: clang-tidy processes at a time (default: the number of cores); CLANG_TIDY: the binary
#   (default clang-tidy-14).
# Cost: clang-tidy parses each translation unit as the compiler does (about 3 s of CPU each, nearly all of it
# Eigen and the other headers; the check itself adds little), so the time is the number of the project's own
# translation units over JOBS. Only those are checked: each source file of model/, capi/, fmu/ and cli/ once
# (the compile database names some twice, for two targets), not the tests, benchmarks or examples, and only
# the check asked for (-*,readability-function-size: no other check's matchers run). Functions in the
# project's headers are checked through the sources that include them (--header-filter: only the project's
# own folders, never the system's or Eigen's headers).
set -euo pipefail
root="$(cd "$1" && pwd)"
build="$2"
exceptions="$3"
tidy="${CLANG_TIDY:-clang-tidy-14}"
jobs="${JOBS:-$(nproc)}"
command -v "$tidy" >/dev/null || { echo "check_function_sizes: $tidy not found (apt: clang-tidy-14)" >&2; exit 2; }
[ -f "$build/compile_commands.json" ] || { echo "check_function_sizes: no $build/compile_commands.json" >&2; exit 2; }
[ -f "$exceptions" ] || { echo "check_function_sizes: no exceptions file $exceptions" >&2; exit 2; }
mapfile -t sources < <(/usr/bin/python3 - "$root" "$build/compile_commands.json" <<'PY'
import json, os, sys
root, db = sys.argv[1], sys.argv[2]
seen = set()
for e in json.load(open(db)):
    path = os.path.realpath(os.path.join(e["directory"], e["file"]))
    rel = os.path.relpath(path, root)
    if rel.split(os.sep)[0] in ("model", "capi", "fmu", "cli") and path.endswith((".cpp", ".c")):
        seen.add(path)
print("\n".join(sorted(seen)))
PY
)
[ "${#sources[@]}" -gt 0 ] && [ -n "${sources[0]}" ] || {
  echo "check_function_sizes: no source of model/, capi/, fmu/ or cli/ in the compile database" >&2; exit 2; }
config='{Checks: "-*,readability-function-size", CheckOptions: [{key: readability-function-size.LineThreshold, value: 80}]}'
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# One file per clang-tidy process, so that the slow ones spread over the processes.
status=0
printf '%s\0' "${sources[@]}" |
  xargs -0 -n 1 -P "$jobs" "$tidy" -p "$build" --quiet --config="$config" \
    --header-filter="^$root/(model|capi|fmu|cli)/" >"$work/output" 2>"$work/errors" || status=$?
if [ "$status" -ne 0 ]; then
  echo "check_function_sizes: clang-tidy could not check every file (status $status):" >&2
  grep -E "error:|Error while processing" "$work/output" "$work/errors" | sed 's/^[^:]*://' | sort -u | head -20 >&2
  exit 2
fi
grep -E "warning: function '.*' exceeds recommended size" "$work/output" | sort -u >"$work/report" || true
failures=0
declare -A used
listed="$(grep -v '^#' "$exceptions" | sed -E 's/[[:space:]]+issue-[0-9]+$//' || true)"
while IFS= read -r line; do
  file="${line%%:*}"
  relative="${file#"$root"/}"
  function="$(sed -E "s/.*function '([^']*)'.*/\1/" <<<"$line")"
  key="$relative $function"
  if grep -qxF -- "$key" <<<"$listed"; then
    used[$key]=1
    continue
  fi
  echo "${line%%: warning*}: function '$function' is over 80 lines: split it" >&2
  failures=$((failures + 1))
done <"$work/report"
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
