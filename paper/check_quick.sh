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
