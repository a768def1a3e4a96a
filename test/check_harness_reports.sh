#!/usr/bin/env bash
# The harnesses' JSON reports follow DESIGN.md's schema (check_report_schema.py):
# bench_measures (figures of chapter 3 and 4) and bench_ring --quick (tables
# D.1, appendix C, quadrilaterals) are run and their reports checked, with
# their claim checks listed under "checks" and all holding; bench_certify
# --quick at p = 2 (issue 8: certified validity, Gmsh's validity analysis as
# peer) likewise, with its certificate keys and the peer's counts present.
# bench_certify needs Gmsh's library: skipped when it was not built.
# bench_boundary_layer --case sphere --quick (issue 9, table 6.4 at p = 2) too,
# with its planar cut through the curved layer (CSV, and the PNG when
# matplotlib is there).
#   $1 = bench_measures, $2 = bench_ring, $3 = bench_certify (optional; default:
#   bench_certify beside bench_ring, if built), $4 = bench_boundary_layer
#   (optional; default beside bench_ring, if built)
source "$(dirname "$0")/cli_common.sh"
measures=$1
ring=$2
certify=${3:-$(dirname "$ring")/bench_certify}
layer=${4:-$(dirname "$ring")/bench_boundary_layer}

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
if [[ -x $layer ]]; then
  "$layer" --case sphere --quick --threads 2 --out "$work/layer" --json "$work/layer.json" >/dev/null ||
    fail "bench_boundary_layer exit $?"
  "$py" "$schema" "$work/layer.json" --tool bench_boundary_layer --stage inserted --stage optimized ||
    fail "bench_boundary_layer report"
  all_checks_hold "$work/layer.json" || fail "bench_boundary_layer checks"
  # The cut: polygons of layer elements (level >= 0) and of the rest, none inverted.
  "$py" - "$work/layer/cut_sphere.csv" <<'PY' || fail "bench_boundary_layer cut CSV"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert rows, "empty cut"
levels = {int(r["level"]) for r in rows}
assert -1 in levels and max(levels) >= 0, levels
assert all(r["inverted"] == "0" for r in rows)
PY
  if "$py" -c "import matplotlib" 2>/dev/null; then
    [[ -s "$work/layer/cut_sphere.png" ]] || fail "bench_boundary_layer: no cut figure"
  fi
else
  echo "bench_boundary_layer not built: skipped"
fi
echo "harness reports conform"
