#!/usr/bin/env python3
"""Folds a curved (degree 2) triangle edge on a CAD curve: its edge node
moves along the chord to 0.95 of the way from one end to the other, so the
edge's derivative, and det D phi of the elements on it, turn negative at the
far end; and every node of the edge stays on the curve, so hom holds them.
Writes the mesh without parametric coordinates (hom projects the nodes).

usage: fold_curve_node.py IN.msh OUT.msh   (python3-gmsh)
"""
import sys, gmsh
import numpy as np
src, dst = sys.argv[1], sys.argv[2]
gmsh.initialize(); gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(src)
on_curves = set()
for _, c in gmsh.model.getEntities(1):
    on_curves.update(int(n) for n in gmsh.model.mesh.getNodes(1, c)[0])
_, _, nodes = gmsh.model.mesh.getElements(2)
tri = np.array(nodes[0], dtype=int).reshape(-1, 6)
for t in tri:
    for k in range(3):  # edge k: corners k, k+1, mid-edge node 3 + k
        a, b, m = t[k], t[(k + 1) % 3], t[3 + k]
        if m in on_curves:
            xa = np.array(gmsh.model.mesh.getNode(a)[0]); xb = np.array(gmsh.model.mesh.getNode(b)[0])
            gmsh.model.mesh.setNode(int(m), list(xa + 0.95 * (xb - xa)), [])
            gmsh.option.setNumber("Mesh.SaveParametric", 0)
            gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
            gmsh.write(dst)
            print("moved node", m)
            sys.exit(0)
sys.exit("no mid-edge node on a CAD curve")
