#!/usr/bin/env bash
# The function-size check itself, on a scratch tree of its own (two small files of model/ and a compile
# database; a second each): a function one line within clang-tidy's count of 80 passes, one a line longer
# fails naming its file and function, in a source or in a project header a source includes; an exception
# entry lets it pass, an entry for a function that is not long fails, and so does a file that does not parse.
# usage: check_function_sizes_catches.sh SOURCE_ROOT SCRATCH_DIR
set -euo pipefail
root="$(cd "$1" && pwd)"
work="$2"
check="$root/tests/limits/check_function_sizes.sh"
rm -rf "$work"
mkdir -p "$work/model/common" "$work/build"
work="$(cd "$work" && pwd)"

# A function whose definition spans LINES lines, from its signature to its closing brace.
function_of() {  # function_of NAME LINES
  echo "int $1(int x) {"
  for ((i = 0; i < $2 - 3; ++i)); do echo "  x += $i;"; done
  echo "  return x;"
  echo "}"
}
{
  echo '#include "model/common/planted.hpp"'
  function_of within 81  # clang-tidy counts from the opening brace's line to the closing one's: 80
} >"$work/model/common/planted.cpp"
echo '#pragma once' >"$work/model/common/planted.hpp"
cat >"$work/build/compile_commands.json" <<EOF
[{"directory": "$work/build", "file": "$work/model/common/planted.cpp",
  "command": "c++ -I$work -std=c++17 -c $work/model/common/planted.cpp -o planted.o"}]
EOF
: >"$work/exceptions.txt"
run() { JOBS=1 bash "$check" "$work" "$work/build" "$work/exceptions.txt" >"$work/out" 2>"$work/message"; }
expect_failure() {  # expect_failure WHAT PATTERN: the check fails, its message matching PATTERN
  if run; then echo "check_function_sizes_catches: $1 passed the check" >&2; exit 1; fi
  grep -qE "$2" "$work/message" || {
    echo "check_function_sizes_catches: for $1 the message does not match '$2':" >&2; cat "$work/message" >&2; exit 1; }
}

run || { echo "check_function_sizes_catches: a function of 80 lines failed the check:" >&2; cat "$work/message" >&2; exit 1; }

function_of planted_long 82 >>"$work/model/common/planted.cpp"
expect_failure "a function of 81 lines" "model/common/planted.cpp:[0-9]+:[0-9]+: function 'planted_long' is over 80 lines"

echo "model/common/planted.cpp planted_long issue-1" >"$work/exceptions.txt"
run || { echo "check_function_sizes_catches: a listed exception failed the check:" >&2; cat "$work/message" >&2; exit 1; }

echo "model/common/planted.cpp within issue-1" >>"$work/exceptions.txt"
expect_failure "an exception for a function within the limit" "'model/common/planted.cpp within' is no longer over 80 lines"

: >"$work/exceptions.txt"
sed -i '/^int planted_long/,$d' "$work/model/common/planted.cpp"
function_of in_header 82 | sed 's/^int /inline int /' >>"$work/model/common/planted.hpp"
expect_failure "a long function in a project header" "model/common/planted.hpp:[0-9]+:[0-9]+: function 'in_header' is over 80 lines"

echo '#pragma once' >"$work/model/common/planted.hpp"
echo 'int broken( {' >>"$work/model/common/planted.cpp"
expect_failure "a file that does not parse" "clang-tidy could not check every file"

echo "check_function_sizes_catches: long functions, stale exceptions and unparsed files are refused and named"
