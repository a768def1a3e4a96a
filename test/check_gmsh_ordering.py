#!/usr/bin/env python3
"""Compares hom's Gmsh node orders (io/gmsh_elements.hpp) with Gmsh's own
reference elements: gmsh.model.mesh.getElementProperties(type) gives the
local node coordinates of every element type, which must equal hom's lattice
points (simplices: x = l / p; lines, quadrilaterals, hexahedra: x = -1 + 2 l / p).

usage: check_gmsh_ordering.py IO_HELPER     (exit 77 = skipped: no gmsh module)
"""
import subprocess
import sys

try:
    import gmsh
except ImportError:
    print("gmsh Python module not available: skipping")
    sys.exit(77)

GMSH_NAME = {"line": "Line", "triangle": "Triangle", "quadrilateral": "Quadrangle",
             "tetrahedron": "Tetrahedron", "hexahedron": "Hexahedron"}


def main():
    out = subprocess.run([sys.argv[1], "orderings"], check=True, capture_output=True, text=True).stdout
    gmsh.initialize()
    gmsh.option.setNumber("General.Verbosity", 0)
    checked, failures = 0, []
    seen = set()
    for line in out.splitlines():
        words = line.split()
        if words[0] != "gmsh":
            continue
        shape, p = words[1], int(words[2])
        seen.add((shape, p))
        if shape == "line":
            hom = [(int(w),) for w in words[3:]]
        else:
            hom = [tuple(int(c) for c in w.split(",")) for w in words[3:]]
        etype = gmsh.model.mesh.getElementType(GMSH_NAME[shape], p)
        name, dim, order, nn, coords, nv = gmsh.model.mesh.getElementProperties(etype)
        simplex = shape in ("triangle", "tetrahedron")
        ref = []
        for i in range(nn):
            x = coords[dim * i: dim * i + dim]
            ref.append(tuple(round(v * p) if simplex else round((v + 1) * p / 2) for v in x))
            # The lattice must reproduce the coordinates exactly (equispaced nodes).
            back = [l / p if simplex else -1 + 2 * l / p for l in ref[-1]]
            if max(abs(a - b) for a, b in zip(back, x)) > 1e-12:
                failures.append(f"{shape} p={p}: node {i} is not equispaced: {x}")
        checked += 1
        if ref != hom:
            first = next(i for i, (a, b) in enumerate(zip(ref, hom)) if a != b) if len(ref) == len(hom) else -1
            failures.append(f"{shape} p={p} (type {etype}): hom's order differs from Gmsh's at node {first}: "
                            f"gmsh {ref[first] if first >= 0 else len(ref)} vs hom {hom[first] if first >= 0 else len(hom)}")
    gmsh.finalize()
    expected = {(s, p) for s in GMSH_NAME for p in range(1, 11) if not (s == "hexahedron" and p == 10)}
    if seen != expected:
        failures.append(f"missing orders: {sorted(expected - seen)}")
    for f in failures:
        print("FAIL:", f)
    print(f"{checked} Gmsh element types compared, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
