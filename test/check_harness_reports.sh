#!/usr/bin/env bash
# The harnesses' JSON reports follow DESIGN.md's schema (check_report_schema.py):
# bench_measures (figures of chapter 3 and 4) and bench_ring --quick (tables
# D.1, appendix C, quadrilaterals) are run and their reports checked, with
# their claim checks listed under "checks" and all holding.
#   $1 = bench_measures, $2 = bench_ring
set -uo pipefail
measures=$1
ring=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
py=/usr/bin/python3
[[ -x $py ]] || py=python3
schema="$(dirname "$0")/check_report_schema.py"

# all_checks_hold FILE: the report has a non-empty "checks" list and every claim holds.
all_checks_hold() {
  "$py" -c 'import json, sys
checks = json.load(open(sys.argv[1])).get("checks", [])
assert checks, "no checks"
failed = [c["claim"] for c in checks if not c["holds"]]
assert not failed, failed' "$1"
}

"$measures" --out "$work/measures" --json "$work/measures.json" >/dev/null || fail "bench_measures exit $?"
"$py" "$schema" "$work/measures.json" --tool bench_measures --stage "level sets" || fail "bench_measures report"
all_checks_hold "$work/measures.json" || fail "bench_measures checks"

"$ring" --quick --no-vtu --out "$work/ring" --json "$work/ring.json" >/dev/null || fail "bench_ring exit $?"
"$py" "$schema" "$work/ring.json" --tool bench_ring --stage initial --stage optimized || fail "bench_ring report"
all_checks_hold "$work/ring.json" || fail "bench_ring checks"
echo "harness reports conform"
