#!/usr/bin/env python3
"""Gmsh compatibility of hom's MSH reader and writer, with Gmsh's Python API:
meshes Gmsh generates at order p (disk of triangles and quadrilaterals, box
of tetrahedra and hexahedra) are read by hom and written back (`hom convert`
to MSH 4.1 ASCII / binary and 2.2, `io_helper reread` through warp & blend
nodes), then read by Gmsh again: same node and element counts, same node
positions, same physical groups, and the same element Jacobian determinants
at the nodes (so the same validity). Also: `hom convert --order`, `hom info`,
VTU output, and the exit status and message for a broken file.

usage: check_gmsh_roundtrip.py HOM IO_HELPER     (exit 77 = skipped: no gmsh module)
"""
import os
import subprocess
import sys
import tempfile

try:
    import gmsh
    import numpy as np
except ImportError:
    print("gmsh Python module not available: skipping")
    sys.exit(77)

HOM, HELPER = sys.argv[1], sys.argv[2]
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)
    return cond


def generate(path, kind, p, size):
    gmsh.clear()
    gmsh.model.add(kind)
    occ = gmsh.model.occ
    if kind in ("tri", "quad"):
        occ.addDisk(0, 0, 0, 1, 0.8)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [1], 10)
        gmsh.model.setPhysicalName(2, 10, "disk")
        gmsh.model.addPhysicalGroup(1, [1], 11)
        gmsh.model.setPhysicalName(1, 11, "rim")
    else:
        occ.addBox(0, 0, 0, 1, 0.8, 0.6)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], 20)
        gmsh.model.setPhysicalName(3, 20, "box")
        gmsh.model.addPhysicalGroup(2, [1, 2], 21)
        gmsh.model.setPhysicalName(2, 21, "walls")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.RecombineAll", 1 if kind in ("quad", "hex") else 0)
    if kind == "hex":
        gmsh.model.mesh.setTransfiniteAutomatic()
    gmsh.model.mesh.generate(3 if kind in ("tet", "hex") else 2)
    gmsh.model.mesh.setOrder(p)
    gmsh.option.setNumber("Mesh.SaveAll", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.option.setNumber("Mesh.SaveParametric", 1 if kind == "tri" else 0)
    gmsh.write(path)


def describe(path, dim):
    """What Gmsh sees in a file: counts, sorted coordinates, sorted Jacobians."""
    gmsh.clear()
    gmsh.open(path)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = np.array(coords).reshape(-1, 3)
    types, etags, _ = gmsh.model.mesh.getElements(dim)
    ftypes, ftags, _ = gmsh.model.mesh.getElements(dim - 1)
    dets = []
    for t in types:
        local = gmsh.model.mesh.getElementProperties(t)[4]
        _, d, _ = gmsh.model.mesh.getJacobians(t, local)
        dets.append(np.sort(np.array(d)))
    phys = sorted((d_, t_, gmsh.model.getPhysicalName(d_, t_)) for d_, t_ in gmsh.model.getPhysicalGroups())
    return {
        "nodes": len(tags),
        "types": list(types),
        "elements": sum(len(e) for e in etags),
        "facet_types": list(ftypes),
        "facets": sum(len(e) for e in ftags),
        # Sorted by coordinates rounded well above round-off, so that nodes
        # equal up to round-off sort the same way in both files.
        "xyz": xyz[np.lexsort(np.round(xyz, 8).T[::-1])],
        "dets": np.concatenate(dets) if dets else np.array([]),
        "phys": phys,
    }


def same(a, b, name, dim):
    ok = check(a["nodes"] == b["nodes"], f"{name}: {b['nodes']} nodes, Gmsh's mesh has {a['nodes']}")
    ok &= check(a["types"] == b["types"] and a["elements"] == b["elements"],
                f"{name}: {dim}D elements {b['types']} x {b['elements']}, expected {a['types']} x {a['elements']}")
    ok &= check(a["facet_types"] == b["facet_types"] and a["facets"] == b["facets"],
                f"{name}: boundary elements {b['facet_types']} x {b['facets']}, "
                f"expected {a['facet_types']} x {a['facets']}")
    if not ok:
        return
    dx = np.abs(a["xyz"] - b["xyz"]).max()
    check(dx < 1e-12, f"{name}: node positions differ by {dx:.3g}")
    scale = np.abs(a["dets"]).max()
    check(np.abs(a["dets"] - b["dets"]).max() < 1e-9 * scale, f"{name}: Jacobian determinants differ")
    check((a["dets"] <= 0).sum() == (b["dets"] <= 0).sum(), f"{name}: Jacobian validity differs")
    if name.endswith("22.msh") is False:
        check(a["phys"] == b["phys"], f"{name}: physical groups {b['phys']} vs {a['phys']}")


def run(args, expect=0):
    r = subprocess.run(args, capture_output=True, text=True)
    check(r.returncode == expect, f"{' '.join(args)}: exit {r.returncode}, expected {expect}: {r.stderr.strip()}")
    return r


def main():
    gmsh.initialize()
    gmsh.option.setNumber("General.Verbosity", 0)
    cases = [("tri", 2, 0.4), ("tri", 3, 0.5), ("tri", 5, 0.8), ("quad", 2, 0.5), ("quad", 3, 0.6),
             ("tet", 2, 0.5), ("tet", 3, 0.6), ("hex", 2, 0.5)]
    with tempfile.TemporaryDirectory() as tmp:
        for kind, p, size in cases:
            dim = 3 if kind in ("tet", "hex") else 2
            src = os.path.join(tmp, f"{kind}{p}.msh")
            generate(src, kind, p, size)
            ref = describe(src, dim)
            family = {"tri": "Triangle", "quad": "Quadrilateral", "tet": "Tetrahedron", "hex": "Hexahedron"}[kind]
            check(len(ref["types"]) == 1 and gmsh.model.mesh.getElementProperties(ref["types"][0])[0].startswith(family),
                  f"{kind}{p}: Gmsh did not make a pure {family} mesh")
            check(ref["elements"] > 0 and all(d > 0 for d in ref["dets"]), f"{kind}{p}: Gmsh's own mesh is invalid")
            info = run([HOM, "info", src])
            check(f"order {p}" in info.stdout, f"hom info {kind}{p}: {info.stdout}")
            outs = {
                "o41.msh": [HOM, "convert", src],
                "o41b.msh": [HOM, "convert", src, "--binary"],
                "o22.msh": [HOM, "convert", src, "--msh-version", "2.2"],
                "owb.msh": [HELPER, "reread", src],
            }
            for name, cmd in outs.items():
                out = os.path.join(tmp, f"{kind}{p}_{name}")
                args = cmd[:3] + [out] + cmd[3:] if cmd[0] == HOM else cmd + [out]
                if run(args).returncode == 0:
                    same(ref, describe(out, dim), os.path.basename(out), dim)
            run([HOM, "convert", src, os.path.join(tmp, f"{kind}{p}.vtu")])
            check(os.path.exists(os.path.join(tmp, f"{kind}{p}.vtu")), f"{kind}{p}: no VTU written")

            # Elevation keeps the elements and their validity.
            up = os.path.join(tmp, f"{kind}{p}_up.msh")
            q = p + 2
            if run([HOM, "convert", src, up, "--order", str(q)]).returncode == 0:
                e = describe(up, dim)
                check(e["elements"] == ref["elements"], f"{kind}{p} -> order {q}: element count changed")
                name = gmsh.model.mesh.getElementProperties(e["types"][0])
                check(name[2] == q, f"{kind}{p} -> order {q}: Gmsh reads order {name[2]}")
                check((e["dets"] > 0).all(), f"{kind}{p} -> order {q}: invalid elements")

        # Parametric coordinates survive hom (equispaced nodes keep the file's positions).
        src, out = os.path.join(tmp, "tri3.msh"), os.path.join(tmp, "tri3_o41.msh")
        params = []
        for path in (src, out):
            gmsh.clear()
            gmsh.open(path)
            _, c, u = gmsh.model.mesh.getNodes(1, 1, includeBoundary=False, returnParametricCoord=True)
            xyz = np.array(c).reshape(-1, 3)
            order = np.lexsort(xyz.T[::-1])
            params.append(np.array(u)[order])
        check(len(params[0]) > 0 and len(params[0]) == len(params[1]) and np.abs(params[0] - params[1]).max() < 1e-12,
              "parametric coordinates on the disk's rim changed")

        # A broken file: one-line error naming the file and line, exit 1, no output.
        bad, out = os.path.join(tmp, "bad.msh"), os.path.join(tmp, "never.msh")
        with open(os.path.join(tmp, "tet2.msh")) as f:
            text = f.read()
        with open(bad, "w") as f:
            f.write(text[: len(text) // 2])
        r = run([HOM, "convert", bad, out], expect=1)
        check(r.stderr.startswith("hom: " + bad + ":") and r.stderr.count("\n") == 1,
              f"error message for a truncated file: {r.stderr!r}")
        check(not os.path.exists(out) and not os.path.exists(out + ".tmp"), "a failed conversion left a file")
        run([HOM, "convert", bad], expect=2)
        run([HOM, "convert", src, os.path.join(tmp, "x.obj")], expect=2)
        run([HOM, "frobnicate"], expect=2)
    gmsh.finalize()
    print(f"{len(cases)} Gmsh meshes checked, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
