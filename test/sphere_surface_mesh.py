"""Helper of check_cli_optimize_cad.sh, through Gmsh's Python API:
  model OUT.brep            the unit sphere (OpenCASCADE kernel)
  linear OUT.msh            a linear triangle mesh of it
  perturb IN.msh OUT.msh A  every node inside a surface rotated about the z axis
                            by A sin(node tag) radians (it stays on the sphere),
                            written without parametric coordinates
  check IN.msh TOL GAP      exit 1 unless every element vertex is at distance
                            1 +- TOL from the origin and every node 1 +- GAP (the
                            file's high-order nodes are the curved map at Gmsh's
                            equispaced positions: on the sphere up to the
                            interpolation error)
"""
import math
import sys

import gmsh


def main(argv):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        command = argv[1]
        if command == "model":
            gmsh.model.occ.addSphere(0, 0, 0, 1.0)
            gmsh.model.occ.synchronize()
            gmsh.write(argv[2])
        elif command == "linear":
            gmsh.model.occ.addSphere(0, 0, 0, 1.0)
            gmsh.model.occ.synchronize()
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
            gmsh.model.mesh.generate(2)
            gmsh.write(argv[2])
        elif command == "perturb":
            gmsh.open(argv[2])
            amplitude = float(argv[4])
            for dim, tag in gmsh.model.getEntities(2):
                tags, xyz, _ = gmsh.model.mesh.getNodes(dim, tag, includeBoundary=False)
                for k, t in enumerate(tags):
                    x, y, z = xyz[3 * k:3 * k + 3]
                    a = amplitude * math.sin(float(t))
                    c, s = math.cos(a), math.sin(a)
                    gmsh.model.mesh.setNode(t, [c * x - s * y, s * x + c * y, z], [])
            gmsh.option.setNumber("Mesh.SaveParametric", 0)
            gmsh.write(argv[3])
        elif command == "check":
            gmsh.open(argv[2])
            tags, xyz, _ = gmsh.model.mesh.getNodes()
            distance = {int(t): abs(math.sqrt(xyz[3 * k] ** 2 + xyz[3 * k + 1] ** 2 + xyz[3 * k + 2] ** 2) - 1.0)
                        for k, t in enumerate(tags)}
            corners = set()
            for dim, tag in gmsh.model.getEntities(2):
                for etype, _, nodes in zip(*gmsh.model.mesh.getElements(dim, tag)):
                    per = gmsh.model.mesh.getElementProperties(etype)[3]  # nodes per element
                    nodes = list(nodes)
                    for e in range(0, len(nodes), per):
                        corners.update(int(n) for n in nodes[e:e + 3])
            worst_corner = max(distance[n] for n in corners)
            worst = max(distance.values())
            print(f"largest distance from the unit sphere: {worst_corner:.3g} (vertices), {worst:.3g} (all nodes)")
            return 0 if corners and worst_corner <= float(argv[3]) and worst <= float(argv[4]) else 1
        else:
            raise SystemExit(f"unknown command {command}")
    finally:
        gmsh.finalize()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
