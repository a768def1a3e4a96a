#!/usr/bin/env bash
# `hom optimize` end to end: generated curved meshes with randomly moved
# interior nodes (some elements inverted) are untangled (exit 0, `hom quality`
# of the output finds no inverted element, the boundary nodes did not move, the
# JSON report says 0 inverted, the output keeps the input's MSH version); bad
# input, bad options and surface meshes fail with the documented exit status
# and leave no output behind.
#   $1 = hom, $2 = make_tangled_mesh (test/make_tangled_mesh.cpp)
source "$(dirname "$0")/cli_common.sh"
hom=$1
gen=$2

# json_field FILE STAGE KEY: the KEY of the case whose stage is STAGE.
json_field() { report_field "$1" "hom optimize" "$3" stage="$2"; }

# optimize_case NAME FAMILY P N MSH_VERSION [hom optimize options...]
optimize_case() {
  local name=$1 family=$2 p=$3 n=$4 version=$5
  shift 5
  local in="$work/$name.msh" out="$work/$name.opt.msh" json="$work/$name.json"
  "$gen" make "$family" "$p" "$n" "$in" "$version" || fail "$name: generator (no inverted element?)"
  "$hom" quality "$in" >/dev/null; [[ $? -eq 3 ]] || fail "$name: hom quality does not see the input as tangled"
  local log rc
  log=$("$hom" optimize "$in" -o "$out" --json "$json" "$@" 2>&1); rc=$?
  echo "$log" | sed "s/^/  [$name] /"
  [[ $rc -eq 0 ]] || fail "$name: hom optimize exit $rc"
  [[ -s "$out" ]] || fail "$name: no output mesh"
  [[ ! -e "$out.tmp" && ! -e "$json.tmp" ]] || fail "$name: temporary file left behind"
  grep -q "^initial" <<<"$log" && grep -q "^optimized" <<<"$log" || fail "$name: no before/after table"
  grep -q "iterations, stopped on" <<<"$log" || fail "$name: no solver summary"
  # The output is valid for `hom quality` too (an independent read of the file).
  "$hom" quality "$out" >/dev/null; rc=$?
  [[ $rc -eq 0 ]] || fail "$name: hom quality of the output exits $rc"
  # Same MSH version as the input.
  [[ $(sed -n 2p "$out" | cut -d' ' -f1) == "$version" ]] || fail "$name: output is not MSH $version"
  # Boundary (non-free) nodes unchanged, free nodes moved.
  "$gen" fixed-match "$in" "$out" || fail "$name: boundary nodes moved or nothing moved"
  # The JSON report.
  [[ $(json_field "$json" initial inverted) -gt 0 ]] || fail "$name: json: initial case has no inverted element"
  [[ $(json_field "$json" optimized inverted) -eq 0 ]] || fail "$name: json: optimized case has inverted elements"
  [[ $(json_field "$json" optimized iterations) -gt 0 ]] || fail "$name: json: no iterations"
  json_field "$json" optimized stop_reason >/dev/null || fail "$name: json: no stop_reason"
  json_field "$json" optimized time_s >/dev/null || fail "$name: json: no time_s"
  "$py" "$schema" "$json" --tool "hom optimize" --stage initial --stage optimized || fail "$name: json: not the DESIGN.md schema"
}

optimize_case tri3 tri 3 4 4.1 --vtu "$work/tri3.vtu"
grep -q 'Name="pointwise_quality"' "$work/tri3.vtu" || fail "tri3: vtu has no pointwise_quality array"
[[ $(json_field "$work/tri3.json" optimized solver) == newton ]] || fail "tri3: auto should pick newton"
# One thread from here on: these meshes are small, and OpenMP's default team
# spinning on a loaded machine costs seconds per solve.
optimize_case quad3 quad 3 4 2.2 --solver gauss-seidel --pcont --threads 1
optimize_case tet2 tet 2 2 4.1 --solver matrix-free --measure oddy --threads 1
optimize_case hex2 hex 2 2 2.2 --solver newton --quadrature thesis --ideal equilateral --threads 1
optimize_case tri3v tri 3 4 4.1 --vertex-continuation --scope whole-mesh --threads 1
[[ $(json_field "$work/tri3v.json" optimized regularization_scope) == whole-mesh ]] || fail "tri3v: json: scope not recorded"

# Tangled vertices: the straight-sided ideal of those elements is inverted, so
# they are measured against the equilateral element (and the run says so); both
# ideals untangle the mesh.
"$gen" make tri 1 3 "$work/lin.msh" 4.1 2.0 1 >/dev/null || fail "lin: generator"
out=$("$hom" optimize "$work/lin.msh" -o "$work/lin.opt.msh" --threads 1 2>&1); rc=$?
[[ $rc -eq 0 ]] || fail "tangled vertices, straight-sided ideal: exit $rc, expected 0: $out"
grep -q "elements measured against the equilateral element: their straight-sided counterparts are inverted" \
  <<<"$out" ||
  fail "tangled vertices: no note: $out"
"$hom" quality "$work/lin.opt.msh" >/dev/null || fail "tangled vertices, straight-sided ideal: output not valid"
"$hom" optimize "$work/lin.msh" -o "$work/lin.opt.msh" --threads 1 --ideal equilateral >/dev/null 2>&1; rc=$?
[[ $rc -eq 0 ]] || fail "tangled vertices, equilateral ideal: exit $rc, expected 0"
"$hom" quality "$work/lin.opt.msh" --ideal equilateral >/dev/null || fail "tangled vertices: output not valid"

# --certify (issue 8). A curved boundary node near a corner turns the boundary
# edge's tangent into its element: plain optimization ends valid at every
# quadrature point (exit 0) with a fold at the corner that `hom quality
# --certify` rejects (exit 3); `--certify` repairs it (exit 0, JSON counts
# with hom quality's keys, the output certifies valid independently);
# `--certify-rounds 0` only reports (exit 3).
"$gen" make tri 3 3 "$work/fold.msh" 4.1 0.0 >/dev/null   # unperturbed interior (exits 1: nothing inverted)
"$py" - "$work/fold.msh" <<'PY' || fail "fold: could not move the boundary node"
import math, sys
path = sys.argv[1]
lines = open(path).read().split("\n")
start = lines.index("$Nodes")
blocks = int(lines[start + 1].split()[0])
i, best = start + 2, None
target = (1 / 3 + 1 / 18, 0.1 * math.sin(math.pi * (1 / 3 + 1 / 18)))
for _ in range(blocks):
    dim, tag, parametric, count = map(int, lines[i].split())
    coords = i + 1 + count
    for k in range(count):
        x = list(map(float, lines[coords + k].split()[:3]))
        d = math.hypot(x[0] - target[0], x[1] - target[1])
        if dim < 2 and (best is None or d < best[0]):
            best = (d, coords + k, x)
    i = coords + count
d, line, x = best
assert d < 0.1, d
x[0] -= 0.3 / 3
x[1] += 0.4 / 3
lines[line] = " ".join(repr(v) for v in x)
open(path, "w").write("\n".join(lines))
PY
"$hom" optimize "$work/fold.msh" -o "$work/fold.plain.msh" --threads 1 >/dev/null 2>&1; rc=$?
[[ $rc -eq 0 ]] || fail "fold: plain optimize exit $rc, expected 0 (valid at the quadrature points)"
"$hom" quality "$work/fold.plain.msh" --certify >/dev/null; rc=$?
[[ $rc -eq 3 ]] || fail "fold: hom quality --certify of the plain result exits $rc, expected 3 (a corner fold)"
log=$("$hom" optimize "$work/fold.msh" -o "$work/fold.cert.msh" --threads 1 --certify --json "$work/fold.json" 2>&1); rc=$?
echo "$log" | sed "s/^/  [fold] /"
[[ $rc -eq 0 ]] || fail "fold: hom optimize --certify exit $rc, expected 0"
grep -q "after optimization: .* [1-9][0-9]* certified invalid" <<<"$log" || fail "fold: no certificate before repair"
grep -q "repair: [1-9]" <<<"$log" || fail "fold: no repair round reported"
[[ $(json_field "$work/fold.json" optimized certified_invalid) -eq 0 ]] || fail "fold: json: certified_invalid"
[[ $(json_field "$work/fold.json" optimized undecided) -eq 0 ]] || fail "fold: json: undecided"
[[ $(json_field "$work/fold.json" optimized certified_valid) -eq $(json_field "$work/fold.json" optimized elements) ]] ||
  fail "fold: json: certified_valid is not the element count"
[[ $(json_field "$work/fold.json" optimized initial_certified_invalid) -gt 0 ]] || fail "fold: json: initial_certified_invalid"
json_field "$work/fold.json" optimized certified_min_scaled_jacobian >/dev/null || fail "fold: json: no certified_min_scaled_jacobian"
"$py" "$schema" "$work/fold.json" --tool "hom optimize" --stage initial --stage optimized || fail "fold: json: not the DESIGN.md schema"
"$hom" quality "$work/fold.cert.msh" --certify >/dev/null || fail "fold: hom quality --certify of the repaired mesh fails"
"$gen" fixed-match "$work/fold.msh" "$work/fold.cert.msh" >/dev/null || fail "fold: boundary nodes moved"
"$hom" optimize "$work/fold.msh" -o "$work/fold.r0.msh" --threads 1 --certify --certify-rounds 0 --json "$work/fold.r0.json" >/dev/null 2>&1; rc=$?
[[ $rc -eq 3 ]] || fail "fold: --certify-rounds 0 exit $rc, expected 3"
[[ $(json_field "$work/fold.r0.json" optimized certified_invalid) -gt 0 ]] || fail "fold: rounds 0: json: certified_invalid"
"$hom" optimize "$work/fold.msh" -o "$work/x.msh" --certify --certify-depth 99 >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --certify-depth"
[[ ! -e "$work/x.msh" ]] || fail "bad --certify-depth: output written"

# Bad input: a truncated file -> exit 1, FILE:LINE message, no output file.
head -n 20 "$work/tri3.msh" > "$work/truncated.msh"
err=$("$hom" optimize "$work/truncated.msh" -o "$work/x.msh" --json "$work/x.json" 2>&1 >/dev/null); rc=$?
[[ $rc -eq 1 ]] || fail "truncated: exit $rc, expected 1"
grep -q "truncated.msh:[0-9]" <<<"$err" || fail "truncated: message has no FILE:LINE: $err"
for f in x.msh x.msh.tmp x.json x.json.tmp; do [[ ! -e "$work/$f" ]] || fail "truncated: $f left behind"; done
"$hom" optimize "$work/missing.msh" -o "$work/x.msh" >/dev/null 2>&1; [[ $? -eq 1 ]] || fail "missing file: expected exit 1"

# Bad options -> exit 2, nothing written.
"$hom" optimize "$work/tri3.msh" -o "$work/x.msh" --solver nope >/dev/null 2>&1; rc=$?
[[ $rc -eq 2 ]] || fail "unknown --solver: exit $rc, expected 2"
"$hom" optimize "$work/tri3.msh" -o "$work/x.msh" --measure nope >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --measure"
"$hom" optimize "$work/tri3.msh" -o "$work/x.msh" --ideal nope >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --ideal"
"$hom" optimize "$work/tri3.msh" -o "$work/x.msh" --scope nope >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --scope"
"$hom" optimize "$work/tri3.msh" -o "$work/x.msh" --max-iterations 0 >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --max-iterations"
"$hom" optimize "$work/tri3.msh" >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "no -o"
"$hom" optimize >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "no input"
[[ ! -e "$work/x.msh" ]] || fail "bad options: output written"

# A surface mesh (triangles off z = 0) is refused with exit 2.
cat > "$work/surface.msh" <<'MSH'
$MeshFormat
4.1 0 8
$EndMeshFormat
$Nodes
1 4 1 4
2 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
1 1 1
$EndNodes
$Elements
1 2 1 2
2 1 2 2
1 1 2 3
2 2 4 3
$EndElements
MSH
err=$("$hom" optimize "$work/surface.msh" -o "$work/s.msh" 2>&1 >/dev/null); rc=$?
[[ $rc -eq 2 ]] || fail "surface mesh: exit $rc, expected 2"
grep -q "surface mesh" <<<"$err" || fail "surface mesh: unclear message: $err"
[[ ! -e "$work/s.msh" ]] || fail "surface mesh: output written"
echo "cli optimize: ok"
