#!/usr/bin/env bash
# The harnesses' JSON reports follow DESIGN.md's schema (check_report_schema.py):
# bench_measures (figures of chapter 3 and 4) and bench_ring --quick (tables
# D.1, appendix C, quadrilaterals) are run and their reports checked, with
# their claim checks listed under "checks" and all holding; bench_certify
# --quick at p = 2 (issue 8: certified validity, Gmsh's validity analysis as
# peer) likewise, with its certificate keys and the peer's counts present.
# bench_certify needs Gmsh's library: skipped when it was not built.
#   $1 = bench_measures, $2 = bench_ring, $3 = bench_certify (optional; default:
#   bench_certify beside bench_ring, if built)
source "$(dirname "$0")/cli_common.sh"
measures=$1
ring=$2
certify=${3:-$(dirname "$ring")/bench_certify}

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

if [[ -x $certify ]]; then
  "$certify" --quick --p 2 --max-iterations 10 --threads 2 --out "$work/certify" --json "$work/certify.json" >/dev/null ||
    fail "bench_certify exit $?"
  "$py" "$schema" "$work/certify.json" --tool bench_certify --stage initial --stage optimized || fail "bench_certify report"
  all_checks_hold "$work/certify.json" || fail "bench_certify checks"
  "$py" -c 'import json, sys
for c in json.load(open(sys.argv[1]))["cases"]:
    n = c["certified_valid"] + c["certified_invalid"] + c["undecided"]
    assert n == c["elements"], (c["stage"], n, c["elements"])
    assert c["certified_min_scaled_jacobian"] <= c["min_scaled_jacobian"] + 1e-12, c["stage"]
    peer = c["peer"]
    assert peer["tool"] == "gmsh" and peer["certified_valid"] + peer["certified_invalid"] == n, peer
    assert peer["disagreements"] == 0, peer' "$work/certify.json" || fail "bench_certify certificate keys"
else
  echo "bench_certify not built (no Gmsh library): skipped"
fi
echo "harness reports conform"
