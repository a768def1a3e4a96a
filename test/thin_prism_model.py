"""Helper of check_cli_curve.sh (hom curve --mesh with ears), through Gmsh's Python API:
  thin_prism_model.py OUT.brep OUT.msh
writes a prism on a thin ellipse (semi-axes 1 and 0.08, height 0.5) and
Gmsh's linear tetrahedral mesh of it (size 0.3, MSH 4.1), as a user would
make it: at each sharp end of the ellipse a cap triangle has two edges on
the ellipse (an ear), which hom's own meshing would have split.
"""
import sys

import gmsh


def main(brep, msh):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("thin_prism")
    ellipse = gmsh.model.occ.addEllipse(0, 0, 0, 1.0, 0.08)
    cap = gmsh.model.occ.addPlaneSurface([gmsh.model.occ.addCurveLoop([ellipse])])
    gmsh.model.occ.extrude([(2, cap)], 0, 0, 0.5)
    gmsh.model.occ.synchronize()
    gmsh.write(brep)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(msh)
    gmsh.finalize()


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
