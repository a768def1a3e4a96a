"""Helper of check_cli_curve.sh (hom curve --solids), through Gmsh's Python API:
  model OUT.brep   two solids that touch without sharing faces, as a body
                   and the far field around it often come from CAD: solid 1
                   the box [0.4, 0.6]^3, solid 2 the box [0, 1]^3 minus a copy
                   of it (its own 6 faces on the interface)
  outside IN.msh   exit 1 unless no node of IN's tetrahedra lies strictly
                   inside [0.4, 0.6]^3 and some lies on its boundary: the
                   mesh is of solid 2 alone, with its cavity
  inside IN.msh    exit 1 unless every node of IN's tetrahedra lies in
                   [0.4, 0.6]^3: the mesh is of solid 1 alone
"""
import sys

import gmsh

LO, HI, EPS = 0.4, 0.6, 1e-9


def write_model(path):
    # Each solid is made in a model of its own and written to a file, so the
    # two share no topology when both files are read into one model.
    parts = []
    for name in ("body", "far_field"):
        gmsh.model.add(name)
        body = gmsh.model.occ.addBox(LO, LO, LO, HI - LO, HI - LO, HI - LO)
        if name == "far_field":
            outer = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
            gmsh.model.occ.cut([(3, outer)], [(3, body)])
        gmsh.model.occ.synchronize()
        parts.append(path + "." + name + ".brep")
        gmsh.write(parts[-1])
    gmsh.model.add("box_in_box")
    for p in parts:
        gmsh.model.occ.importShapes(p)
    gmsh.model.occ.synchronize()
    if len(gmsh.model.getEntities(3)) != 2 or len(gmsh.model.getEntities(2)) != 18:
        raise SystemExit("box_in_box: expected 2 solids and 18 faces")
    gmsh.write(path)


def tetrahedron_nodes(path):
    gmsh.open(path)
    types, _, nodes = gmsh.model.mesh.getElements(3)
    used = {int(n) for block in nodes for n in block}
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = {int(t): coords[3 * i:3 * i + 3] for i, t in enumerate(tags)}
    if not used:
        raise SystemExit(path + ": no volume elements")
    return [xyz[n] for n in used]


def main(argv):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        command = argv[1]
        if command == "model":
            write_model(argv[2])
        elif command == "outside":
            points = tetrahedron_nodes(argv[2])
            inside = [x for x in points if all(LO + EPS < c < HI - EPS for c in x)]
            on_cavity = [x for x in points if all(LO - EPS <= c <= HI + EPS for c in x)]
            if inside or not on_cavity:
                raise SystemExit(f"{argv[2]}: {len(inside)} nodes inside the body, {len(on_cavity)} on its boundary")
        elif command == "inside":
            points = tetrahedron_nodes(argv[2])
            out = [x for x in points if not all(LO - EPS <= c <= HI + EPS for c in x)]
            if out:
                raise SystemExit(f"{argv[2]}: {len(out)} nodes outside the body")
        else:
            raise SystemExit("usage: box_in_box_model.py model OUT.brep | outside IN.msh | inside IN.msh")
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main(sys.argv)
