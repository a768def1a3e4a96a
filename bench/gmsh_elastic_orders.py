#!/usr/bin/python3
"""Where Gmsh's elastic analogy (Mesh.HighOrderOptimize 2 and 3) stops working, on a mesh of Gmsh's own.

bench_untangle's peer runs at p = 10 see Gmsh 4.8.4 crash in "Generating elastic system..." (modes 2, 3).
This script takes hom out of the question: Gmsh meshes the cube with a spherical cavity itself, raises the
order with gmsh.model.mesh.setOrder and runs gmsh.model.mesh.optimize("HighOrderElastic"), each order in a
child process under a time limit, and prints how each ended.

Usage (Debian's python3-gmsh): /usr/bin/python3 bench/gmsh_elastic_orders.py [--size H] [--timeout S] ORDER...
"""
import argparse
import signal
import subprocess
import sys
import time


def child(order, size):
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.addSphere(0.5, 0.5, 0.5, 0.25, 2)
    gmsh.model.occ.cut([(3, 1)], [(3, 2)])
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(order)
    tetrahedra = len(gmsh.model.mesh.getElements(3)[1][0])
    start = time.time()
    gmsh.model.mesh.optimize("HighOrderElastic", True)
    print("%d tetrahedra, elastic analogy %.1f s" % (tetrahedra, time.time() - start), flush=True)
    gmsh.finalize()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("orders", type=int, nargs="+", help="the degrees to try")
    ap.add_argument("--size", type=float, default=0.5, help="Mesh.MeshSizeMax (default 0.5)")
    ap.add_argument("--timeout", type=float, default=600, help="seconds per order (default 600)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.orders[0], a.size)
        return 0
    for order in a.orders:
        start = time.time()
        try:
            r = subprocess.run([sys.executable, __file__, "--child", "--size", str(a.size), str(order)],
                               capture_output=True, text=True, timeout=a.timeout)
        except subprocess.TimeoutExpired:
            print("order %d: no result within %g s" % (order, a.timeout))
            continue
        if r.returncode == 0:
            outcome = "ok, " + r.stdout.strip()
        elif r.returncode < 0:
            outcome = "crashed (%s)" % signal.Signals(-r.returncode).name
        else:
            outcome = "exit %d" % r.returncode
        lines = [l for l in r.stderr.splitlines() if l.strip()]
        print("order %d: %s after %.1f s%s" % (order, outcome, time.time() - start,
                                                ("; " + lines[-1]) if lines and r.returncode else ""), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
