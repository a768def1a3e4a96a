#!/usr/bin/env python3
"""Checks hom's VTU output with VTK itself (python3-vtk9):
  1. hom's VTK Lagrange node orders equal vtkLagrange*::GetParametricCoords
     for orders 1..10;
  2. files written by hom (base64 appended and ASCII) read back with
     vtkXMLUnstructuredGridReader: cell types, counts, arrays;
  3. VTK's own interpolation (vtkCell.EvaluateLocation, and the point field
     through the cell's weights) at random parametric points equals hom's map
     and field there: so the node order, the point positions and the data
     agree with hom's element map, not only at the nodes.

usage: check_vtu.py IO_HELPER     (exit 77 = skipped: no vtk module)
"""
import json
import os
import subprocess
import sys
import tempfile

try:
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError:
    print("vtk Python module not available: skipping")
    sys.exit(77)

CELL = {"triangle": vtk.vtkLagrangeTriangle, "quadrilateral": vtk.vtkLagrangeQuadrilateral,
        "tetrahedron": vtk.vtkLagrangeTetra, "hexahedron": vtk.vtkLagrangeHexahedron}
NUM = {"triangle": lambda p: (p + 1) * (p + 2) // 2, "quadrilateral": lambda p: (p + 1) ** 2,
       "tetrahedron": lambda p: (p + 1) * (p + 2) * (p + 3) // 6, "hexahedron": lambda p: (p + 1) ** 3}
DIM = {"triangle": 2, "quadrilateral": 2, "tetrahedron": 3, "hexahedron": 3}


def vtk_lattice(shape, p):
    n = NUM[shape](p)
    c = CELL[shape]()
    c.GetPointIds().SetNumberOfIds(n)
    c.GetPoints().SetNumberOfPoints(n)
    for i in range(n):
        c.GetPointIds().SetId(i, i)
        c.GetPoints().SetPoint(i, 0, 0, 0)
    if shape in ("quadrilateral", "hexahedron"):
        c.SetOrder(*([p] * DIM[shape]))
    else:
        c.Initialize()
    pc = c.GetParametricCoords()
    return [tuple(round(pc[3 * i + k] * p) for k in range(DIM[shape])) for i in range(n)]


def main():
    helper = sys.argv[1]
    failures = []
    out = subprocess.run([helper, "orderings"], check=True, capture_output=True, text=True).stdout
    n_orders = 0
    for line in out.splitlines():
        words = line.split()
        if words[0] != "vtk":
            continue
        shape, p = words[1], int(words[2])
        hom = [tuple(int(c) for c in w.split(",")) for w in words[3:]]
        n_orders += 1
        if vtk_lattice(shape, p) != hom:
            failures.append(f"VTK node order of {shape} p={p} differs from hom's")
    if n_orders != 40:
        failures.append(f"expected 40 VTK orders, got {n_orders}")

    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([helper, "vtu", tmp], check=True)
        with open(os.path.join(tmp, "cases.json")) as f:
            cases = json.load(f)
        worst = 0.0
        for case in cases:
            for path in (case["file"], case["file"].replace(".vtu", "_ascii.vtu")):
                r = vtk.vtkXMLUnstructuredGridReader()
                r.SetFileName(path)
                r.Update()
                g = r.GetOutput()
                tag = f"{case['name']} p={case['p']} {os.path.basename(path)}"
                if g.GetNumberOfCells() != case["cells"] or g.GetNumberOfPoints() != case["points"]:
                    failures.append(f"{tag}: {g.GetNumberOfCells()} cells, {g.GetNumberOfPoints()} points")
                    continue
                types = {g.GetCellType(i) for i in range(g.GetNumberOfCells())}
                if types != {case["cell_type"]}:
                    failures.append(f"{tag}: cell types {types}")
                field = g.GetPointData().GetArray("field")
                if field is None or g.GetCellData().GetArray("cell_id") is None or \
                        g.GetCellData().GetArray("entity") is None:
                    failures.append(f"{tag}: missing data arrays")
                    continue
                cell_id = vtk_to_numpy(g.GetCellData().GetArray("cell_id"))
                if list(cell_id) != list(range(case["cells"])):
                    failures.append(f"{tag}: cell data out of order")
                for s in case["samples"]:
                    cell = g.GetCell(s["cell"])
                    x = [0.0, 0.0, 0.0]
                    w = [0.0] * cell.GetNumberOfPoints()
                    cell.EvaluateLocation(vtk.mutable(0), s["pcoords"], x, w)
                    err = max(abs(a - b) for a, b in zip(x, s["x"]))
                    fv = sum(wi * field.GetValue(cell.GetPointId(i)) for i, wi in enumerate(w))
                    ferr = abs(fv - s["field"])
                    worst = max(worst, err, ferr)
                    if err > 1e-9 or ferr > 1e-9:
                        failures.append(f"{tag}: cell {s['cell']} at {s['pcoords']}: VTK gives {x} "
                                        f"(field {fv}), hom {s['x']} (field {s['field']})")
                        break
        print(f"{len(cases)} meshes read back by VTK {vtk.vtkVersion.GetVTKVersion()}, "
              f"largest difference from hom's map {worst:.2e}")
    for f in failures[:20]:
        print("FAIL:", f)
    print(f"{n_orders} node orders compared, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
