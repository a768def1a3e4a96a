#!/usr/bin/env bash
# The meson test paper_quick: `paper/make --quick` against the build directory into a temporary
# directory, then paper/check_report.py on the report (header with command, commit and machine;
# every thesis table with thesis and hom columns holding numbers, or a stated reason; figure links).
# It skips the four costliest runs on a loaded 2-core machine (the appendix F plots, two of the
# solver-comparison runs, and the CAD cube, whose table 6.2 then says so); the report lists them
# as skipped.
#   $1 = the build directory (meson's project build root)
set -uo pipefail
build=${1:?usage: check_quick.sh BUILD_DIR}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
py=/usr/bin/python3
[[ -x $py ]] || { echo "no /usr/bin/python3: skipped"; exit 77; }
"$py" -c 'import matplotlib' 2>/dev/null || { echo "no matplotlib for /usr/bin/python3: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
start=$(date +%s)
"$here/make" --quick --build "$build" --out "$work/out" --work "$work/runs" \
  --skip surface_appendixF,curve_cube,untangle_newton,untangle_pcont || { echo "FAIL: paper/make exit $?"; exit 1; }
echo "paper/make --quick took $(( $(date +%s) - start )) s"
"$py" "$here/check_report.py" "$work/out/report.md" || exit 1
# The quick untangling run names two Gmsh modes (--peer-mode 3,4): hom runs once, Gmsh once per
# mode, and the peer table has a row for each.
for mode in 3 4; do
  grep -q "^| perturbed p = 2 | mode $mode | " "$work/out/report.md" ||
    { echo "FAIL: no peer row for Gmsh mode $mode in the report"; exit 1; }
done
"$py" -c 'import json, sys
opt = [c for c in json.load(open(sys.argv[1]))["cases"] if c["stage"] == "optimized"]
assert len(opt) == 1 and [p["mode"] for p in opt[0]["peers"]] == [3, 4], opt
assert opt[0]["peer"] == opt[0]["peers"][0]' "$work/runs/untangle.json" ||
  { echo "FAIL: bench_untangle --peer-mode 3,4: the optimized case's peers"; exit 1; }
"$build/bench/bench_untangle" --peer gmsh --peer-mode 3,3 >"$work/bad.txt" 2>&1
[[ $? -eq 2 ]] && grep -q "named twice" "$work/bad.txt" ||
  { echo "FAIL: bench_untangle --peer-mode 3,3 is not refused"; cat "$work/bad.txt"; exit 1; }
# A new work directory (a fresh checkout) gathers the same report again from what the first one
# kept beside it (data/runs.json, data/*.json, figures/): only the lines that name how and where
# it was made may differ.
same_report() { grep -v -e '^- report rebuilt' -e '^- total wall time' -e 'stay in the work directory' "$1"; }
cp "$work/out/report.md" "$work/first.md"
"$here/make" --quick --build "$build" --out "$work/out" --work "$work/fresh" --no-run >/dev/null ||
  { echo "FAIL: paper/make --no-run in a new work directory"; exit 1; }
if ! diff <(same_report "$work/first.md") <(same_report "$work/out/report.md") >"$work/kept.diff"; then
  echo "FAIL: the report gathered again from data/runs.json differs:"
  head -20 "$work/kept.diff"
  exit 1
fi
"$py" "$here/check_report.py" "$work/out/report.md" || exit 1
echo "the report gathers again from a new work directory"
