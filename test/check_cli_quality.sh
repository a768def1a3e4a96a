#!/usr/bin/env bash
# `hom quality` end to end: a valid mesh exits 0, a tangled one exits 3 and
# counts its inverted element, the JSON and VTU outputs are written, bad
# input and bad options fail with a message and leave no output behind.
set -uo pipefail
hom=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

# Two tetrahedra sharing the face (1,2,3); apex 5 above it, apex 4 below.
write_mesh() {  # $1 = file, $2 = z of node 5
  cat > "$1" <<MSH
\$MeshFormat
4.1 0 8
\$EndMeshFormat
\$Nodes
1 5 1 5
3 1 0 5
1
2
3
4
5
0 0 0
1 0 0
0 1 0
0.3 0.3 -1
0.3 0.3 $2
\$EndNodes
\$Elements
1 2 1 2
3 1 4 2
1 1 2 3 4
2 2 1 3 5
\$EndElements
MSH
}
write_mesh "$work/valid.msh" 1
write_mesh "$work/tangled.msh" -0.5   # apex 5 pushed through the shared face

"$hom" convert "$work/valid.msh" "$work/valid3.msh" --order 3 || fail "convert"
out=$("$hom" quality "$work/valid3.msh" --json "$work/v.json" --vtu "$work/v.vtu"); rc=$?
[[ $rc -eq 0 ]] || fail "valid mesh: exit $rc"
grep -q "valid at every quadrature point" <<<"$out" || fail "valid mesh: no validity line"
[[ -s "$work/v.json" && -s "$work/v.vtu" ]] || fail "outputs missing"
grep -q '"inverted": 0' "$work/v.json" || fail "json: inverted != 0"
grep -q 'Name="quality"' "$work/v.vtu" || fail "vtu: no quality array"

"$hom" convert "$work/tangled.msh" "$work/tangled2.msh" --order 2 || fail "convert tangled"
out=$("$hom" quality "$work/tangled2.msh" --json "$work/t.json"); rc=$?
[[ $rc -eq 3 ]] || fail "tangled mesh: exit $rc, expected 3"
grep -q '"inverted": 1' "$work/t.json" || fail "tangled json: expected 1 inverted"
grep -q "INVALID" <<<"$out" || fail "tangled: no INVALID line"

# Absolute (equilateral) ideal and Oddy measure run and report the same validity.
"$hom" quality "$work/valid3.msh" --ideal equilateral --measure oddy >/dev/null || fail "equilateral/oddy"

# Surface meshes (chapter 5): two curved quadratic triangles in 3D, off z = 0.
write_surface() {  # $1 = file, $2 = position of node 7 (midpoint of edge 3-1)
  cat > "$1" <<MSH
\$MeshFormat
4.1 0 8
\$EndMeshFormat
\$Nodes
1 9 1 9
2 1 0 9
1
2
3
4
5
6
7
8
9
0 0 0
1 0 0
0 1 0
1 1 0.3
0.5 0 0.05
0.5 0.5 0.1
$2
1 0.5 0.2
0.5 1 0.2
\$EndNodes
\$Elements
1 2 1 2
2 1 9 2
1 1 2 3 5 6 7
2 2 4 3 8 9 6
\$EndElements
MSH
}
write_surface "$work/surface.msh" "0 0.5 0.05"
write_surface "$work/folded_surface.msh" "0.8 0.1 0.05"   # edge node pulled through its element
"$hom" convert "$work/surface.msh" "$work/surface3.msh" --order 3 || fail "convert surface"
out=$("$hom" quality "$work/surface3.msh" --json "$work/s.json" --vtu "$work/s.vtu"); rc=$?
[[ $rc -eq 0 ]] || fail "surface mesh: exit $rc: $out"
grep -q "surface mesh" <<<"$out" || fail "surface mesh: not reported as a surface mesh"
grep -q "valid at every quadrature point" <<<"$out" || fail "surface mesh: no validity line"
grep -q '"inverted": 0' "$work/s.json" || fail "surface json: inverted != 0"
grep -q '"surface": true' "$work/s.json" || fail "surface json: no surface flag"
grep -q '"max_q": 1' "$work/s.json" && fail "surface json: curved elements scored q = 1"
grep -q 'Name="quality"' "$work/s.vtu" || fail "surface vtu: no quality array"
"$hom" quality "$work/surface3.msh" --ideal equilateral --measure oddy >/dev/null || fail "surface equilateral/oddy"
out=$("$hom" quality "$work/folded_surface.msh" --json "$work/f.json"); rc=$?
[[ $rc -eq 3 ]] || fail "folded surface mesh: exit $rc, expected 3"
grep -q '"inverted": 1' "$work/f.json" || fail "folded surface json: expected 1 inverted"

# Bad input: truncated file -> exit 1, message names the file, no output file.
head -n 12 "$work/valid.msh" > "$work/truncated.msh"
err=$("$hom" quality "$work/truncated.msh" --json "$work/x.json" 2>&1 >/dev/null); rc=$?
[[ $rc -eq 1 ]] || fail "truncated: exit $rc"
grep -q "truncated.msh" <<<"$err" || fail "truncated: message does not name the file: $err"
[[ ! -e "$work/x.json" && ! -e "$work/x.json.tmp" ]] || fail "truncated: output left behind"

# Bad options -> exit 2.
"$hom" quality "$work/valid.msh" --measure nope >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --measure"
"$hom" quality "$work/valid.msh" --ideal nope >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --ideal"
"$hom" quality >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "no mesh"
echo "cli quality: ok"
