#!/usr/bin/env bash
# Nothing lost: `jointcomp` killed (SIGKILL, its whole process group) at many moments of a writing run
# leaves every output file either whole (byte-identical to an uninterrupted run's) or absent, never a
# partial file or a temporary; the input files are byte-identical afterwards.
#   kill_during_write.sh <jointcomp binary> <model folder (robots/, params/)>
# Runs `jointcomp paper --quasi-static` (writes out/paper/spiral_runs.csv, summary.json and out/paper/fmu/*.fmu)
# and `jointcomp simulate --perturb` (a campaign and its perturbed truth). The plots are left out
# (--no-plot): matplotlib writes the PNG in place (see docs/testing.md). The campaign has 20,000
# poses (about 0.25 s, 3.5 MB): with the default 200 it took 30 ms, less than starting the processes that time
# the kills on a loaded machine, and then no kill landed before it ended.
set -euo pipefail
jointcomp="$(realpath "$1")" model="$(realpath "$2")"
work="$(mktemp -d /tmp/jointcomp-kill-XXXXXX)"
trap 'rm -rf "$work"' EXIT

mkdir -p "$work/in"
cp "$model/robots/rx170.urdf" "$model/params/rx170.json" "$work/in/"
chmod a-w "$work/in"/*  # a tool that tried to write them would fail loudly
inputs_before="$(cd "$work/in" && sha256sum -- *)"

commands=(
  "paper --quasi-static --urdf $work/in/rx170.urdf --params $work/in/rx170.json --out out/paper --no-plot"
  "simulate --protocol random --count 20000 --urdf $work/in/rx170.urdf --truth $work/in/rx170.json --perturb 3 --out out/campaign.csv"
)

failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# Every file under <folder> must be one of the reference's, with the same bytes.
check_outputs() {
  local folder="$1" reference="$2" what="$3"
  while IFS= read -r -d '' file; do
    local name="${file#"$folder"/}"
    case "$name" in
      *.tmp.*) fail "$what: a temporary was left behind: $name" ;;
      *)
        if [ ! -f "$reference/$name" ]; then
          fail "$what: an unexpected file: $name"
        elif ! cmp -s "$file" "$reference/$name"; then
          fail "$what: $name differs from the uninterrupted run's (partial?)"
        fi ;;
    esac
  done < <(find "$folder" -type f -print0)
}

for index in "${!commands[@]}"; do
  command="${commands[$index]}"
  reference="$work/reference$index"
  mkdir -p "$reference"
  started=$(date +%s%N)
  # shellcheck disable=SC2086  # the command is a list of words
  (cd "$reference" && "$jointcomp" $command >/dev/null)
  took_ms=$((($(date +%s%N) - started) / 1000000))
  outputs=$(find "$reference" -type f | wc -l)
  [ "$outputs" -gt 0 ] || fail "jointcomp $command wrote nothing"
  echo "jointcomp ${command%% *}: $outputs files in $took_ms ms uninterrupted"

  interrupted=0 partial_sets=0
  # Kill at 3 %, 10 %, 25 %, ... 98 % of the uninterrupted run's time.
  for percent in 3 10 25 40 55 70 80 90 95 98; do
    run="$work/run$index-$percent"
    mkdir -p "$run"
    delay="$(awk -v ms="$took_ms" -v p="$percent" 'BEGIN { printf "%.3f", ms * p / 100000 }')"  # before the start
    # setsid: a process group of its own, killed whole as a crash or an OOM kill of the session would.
    # shellcheck disable=SC2086
    (cd "$run" && exec setsid "$jointcomp" $command >/dev/null 2>&1) &
    pid=$!
    sleep "$delay"
    if kill -0 "$pid" 2>/dev/null; then
      interrupted=$((interrupted + 1))
      kill -KILL -- "-$pid" 2>/dev/null || kill -KILL "$pid" 2>/dev/null || true
    fi
    wait "$pid" 2>/dev/null || true
    written=$(find "$run" -type f | wc -l)
    if [ "$written" -gt 0 ] && [ "$written" -lt "$outputs" ]; then partial_sets=$((partial_sets + 1)); fi
    check_outputs "$run" "$reference" "killed at $percent % of jointcomp ${command%% *}"
  done
  echo "  $interrupted runs killed part-way, $partial_sets of them after some of the files were written"
  [ "$interrupted" -gt 0 ] || fail "no run of jointcomp ${command%% *} was killed part-way: the test proves nothing"
done

inputs_after="$(cd "$work/in" && sha256sum -- *)"
[ "$inputs_before" = "$inputs_after" ] || fail "the input files changed"
if [ "$failures" -gt 0 ]; then
  echo "$failures failures"
  exit 1
fi
echo "every output whole or absent, no temporaries, inputs unchanged"
