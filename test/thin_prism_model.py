"""Helper of check_cli_curve.sh (hom curve --mesh with ears), through Gmsh's Python API:
  thin_prism_model.py OUT.brep OUT.msh [planar-quads]
writes a prism on a thin ellipse (semi-axes 1 and 0.08, height 0.5) and
Gmsh's linear tetrahedral mesh of it (size 0.3, MSH 4.1), as a user would
make it: at each sharp end of the ellipse a cap triangle has two edges on
the ellipse (an ear), which hom's own meshing would have split. With
planar-quads: the thin ellipse alone (a planar model in z = 0) and Gmsh's
quadrilateral mesh of it (recombined and subdivided, size 0.3), whose quads at the sharp
ends have two edges on the ellipse.
"""
import sys

import gmsh


def main(brep, msh, planar_quads):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("thin_prism")
    ellipse = gmsh.model.occ.addEllipse(0, 0, 0, 1.0, 0.08)
    cap = gmsh.model.occ.addPlaneSurface([gmsh.model.occ.addCurveLoop([ellipse])])
    if not planar_quads:
        gmsh.model.occ.extrude([(2, cap)], 0, 0, 0.5)
    gmsh.model.occ.synchronize()
    gmsh.write(brep)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
    if planar_quads:  # all quadrilaterals: recombined, then subdivided (as hom's own quad meshes)
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
        gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
    gmsh.model.mesh.generate(2 if planar_quads else 3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(msh)
    gmsh.finalize()


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4) or (len(sys.argv) == 4 and sys.argv[3] != "planar-quads"):
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], len(sys.argv) == 4)
