#!/usr/bin/env bash
# `hom boundary-layer` end to end: a linear tetrahedral and a triangular mesh
# (make_tangled_mesh with no perturbation: the sheared unit cube / square, a
# curved-but-faceted wall at z = 0 / y = 0) get a boundary layer: exit 0, the
# output is valid for `hom quality`, the JSON report has the five stages with
# the template's element counts and no inverted element at the end (with
# --certify, every element certified valid); a layer
# too thick for the domain stops at the tangled linear stage (c) with exit 3;
# bad options and inputs fail with the documented exit status and leave no
# output behind.
#   $1 = hom, $2 = make_tangled_mesh (test/make_tangled_mesh.cpp)
source "$(dirname "$0")/cli_common.sh"
hom=$1
gen=$2

# check_report JSON PER_FACET WALL_FACETS: five stages, counts, valid result.
check_report() {
  "$py" -c 'import json, sys
r = json.load(open(sys.argv[1]))
per, walls = int(sys.argv[2]), int(sys.argv[3])
assert r["tool"] == "hom boundary-layer", r["tool"]
stages = [c["stage"] for c in r["cases"]]
assert stages == ["inviscid", "inserted", "smoothed", "curved", "optimized"], stages
e0 = r["cases"][0]["elements"]
for c in r["cases"][1:]:
    assert c["elements"] == e0 + per * walls, (c["stage"], c["elements"], e0)
assert r["cases"][-1]["inverted"] == 0, r["cases"][-1]
assert r["cases"][2]["inverted"] == 0, r["cases"][2]
assert r["cases"][-1]["aspect_ratio"] > 1.0
' "$@" || fail "report $1"
}

# bl_case NAME FAMILY N WALL PER_FACET WALL_FACETS [options...]
bl_case() {
  local name=$1 family=$2 n=$3 wall=$4 per=$5 walls=$6
  shift 6
  local in="$work/$name.msh" out="$work/$name.bl.msh" json="$work/$name.json" vtu="$work/$name.vtu"
  "$gen" make "$family" 1 "$n" "$in" 4.1 0 >/dev/null  # exits 1: nothing inverted, which is what we want
  [[ -s $in ]] || fail "$name: generator wrote nothing"
  local log rc
  log=$("$hom" boundary-layer "$in" --walls "$wall" -o "$out" --json "$json" --vtu "$vtu" "$@" 2>&1); rc=$?
  echo "$log" | sed "s/^/  [$name] /"
  [[ $rc -eq 0 ]] || fail "$name: exit $rc"
  [[ -s $out && -s $json && -s $vtu ]] || fail "$name: missing output"
  [[ ! -e "$out.tmp" && ! -e "$json.tmp" ]] || fail "$name: temporary file left behind"
  grep -q "^  optimized" <<<"$log" || fail "$name: no stage table"
  "$hom" quality "$out" >/dev/null; rc=$?
  [[ $rc -eq 0 ]] || fail "$name: hom quality of the output exits $rc"
  check_report "$json" "$per" "$walls"
}

# Tetrahedra: 2 x 2 x 2 cells, wall z = 0 (entity 5: 8 triangles); 12 (L - 1) + 7 per wall triangle.
bl_case tet tet 2 5 19 8 --bl-first 0.02 --bl-layers 2 --p 2 --certify
# --certify: every element of the result certified valid everywhere.
"$py" -c 'import json, sys
c = json.load(open(sys.argv[1]))["cases"][-1]
assert c["certified_valid"] == c["elements"], c
' "$work/tet.json" || fail "tet: not every element certified valid"
# Triangles: 3 x 3 cells, wall y = 0 (entity 3: 3 edges); 4 (L - 1) + 3 per wall edge.
# --bl-total 0.07 = 0.01 + 0.02 + 0.04: the three layers that reach it.
bl_case tri tri 3 3 11 3 --bl-first 0.01 --bl-total 0.07 --p 3

# A layer thicker than the domain (H = 3.5 in the unit square): the smoothed
# linear mesh stays tangled, so the degree-P stages are not run; exit 3, the
# reason on stdout, the tangled linear mesh written, and the report's three
# stages end inverted.
tangled_json="$work/thick.json"
log=$("$hom" boundary-layer "$work/tri.msh" --walls 3 --bl-first 0.5 --bl-layers 3 --p 3 --max-iterations 20 \
      -o "$work/thick.msh" --json "$tangled_json" 2>&1); rc=$?
echo "$log" | sed "s/^/  [thick] /"
[[ $rc -eq 3 ]] || fail "thick layer: exit $rc, want 3"
grep -q "stages (d) and (e) were not run" <<<"$log" || fail "thick layer: no reason given"
[[ -s "$work/thick.msh" ]] || fail "thick layer: the tangled linear mesh was not written"
"$hom" info "$work/thick.msh" | grep -q "order 1$" || fail "thick layer: the output is not the linear stage (c) mesh"
"$py" -c 'import json, sys
r = json.load(open(sys.argv[1]))
stages = [c["stage"] for c in r["cases"]]
assert stages == ["inviscid", "inserted", "smoothed"], stages
assert r["cases"][-1]["inverted"] > 0, r["cases"][-1]
assert r["cases"][-1]["p"] == 1, r["cases"][-1]
' "$tangled_json" || fail "thick layer: report"

# Bad options and inputs: exit 2 (1 for an unreadable file), no output.
in="$work/tet.msh"
expect() {
  local want=$1
  shift
  rm -f "$work/bad.msh"
  "$hom" boundary-layer "$@" -o "$work/bad.msh" >/dev/null 2>"$work/err"; local rc=$?
  [[ $rc -eq $want ]] || fail "'$*': exit $rc, want $want ($(cat "$work/err"))"
  [[ -s "$work/err" ]] || fail "'$*': no error message"
  [[ ! -e "$work/bad.msh" ]] || fail "'$*': output written"
}
expect 2 "$in" --walls 5                                         # no --bl-first
expect 2 "$in" --walls 5 --bl-first 0                            # bad height
expect 2 "$in" --walls 5 --bl-first 0.1 --bl-growth 0.5         # bad growth
expect 2 "$in" --walls 5 --bl-first 0.1 --bl-layers 0           # bad layers
expect 2 "$in" --walls 5 --bl-first 0.1 --bl-layers 3 --bl-total 0.7   # layers given twice
expect 2 "$in" --walls 5 --bl-first 0.1 --bl-total -1           # bad total height
expect 2 "$in" --walls 99 --bl-first 0.1                        # no such wall
expect 2 "$in" --walls x --bl-first 0.1                         # not a tag
expect 2 "$in" --walls 5 --bl-first 0.1 --wall-geometry sphere:1,2   # bad geometry
expect 2 "$in" --bl-first 0.1                                   # no wall
expect 2 "$in" --walls 5 --bl-first 0.1 --certify-depth 21      # bad certification depth
"$gen" make tet 2 1 "$work/p2.msh" 4.1 0 >/dev/null
expect 2 "$work/p2.msh" --walls 5 --bl-first 0.1                # not linear
expect 1 "$work/missing.msh" --walls 5 --bl-first 0.1           # unreadable
echo "all boundary-layer CLI checks passed"
