#!/usr/bin/env bash
# Fails when a source file (C, C++, Python, CMake, shell) of the repository is longer than 800 lines, naming
# it and its length. A file may stand over the limit only while an entry of the exceptions file names it with
# the issue that splits it and its length then; the entry fails the check as soon as the file grows past that
# length, and once the file is within the limit (drop the entry), so that the list only gets shorter.
# usage: check_file_sizes.sh SOURCE_ROOT EXCEPTIONS_FILE
set -euo pipefail
root="$1"
exceptions="$2"
limit=800
declare -A allowed
while read -r path lines issue; do
  [[ -z "${path:-}" || "$path" == \#* ]] && continue
  [[ "$lines" =~ ^[0-9]+$ && "$issue" =~ ^issue-[0-9]+$ ]] || {
    echo "$exceptions: '$path $lines $issue': expected 'PATH LINES issue-N'" >&2; exit 2; }
  allowed[$path]=$lines
done <"$exceptions"
failures=0
checked=0
while IFS= read -r -d '' file; do
  relative="${file#"$root"/}"
  lines=$(wc -l <"$file")
  checked=$((checked + 1))
  if [ -n "${allowed[$relative]+x}" ]; then
    if [ "$lines" -gt "${allowed[$relative]}" ]; then
      echo "$relative: $lines lines, more than the ${allowed[$relative]} its exception allows (split it)" >&2
      failures=$((failures + 1))
    elif [ "$lines" -le "$limit" ]; then
      echo "$relative: $lines lines, within the limit: drop its entry from $exceptions" >&2
      failures=$((failures + 1))
    elif [ "$lines" -lt "${allowed[$relative]}" ]; then
      echo "note: $relative shrank to $lines lines: lower its entry in $exceptions (${allowed[$relative]})"
    fi
    unset "allowed[$relative]"
  elif [ "$lines" -gt "$limit" ]; then
    echo "$relative: $lines lines, over the limit of $limit: split it" >&2
    failures=$((failures + 1))
  fi
done < <(find "$root" \( -path "$root/build" -o -path "$root/.git" -o -path "$root/tests/data" \) -prune -o \
           -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.c' -o -name '*.h' -o -name '*.py' -o -name '*.sh' \
           -o -name 'CMakeLists.txt' -o -name '*.cmake' \) -print0)
for path in "${!allowed[@]}"; do
  echo "$exceptions: $path is no longer in the tree: drop its entry" >&2
  failures=$((failures + 1))
done
[ "$checked" -gt 0 ] || { echo "check_file_sizes: no source file under $root" >&2; exit 2; }
if [ "$failures" -gt 0 ]; then
  echo "check_file_sizes: $failures file(s) against the limit of $limit lines" >&2
  exit 1
fi
echo "check_file_sizes: $checked files within $limit lines (exceptions: $(grep -c '^[^#[:space:]]' "$exceptions" || true))"
