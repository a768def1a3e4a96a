#!/usr/bin/env bash
# `hom optimize --cad` end to end (chapter 5 through the command line): a
# curved degree-3 surface mesh of a sphere (written by `hom curve`), whose
# face nodes are then moved along the sphere (rotated about the axis by a
# node-dependent angle, so they stay on it but the elements distort), is
# optimized on the CAD sphere: exit 0, the minimum quality up by more than
# 0.02 and at least 0.99, no inverted element, every node on the sphere to 1e-9 (as
# hom evaluates it; the file's vertices too), the
# report in DESIGN.md's schema. With --certify every element is certified
# valid and the report says so. A tangled start (0.04 rad) is untangled; a
# corner fold (0.02 rad) is refused with its element named, or, with
# --certify, repaired; with --certify and no repair rounds the uncertified
# CAD face is named with the element. A linear mesh, options that do not
# apply on a CAD model, a missing model and a surface mesh without --cad are
# refused with the documented exit status and no output.
#   $1 = hom
source "$(dirname "$0")/cli_common.sh"
hom=$1
helper="$(dirname "$0")/sphere_surface_mesh.py"

# json_field FILE STAGE KEY: the surface part's KEY at STAGE.
json_field() { report_field "$1" "hom optimize" "$3" part=surface stage="$2"; }

"$py" "$helper" model "$work/sphere.brep" || fail "could not write the sphere model (python3-gmsh)"
log=$("$hom" curve "$work/sphere.brep" --surface --p 3 --size 0.5 -o "$work/curved.msh" --threads 1 2>&1) \
  || { echo "$log"; fail "hom curve of the sphere failed"; }
# 0.01 rad: a smoothing case (min quality about 0.96); larger rotations in 2b.
"$py" "$helper" perturb "$work/curved.msh" "$work/perturbed.msh" 0.01 || fail "could not perturb the mesh"

# 1. The perturbed mesh, optimized on the sphere.
log=$("$hom" optimize "$work/perturbed.msh" --cad "$work/sphere.brep" -o "$work/opt.msh" --json "$work/opt.json" \
        --vtu "$work/opt.vtu" --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3] /'
[[ $rc -eq 0 ]] || fail "optimize --cad: exit $rc"
[[ -s "$work/opt.msh" && -s "$work/opt.vtu" ]] || fail "optimize --cad: an output is missing"
initial=$(json_field "$work/opt.json" initial min_q) || fail "json: no initial stage"
final=$(json_field "$work/opt.json" optimized min_q) || fail "json: no optimized stage"
[[ $(json_field "$work/opt.json" optimized inverted) -eq 0 ]] || fail "json: inverted elements after optimization"
"$py" -c "import sys; sys.exit(0 if float('$final') > float('$initial') + 0.02 and float('$final') >= 0.99 else 1)" \
  || fail "minimum quality $initial -> $final: not smoothed"
"$py" "$schema" "$work/opt.json" --tool "hom optimize" --stage initial --stage optimized \
  || fail "json: not the DESIGN.md schema"
"$py" -c "import sys; sys.exit(0 if float('$(json_field "$work/opt.json" optimized max_cad_distance)') <= 1e-9 else 1)" \
  || fail "json: boundary nodes off the CAD"
"$py" "$helper" check "$work/opt.msh" 1e-9 1e-2 || fail "optimized nodes are not on the sphere"

# 2. --certify: each element, against its nodes' interpolated surface normals, certified valid
# (Bernstein bounds); the report carries the certificate, and for a surface
# mesh no scaled-Jacobian bound (it would bound (x_xi x x_eta) . n instead).
log=$("$hom" optimize "$work/perturbed.msh" --cad "$work/sphere.brep" -o "$work/cert.msh" --json "$work/cert.json" \
        --certify --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3 --certify] /'
[[ $rc -eq 0 ]] || fail "optimize --cad --certify: exit $rc"
[[ -s "$work/cert.msh" ]] || fail "optimize --cad --certify: no mesh written"
elements=$(json_field "$work/cert.json" optimized elements) || fail "json: no optimized stage"
[[ $(json_field "$work/cert.json" optimized certified_valid) -eq $elements ]] || fail "json: not every element certified valid"
[[ $(json_field "$work/cert.json" optimized certified_invalid) -eq 0 ]] || fail "json: certified invalid elements"
[[ $(json_field "$work/cert.json" optimized undecided) -eq 0 ]] || fail "json: undecided elements"
json_field "$work/cert.json" optimized certified_min_scaled_jacobian >/dev/null 2>&1 \
  && fail "json: a surface mesh reports a scaled-Jacobian bound"
grep -q "^  NOT CERTIFIED" <<<"$log" && fail "optimize --cad --certify: prints NOT CERTIFIED on exit 0"

# 2b. Larger rotations. At 0.04 rad 49 elements are tangled; the surface
# stage untangles them with p-continuation (appendix C on the surface):
# exit 0, nothing inverted. At 0.02 rad the optimized mesh folds one element
# at a corner node, between the quadrature points: without --certify the
# refusal (exit 3, nothing written) names the folded element with its
# centroid; with --certify the surface repair (surface/certified_surface.hpp)
# slides its nodes on the sphere until every element is certified valid.
"$py" "$helper" perturb "$work/curved.msh" "$work/tangled.msh" 0.04 || fail "could not perturb the mesh by 0.04"
log=$("$hom" optimize "$work/tangled.msh" --cad "$work/sphere.brep" -o "$work/untangled.msh" \
        --json "$work/untangled.json" --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3, 0.04 rad] /'
[[ $rc -eq 0 ]] || fail "optimize --cad of the tangled sphere: exit $rc"
[[ $(json_field "$work/untangled.json" initial inverted) -gt 0 ]] || fail "0.04 rad: the start is not tangled"
[[ $(json_field "$work/untangled.json" optimized inverted) -eq 0 ]] || fail "0.04 rad: inverted elements remain"
"$py" "$helper" perturb "$work/curved.msh" "$work/folded.msh" 0.02 || fail "could not perturb the mesh by 0.02"
log=$("$hom" optimize "$work/folded.msh" --cad "$work/sphere.brep" -o "$work/folded_opt.msh" --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3, 0.02 rad] /'
echo "$log" > "$work/folded_log"
[[ $rc -eq 3 ]] || fail "optimize --cad at 0.02 rad without --certify: exit $rc, expected 3 (a fold at a node)"
[[ ! -e "$work/folded_opt.msh" ]] || fail "0.02 rad: an invalid mesh was written"
grep -Eq "^  element [0-9]+: centroid \(" <<<"$log" || fail "0.02 rad: the refusal does not name the folded element"
log=$("$hom" optimize "$work/folded.msh" --cad "$work/sphere.brep" -o "$work/repaired.msh" --certify \
        --json "$work/repaired.json" --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3, 0.02 rad, --certify] /'
[[ $rc -eq 0 ]] || fail "optimize --cad --certify at 0.02 rad: exit $rc"
[[ $(json_field "$work/repaired.json" optimized initial_certified_invalid) -gt 0 ]] \
  || fail "0.02 rad: the optimized mesh was certified valid before the repair (the premise)"
[[ $(json_field "$work/repaired.json" optimized certify_rounds) -ge 1 ]] || fail "0.02 rad: no repair round ran"
[[ $(json_field "$work/repaired.json" optimized certified_invalid) -eq 0 ]] || fail "0.02 rad: certified invalid elements remain"
[[ $(json_field "$work/repaired.json" optimized undecided) -eq 0 ]] || fail "0.02 rad: undecided elements remain"
[[ $(json_field "$work/repaired.json" optimized inverted) -eq 0 ]] || fail "0.02 rad: inverted elements after the repair"
"$py" "$helper" check "$work/repaired.msh" 1e-9 1e-2 || fail "0.02 rad: repaired nodes are not on the sphere"
# With no repair rounds the fold stays: the face left uncertified is named,
# with its element (the one the refusal named) and why its repair stopped.
log=$("$hom" optimize "$work/folded.msh" --cad "$work/sphere.brep" -o "$work/unrepaired.msh" --certify \
        --certify-rounds 0 --threads 1 2>&1); rc=$?
echo "$log" | sed 's/^/  [sphere p=3, 0.02 rad, --certify-rounds 0] /'
[[ $rc -eq 3 ]] || fail "0.02 rad, no repair rounds: exit $rc, expected 3"
[[ ! -e "$work/unrepaired.msh" ]] || fail "0.02 rad, no repair rounds: an uncertified mesh was written"
folded=$(sed -nE 's/^  element ([0-9]+): centroid \(.*/\1/p' "$work/folded_log" | head -1)
[[ -n $folded ]] || fail "0.02 rad: no element named in the refusal"
grep -Eq "^ *CAD face [0-9]+: 1 invalid, 0 undecided of [0-9]+ \(elements $folded\); repair stopped: round limit" <<<"$log" \
  || fail "0.02 rad, no repair rounds: no line naming the uncertified face, element $folded and the round limit"

# 3. Refusals: exit 2 (usage) or 1 (unreadable model), nothing written.
"$py" "$helper" linear "$work/linear.msh" || fail "could not write a linear sphere mesh"
expect() {  # expect RC WORD hom-optimize-arguments...
  local want=$1 word=$2 err rc
  shift 2
  err=$("$hom" optimize "$@" -o "$work/x.msh" 2>&1 >/dev/null); rc=$?
  [[ $rc -eq $want ]] || fail "'$*': exit $rc, expected $want: $err"
  grep -q -- "$word" <<<"$err" || fail "'$*': the message does not mention $word: $err"
  [[ ! -e "$work/x.msh" ]] || fail "'$*': output written"
}
expect 2 "linear mesh" "$work/linear.msh" --cad "$work/sphere.brep"
expect 2 "--ideal" "$work/perturbed.msh" --cad "$work/sphere.brep" --ideal equilateral
expect 1 "missing.step" "$work/perturbed.msh" --cad "$work/missing.step"
expect 2 "--cad" "$work/perturbed.msh"
expect 2 "--merge-small-edges" "$work/perturbed.msh" --merge-small-edges 0.1
expect 2 "--merge-small-edges" "$work/perturbed.msh" --cad "$work/sphere.brep" --merge-small-edges -1

# 4. A square face whose left side is two edges, 9.97 and 0.03 long (test_cad's healing case): curved with
# --merge-small-edges 0.1, the mesh lies on the healed model (4 edges), which hom optimize --cad reads with the
# same option.
"$py" - "$work/small_edge.brep" <<'PY' || fail "could not write the small-edge model (python3-gmsh)"
import sys, gmsh
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
occ = gmsh.model.occ
p = [occ.addPoint(x, y, 0) for x, y in [(0, 0), (10, 0), (10, 10), (0, 10), (0.001, 0.03)]]
lines = [occ.addLine(p[i], p[(i + 1) % 5]) for i in range(5)]
occ.addPlaneSurface([occ.addCurveLoop(lines)])
occ.synchronize()
gmsh.write(sys.argv[1])
gmsh.finalize()
PY
log=$("$hom" curve "$work/small_edge.brep" --merge-small-edges 0.1 --p 3 --size 2 -o "$work/small.msh" \
  --threads 1 2>&1) \
  || { echo "$log"; fail "hom curve --merge-small-edges of the small-edge model failed"; }
grep -q "healed: small edges" <<<"$log" || fail "small-edge model: no healing reported: $log"
log=$("$hom" optimize "$work/small.msh" --cad "$work/small_edge.brep" --merge-small-edges 0.1 -o "$work/small.opt.msh" \
        --threads 1 2>&1); rc=$?
echo "$log" | grep -E "healed|valid" | sed 's/^/  [small edge] /'
[[ $rc -eq 0 && -s "$work/small.opt.msh" ]] || fail "optimize --cad --merge-small-edges: exit $rc: $log"
echo "cli optimize --cad: ok"
