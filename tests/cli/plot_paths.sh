#!/usr/bin/env bash
# Plots start from an argument vector, never a shell: an --out folder whose name is a shell injection is
# just a folder (the plot lands in it, nothing else runs), and a plot that cannot be written is reported
# as not written (never "wrote ..." for a file that is not there).
# usage: plot_paths.sh JOINTCOMP_BINARY SCRATCH_DIR
set -euo pipefail
jointcomp="$1"
work="$2"
fail() { echo "plot_paths: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
cd "$work"
hostile="$work/x'; touch pwned; echo \"\$(touch pwned2)\" '"
"$jointcomp" paper --quasi-static --out "$hostile" >log.txt 2>&1 || { cat log.txt; fail "paper failed"; }
[ ! -e pwned ] && [ ! -e pwned2 ] || fail "a shell ran the folder's name"
[ -s "$hostile/spiral_z_error.png" ] || { cat log.txt; fail "no plot in the folder with the hostile name"; }
grep -qF "wrote $hostile/spiral_z_error.png" log.txt || fail "the plot was not reported"
# The folder is made read-only after the CSV is written: the script cannot write the PNG, and the tool says
# so (as root the permission does not bind, so an existing directory named like the PNG blocks it instead).
blocked="$work/blocked"
mkdir -p "$blocked/spiral_z_error.png"
"$jointcomp" paper --quasi-static --out "$blocked" >log2.txt 2>&1 || { cat log2.txt; fail "paper failed"; }
grep -q "^no plot: " log2.txt || { cat log2.txt; fail "a plot that was not written was not reported as failed"; }
if grep -q "^wrote $blocked/spiral_z_error.png" log2.txt; then fail "reported a plot it did not write"; fi
echo "plot_paths: hostile names are paths; failed plots are reported"
