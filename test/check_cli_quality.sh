#!/usr/bin/env bash
# `hom quality` end to end: a valid mesh exits 0, a tangled one exits 3 and
# counts its inverted element, the JSON and VTU outputs are written, bad
# input and bad options fail with a message and leave no output behind.
source "$(dirname "$0")/cli_common.sh"
hom=$1

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

# --certify: a cubic quadrilateral folded between its quadrature points. The
# map is x = xi^3/3 - e xi, y = eta (e = 0.0289), so det = xi^2 - e < 0 only for
# |xi| < 0.17, between the 4 Gauss points per axis at |xi| = 0.34, 0.86 and the
# nodes at |xi| = 1/3: the quadrature check calls it valid, certification must not.
write_fold() {  # $1 = file; nodes in Gmsh's 16-node quadrilateral order
  awk -v e=0.0289 'function f(s) { return s * s * s / 3 - e * s }
    BEGIN {
      split("-1 1 1 -1 -1/3 1/3 1 1 1/3 -1/3 -1 -1 -1/3 1/3 1/3 -1/3", X, " ")
      split("-1 -1 1 1 -1 -1 -1/3 1/3 1 1 1/3 -1/3 -1/3 -1/3 1/3 1/3", Y, " ")
      print "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 16 1 16\n2 1 0 16"
      for (i = 1; i <= 16; ++i) print i
      for (i = 1; i <= 16; ++i) {
        split(X[i], a, "/"); x = a[1] / (a[2] ? a[2] : 1)
        split(Y[i], b, "/"); y = b[1] / (b[2] ? b[2] : 1)
        printf "%.17g %.17g 0\n", f(x), y
      }
      print "$EndNodes\n$Elements\n1 1 1 1\n2 1 36 1"
      printf "1"; for (i = 1; i <= 16; ++i) printf " %d", i; print ""
      print "$EndElements"
    }' > "$1"
}
write_fold "$work/fold.msh"
out=$("$hom" quality "$work/fold.msh"); rc=$?
[[ $rc -eq 0 ]] || fail "fold: the quadrature check should call it valid (exit $rc): $out"
out=$("$hom" quality "$work/fold.msh" --certify --json "$work/fold.json" --vtu "$work/fold.vtu"); rc=$?
[[ $rc -eq 3 ]] || fail "fold --certify: exit $rc, expected 3: $out"
grep -q "0 certified valid, 1 certified invalid, 0 undecided" <<<"$out" || fail "fold --certify: counts: $out"
grep -q '"certified_invalid": 1' "$work/fold.json" || fail "fold json: certified_invalid != 1"
grep -q '"certified_valid": 0' "$work/fold.json" || fail "fold json: certified_valid != 0"
grep -Eq '"certified_min_scaled_jacobian": -' "$work/fold.json" || fail "fold json: certified bound not negative"
grep -q 'Name="certificate"' "$work/fold.vtu" || fail "fold vtu: no certificate array"
# The fold is the strip |xi| < 0.17, i.e. |x| <= |f(0.17)| = 0.0033: the reported point lies in it.
pt=$(grep -o "det = [^ ]* <= 0 at ([^,]*" <<<"$out" | sed 's/.*(//')
awk -v x="$pt" 'BEGIN { exit !(x != "" && x * x < 0.0034 * 0.0034) }' || fail "fold: invalid point '$pt' outside the fold"
# Valid curved and straight meshes are certified valid; the tangled one invalid.
out=$("$hom" quality "$work/valid3.msh" --certify --json "$work/vc.json"); rc=$?
[[ $rc -eq 0 ]] || fail "valid --certify: exit $rc: $out"
grep -q '"certified_valid": 2' "$work/vc.json" || fail "valid json: certified_valid != 2"
grep -q '"undecided": 0' "$work/vc.json" || fail "valid json: undecided != 0"
out=$("$hom" quality "$work/tangled2.msh" --certify --json "$work/tc.json"); rc=$?
[[ $rc -eq 3 ]] || fail "tangled --certify: exit $rc"
grep -q '"certified_invalid": 1' "$work/tc.json" || fail "tangled json: certified_invalid != 1"
"$hom" quality "$work/valid.msh" --certify --certify-depth -1 >/dev/null 2>&1; [[ $? -eq 2 ]] || fail "bad --certify-depth"

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
