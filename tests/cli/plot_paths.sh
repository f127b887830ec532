#!/usr/bin/env bash
# Plots start from an argument vector, never a shell: an --out folder whose name is a shell injection is
# just a folder (the plot lands in it, nothing else runs), and a plot that cannot be written is reported
# as not written (never "wrote ..." for a file that is not there).
# usage: plot_paths.sh JOINTCOMP_BINARY SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
work="$2"
plots="$(cd "$(dirname "$0")/../../cli/plots" && pwd)"
fail() { echo "plot_paths: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cd "$work"
hostile="$work/x'; touch pwned; echo \"\$(touch pwned2)\" '"
"$jointcomp" paper --quasi-static --nominal-only --out "$hostile" >log.txt 2>&1 || { cat log.txt; fail "paper failed"; }
[ ! -e pwned ] && [ ! -e pwned2 ] || fail "a shell ran the folder's name"
[ -s "$hostile/spiral_z_error.png" ] || { cat log.txt; fail "no plot in the folder with the hostile name"; }
grep -qF "wrote $hostile/spiral_z_error.png" log.txt || fail "the plot was not reported"
# The folder is made read-only after the CSV is written: the script cannot write the PNG, and the tool says
# so (as root the permission does not bind, so an existing directory named like the PNG blocks it instead).
blocked="$work/blocked"
mkdir -p "$blocked/spiral_z_error.png"
"$jointcomp" paper --quasi-static --nominal-only --out "$blocked" >log2.txt 2>&1 || { cat log2.txt; fail "paper failed"; }
grep -q "^no plot: " log2.txt || { cat log2.txt; fail "a plot that was not written was not reported as failed"; }
if grep -q "^wrote $blocked/spiral_z_error.png" log2.txt; then fail "reported a plot it did not write"; fi
# A plot child dies with its parent: jointcomp killed (SIGKILL) while its plot script runs leaves no
# process behind, and no PNG appears later. Children are found through /proc (procps may be absent).
children_of() {
  local stat ppid rest
  for stat in /proc/[0-9]*/stat; do
    read -r _ _ _ ppid rest <"$stat" 2>/dev/null || continue
    if [ "$ppid" = "$1" ]; then stat="${stat%/stat}"; echo "${stat#/proc/}"; fi
  done
}
# Alive: a process that is not a zombie (a dead child whose new parent has not reaped it yet).
alive() {
  local state
  state="$(cut -d ' ' -f 3 "/proc/$1/stat" 2>/dev/null)" || return 1
  [ -n "$state" ] && [ "$state" != Z ]
}
killed="$work/killed"
"$jointcomp" paper --quasi-static --nominal-only --out "$killed" >log3.txt 2>&1 &
parent=$!
# The plot starts after the spiral runs: seconds in a plain build, minutes under the sanitizers. Wait for
# it as long as the parent lives (bounded by the test's timeout), never by a guessed duration.
child=""
while alive "$parent"; do
  child="$(children_of "$parent" | head -n 1)"
  [ -n "$child" ] && break
  sleep 0.02
done
[ -n "$child" ] || { cat log3.txt; fail "no plot child was seen before jointcomp ended"; }
kill -9 "$parent"
wait "$parent" 2>/dev/null || true
for _ in $(seq 1 100); do
  alive "$child" || break
  sleep 0.02
done
if alive "$child"; then
  kill -9 "$child" 2>/dev/null || true
  fail "the plot child $child outlived its killed parent"
fi
sleep 1
[ ! -e "$killed/spiral_z_error.png" ] || fail "a PNG appeared after its writer's parent was killed"
# A plot killed while it saves leaves no temporary behind (issue 41: 11 of 12 kills of `paper` left a
# .XXXX.png.tmp): a figure that writes half a PNG and then kills its own process.
mkdir -p "$work/half"
status=0
PYTHONPATH="$plots" /usr/bin/python3 - "$work/half/plot.png" <<'PY' || status=$?
import os
import signal
import sys

from atomic_png import save_figure


class DyingFigure:
    def savefig(self, stream, dpi, format):
        stream.write(b"\x89PNG half of it")
        stream.flush()
        os.kill(os.getpid(), signal.SIGKILL)


save_figure(DyingFigure(), sys.argv[1], dpi=100)
PY
[ "$status" -eq 137 ] || fail "the dying plot exited $status, not by SIGKILL"
[ -z "$(ls -A "$work/half")" ] || { ls -la "$work/half"; fail "a plot killed while saving left files behind"; }
echo "plot_paths: hostile names are paths; failed plots are reported; a plot child dies with its parent"
