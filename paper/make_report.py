#!/usr/bin/python3
"""Regenerates the reproduction report (paper/report.md) from the harnesses in bench/.

    paper/make [--quick | --full] [--build DIR] [--out DIR] [--work DIR] [--only NAME,...] [--no-run]

Every harness runs with --json into a work directory (default BUILD/paper-work-MODE); its wall
time, exit status and claim checks are recorded; the report puts the thesis's numbers and hom's
side by side for every thesis table, copies the PNG figures the harnesses draw next to it
(OUT/figures/...), draws quality histograms from the VTU files, and ends with the peer
comparison (Gmsh) and the performance section. Nothing in the report is typed by hand: the
thesis's numbers come from the harnesses' JSON ("thesis" entries) or, for tables no harness
reproduces yet, from THESIS_ONLY below (copied from the thesis's tables, cited by number).

Run with Debian's /usr/bin/python3 (matplotlib, numpy).
"""

import argparse
import base64
import datetime
import glob
import json
import math
import os
import platform
import re
import resource
import shlex
import shutil
import struct
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ---------------------------------------------------------------------------------------------
# The harness runs of each mode. name: key of the run (and of its work sub-directory);
# binary: under BUILD/bench; args: options besides --out/--json (or the Google Benchmark
# output options); kind: "json" (DESIGN.md report) or "gbench" (Google Benchmark JSON);
# timeout in seconds; conditions: what differs from the thesis in this mode (printed in the
# report next to the tables the run feeds).
# ---------------------------------------------------------------------------------------------

QUICK = [
    dict(name="measures", binary="bench_measures", args=["--plot"]),
    dict(name="sphere", binary="bench_sphere", args=["--quick", "--case", "sphere"],
         conditions="hollow sphere at p = 2, 4 only (--quick; the thesis also has p = 6)"),
    dict(name="ring", binary="bench_ring", args=["--quick"],
         conditions="table D.1 at p = 3, 4 only (--quick; the thesis also has p = 5, 10); one run per timing"),
    dict(name="surface", binary="bench_surface", args=["--case", "consistency", "--case", "table52"],
         conditions="the robustness case (table 5.3 analogue, about a minute) only in the full mode"),
    dict(name="surface_appendixF", binary="bench_surface", args=["--case", "appendixF", "--grid", "61"],
         conditions="appendix F level sets on a 61 x 61 grid (the full mode: 101 x 101)"),
    dict(name="untangle", binary="bench_untangle",
         args=["--quick", "--p", "2", "--peer", "gmsh", "--peer-mode", "3,4", "--peer-timeout", "60"],
         conditions="coarser linear mesh (--quick: 823 instead of 1441 tetrahedra) at p = 2; p = 5 on the full "
                    "mesh is the next run, p = 10 (about 2.5 minutes) is in the full mode only. Gmsh peer in its fast "
                    "modes (Mesh.HighOrderOptimize = 3, elastic, and 4, fast curving); its optimization mode 1 needs "
                    "more than 2 minutes even here"),
    dict(name="untangle_p5", binary="bench_untangle", args=["--p", "5", "--pcont", "--no-vtu"],
         conditions="the full linear mesh (1436 tetrahedra against the thesis's 1441) at p = 5, matrix-free Newton with "
                    "p-continuation, no peer"),
    dict(name="untangle_newton", binary="bench_untangle", args=["--quick", "--p", "2", "--solver", "newton", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="untangle_gs", binary="bench_untangle", args=["--quick", "--p", "2", "--solver", "gauss-seidel", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="untangle_pcont", binary="bench_untangle", args=["--quick", "--p", "2", "--pcont", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="untangle_1thread", binary="bench_untangle", args=["--quick", "--p", "2", "--threads", "1", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="smooth", binary="bench_smooth", args=["--case", "4.4", "--p44", "2", "--max-iterations-44", "5"],
         conditions="tables 4.4, 4.5 at p = 2 (thesis: 5) with at most 5 iterations per ideal; table 4.2 "
                    "(about a minute and a half on two loaded cores) only in the full mode"),
    dict(name="certify", binary="bench_certify", args=["--quick", "--p", "2", "--max-iterations", "10"],
         conditions="coarser cube (--quick), p = 2 only"),
    dict(name="curve", binary="bench_curve", args=["--quick", "--case", "gear", "--case", "plate_quad", "--certify"],
         conditions="the gear (table 5.5 beside it) at p = 3 and the quadrilateral plate (table D.3 beside it) at "
                    "p = 3 only (--quick); the other CAD cases only in the full mode; every final mesh certified "
                    "(Bernstein bounds) and its folds between the quadrature points repaired (--certify)"),
    dict(name="curve_plate", binary="bench_curve", args=["--case", "plate_tri", "--p", "7", "--certify"],
         conditions="the planar plate at the thesis's p = 7, certified and repaired (--certify)"),
    dict(name="curve_cube", binary="bench_curve", args=["--quick", "--case", "cube_cavity", "--p", "4", "--certify"],
         conditions="the cube with a cavity at the thesis's p = 4, certified and repaired (--certify)"),
    dict(name="boundary_layer", binary="bench_boundary_layer", args=["--case", "sphere", "--quick"],
         conditions="the sphere at p = 2 (thesis: 4) with 2 layers (thesis: 3) from a first height of 0.01 growing by "
                    "2, in a box of side 2 meshed coarser than the thesis's 18936 tetrahedra (--quick)"),
    dict(name="boundary_layer_wing", binary="bench_boundary_layer", args=["--case", "wing", "--quick"],
         conditions="a NACA 0012 wing section (the SD7003 file is used only in the full mode) at p = 2 on a coarse "
                    "inviscid mesh (--quick), 7 layers from 2e-4 chords growing by 2, stage (e) certified and repaired "
                    "(Bernstein bounds, on by default in the harness); tables 3.4 and 6.5 at p = 2 "
                    "(thesis: 4), table 4.3 at the thesis's p = 2"),
    dict(name="kernel", binary="bench_kernel", kind="gbench",
         args=["--benchmark_filter=^(fma_peak|(value_gradient|hessian_vector_product)<Tet>/p:(2|5))/threads:1/",
               "--benchmark_min_time=0.05"]),
    dict(name="reference", binary="bench_reference", kind="gbench",
         args=["--benchmark_filter=/(2|5)$", "--benchmark_min_time=0.02"]),
]

FULL = [
    dict(name="measures", binary="bench_measures", args=["--plot"]),
    dict(name="sphere", binary="bench_sphere", args=["--case", "sphere"]),
    dict(name="sphere_hex", binary="bench_sphere", args=["--case", "hex"]),
    dict(name="ring", binary="bench_ring", args=[]),
    dict(name="surface", binary="bench_surface", args=["--case", "consistency", "--case", "table52", "--case",
                                                       "robustness"]),
    dict(name="surface_appendixF", binary="bench_surface", args=["--case", "appendixF"]),
    dict(name="untangle", binary="bench_untangle", args=["--p", "2,5,10", "--peer", "gmsh", "--peer-timeout", "1800"],
         timeout=6 * 3600),
    dict(name="untangle_unperturbed_peer", binary="bench_untangle",
         args=["--p", "2,5", "--perturb", "0", "--peer", "gmsh", "--peer-mode", "1,2,3,4", "--peer-timeout", "1800",
               "--no-vtu", "--no-cut"],
         role="peer", conditions="the curved mesh without the random perturbation, through hom once and Gmsh's "
                                 "modes 1 to 4"),
    dict(name="untangle_peer_mode2", binary="bench_untangle",
         args=["--p", "2,5", "--peer", "gmsh", "--peer-mode", "2", "--peer-timeout", "1800", "--no-vtu", "--no-cut"], role="peer"),
    dict(name="untangle_peer_mode3", binary="bench_untangle",
         args=["--p", "2,5", "--peer", "gmsh", "--peer-mode", "3", "--peer-timeout", "1800", "--no-vtu", "--no-cut"], role="peer"),
    dict(name="untangle_peer_mode4", binary="bench_untangle",
         args=["--p", "2,5", "--peer", "gmsh", "--peer-mode", "4", "--peer-timeout", "1800", "--no-vtu", "--no-cut"], role="peer"),
    dict(name="untangle_p10_peer_modes", binary="bench_untangle",
         args=["--p", "10", "--peer", "gmsh", "--peer-mode", "2,3,4", "--peer-timeout", "1800", "--no-vtu",
               "--no-cut"], timeout=4 * 3600, role="peer",
         conditions="the perturbed cube at p = 10 through hom once and Gmsh's modes 2, 3 and 4"),
    dict(name="untangle_p10_unperturbed_peer_modes", binary="bench_untangle",
         args=["--p", "10", "--perturb", "0", "--peer", "gmsh", "--peer-mode", "1,2,3,4", "--peer-timeout", "1800",
               "--no-vtu", "--no-cut"], timeout=4 * 3600, role="peer",
         conditions="the unperturbed cube at p = 10 through hom once and Gmsh's modes 1 to 4"),
    dict(name="untangle_newton", binary="bench_untangle", args=["--p", "5", "--solver", "newton", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="untangle_gs", binary="bench_untangle", args=["--p", "5", "--solver", "gauss-seidel", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="untangle_pcont", binary="bench_untangle", args=["--p", "5", "--pcont", "--no-vtu", "--no-cut"], role="solver"),
    dict(name="untangle_1thread", binary="bench_untangle", args=["--p", "5", "--threads", "1", "--no-vtu", "--no-cut"],
         role="solver"),
    dict(name="smooth", binary="bench_smooth", args=[], timeout=4 * 3600),
    dict(name="certify", binary="bench_certify", args=["--p", "2,5,10"], timeout=4 * 3600),
    dict(name="curve", binary="bench_curve", args=["--case", "cube_cavity", "--case", "nurbs_sphere", "--case",
                                                   "plate_tri", "--case", "plate_quad", "--case", "gear", "--certify"],
         timeout=4 * 3600),
    dict(name="curve_p10", binary="bench_curve", args=["--case", "gear", "--p", "10", "--certify"],
         conditions="the gear at p = 10 (tables 5.5, 5.6)"),
    dict(name="curve_models", binary="bench_curve", args=["--case", "propeller_surface", "--case", "propeller",
                                                          "--case", "wing_domain", "--case", "cone", "--certify",
                                                          "--refine-invalid", "3"], timeout=4 * 3600,
         conditions="the propeller-like part, the wing's exterior domain and a cone's sharp apex "
                    "(curve_models.hpp); an invalid or "
                    "uncertified result meshed again finer around its failing elements, up to 3 times "
                    "(--refine-invalid 3; the statistics are the last mesh's)"),
    dict(name="curve_cad", binary="bench_curve", args=["--case", "wing_fuselage", "--case", "ring_in_sphere", "--case",
                                                       "spur_gear", "--case", "gear_face_tri", "--case",
                                                       "gear_face_quad", "--case", "sphere_rhino", "--case",
                                                       "t106_cascade", "--certify", "--refine-invalid", "3"],
         timeout=4 * 3600,
         conditions="an invalid or uncertified result meshed again finer around its failing elements, up to 3 "
                    "times (--refine-invalid 3; the statistics are the last mesh's)"),
    dict(name="curve_wing_merged", binary="bench_curve",
         args=["--case", "wing_fuselage_merged", "--certify", "--refine-invalid", "3"], timeout=3600,
         conditions="wing_fuselage.step without the wing roots' two 0.036-long CAD edges (36 CAD edges instead of "
                    "38, hom curve --merge-small-edges 0.05) at p = 2 to 5; an invalid or uncertified result meshed "
                    "again finer around its failing elements, up to 3 times"),
    dict(name="curve_peer", binary="bench_curve",
         args=["--case", "ring_in_sphere", "--case", "spur_gear", "--p", "2,3,4,5", "--certify", "--threads", "1",
               "--optimizer-peer", "gmsh", "--peer-timeout", "1800"], timeout=4 * 3600, role="peer",
         conditions="two real CAD models (../shared/data/cad) at p = 2 to 5, hom and Gmsh on 1 thread each: hom's "
                    "volume stage (stopping 5 iterations "
                    "after the mesh is valid, bench_curve's default, then certified and repaired) and Gmsh's "
                    "optimizer from the same initial curved mesh"),
    dict(name="curve_peer_modes", binary="bench_curve",
         args=["--case", "ring_in_sphere", "--case", "spur_gear", "--p", "2,3", "--certify", "--threads", "1",
               "--optimizer-peer", "gmsh", "--peer-mode", "2,3,4", "--peer-timeout", "1800"], timeout=4 * 3600,
         role="peer", conditions="curve_peer's cases at p = 2 and 3 against Gmsh's modes 2, 3 and 4"),
    dict(name="boundary_layer_wing", binary="bench_boundary_layer", args=["--case", "wing", "--p", "2"],
         timeout=4 * 3600,
         conditions="the wing section of the full boundary_layer run at the thesis's p = 2 of table 4.3"),
    dict(name="boundary_layer", binary="bench_boundary_layer", args=["--case", "sphere", "--case", "wing"],
         timeout=4 * 3600,
         conditions="the sphere at p = 4 with 3 layers on an inviscid mesh coarser than the thesis's; the wing: the "
                    "SD7003 profile (NACA 0012 when ../shared/data/cad is absent) extruded as a section in a box, 7 "
                    "layers from 2e-4 chords growing by 2, p = 4"),
    dict(name="kernel", binary="bench_kernel", kind="gbench", args=[]),
    dict(name="reference", binary="bench_reference", kind="gbench", args=[]),
]

# ---------------------------------------------------------------------------------------------
# The thesis's tables, in the report's order: id, title, where hom's numbers come from (or why
# not), and the thesis's rows for tables whose harness JSON does not carry them.
# Rows: (label, Min, Max, Mean, Std.Dev., #inv); None where the thesis prints no value.
# ---------------------------------------------------------------------------------------------

TABLES = [
    ("3.2", "Hollow sphere, relative shape quality (straight-sided ideal)", "bench_sphere"),
    ("3.3", "Hollow sphere, absolute shape quality (equilateral ideal)", "bench_sphere"),
    ("3.4", "Boundary layer mesh (SD7003, p = 4), absolute and relative quality", None),
    ("4.1", "Untangling the curved cube with a spherical cavity, p = 2, 5, 10", "bench_untangle"),
    ("4.2", "Moving the cavity 1.5 units: non-linear vs linear formulation (p = 5)", "bench_smooth --case 4.2"),
    ("4.3", "SD7003 airfoil boundary layer, p = 2", None),
    ("4.4", "Graded cube, equilateral vs straight-sided ideal (p = 5): shape quality", "bench_smooth --case 4.4"),
    ("4.5", "Graded cube: scaled Jacobian, volume error, elements with mu = 1", "bench_smooth --case 4.4"),
    ("5.1", "Planar vs surface optimizer (consistency, section 5.5.1.1)", "bench_surface --case consistency"),
    ("5.2", "Parameterization independence on Sigma_1, Sigma_2 (figure 5.8)", "bench_surface --case table52"),
    ("5.3", "Robustness: randomized surface mesh untangled (section 5.5.1.3)", "bench_surface --case robustness"),
    ("5.4", "Falcon aircraft surface mesh, p = 5", None),
    ("5.5", "Gear box component, p = 3, 5, 8, 10 (shape quality)", "bench_curve"),
    ("5.6", "Scaled Jacobian of the optimized surface meshes", "bench_curve (the gear at p = 10)"),
    ("6.1", "Barcelona harbor, planar triangles p = 7", "bench_curve (plate_tri at p = 7)"),
    ("6.2", "Falcon volume mesh, tetrahedra p = 4", "bench_curve (cube_cavity at p = 4)"),
    ("6.3", "Falcon mesh used in the simulation, p = 4", None),
    ("6.4", "Boundary layer around a sphere, p = 4", None),
    ("6.5", "Boundary layer around an SD7003 airfoil, p = 4", None),
    ("C", "p-continuation (degree-4 ring, figure C.2)", "bench_ring"),
    ("D.1", "Circular ring of 24 triangles, p = 3, 4, 5, 10", "bench_ring"),
    ("D.2", "Motorbike brake, triangles p = 2", None),
    ("D.3", "Quadrilateral meshes, p = 3 and 4", "bench_ring, bench_curve"),
    ("D.4", "Hexahedral mesh of degree 4, every element inverted", "bench_sphere --case hex"),
]

# Thesis rows for the tables the JSON reports do not carry (copied from the thesis's tables).
THESIS_ONLY = {
    "3.4": [("Equilateral ideal, fig 3.9(a)", 0.05, 1.00, 0.65, 0.19, 0),
            ("Straight-sided ideal, fig 3.9(b)", 0.24, 1.00, 0.93, 0.05, 0)],
    "4.3": [("Initial, fig 4.9(a)", 0.00, 1.00, 0.96, 0.05, 130), ("Smoothed, fig 4.9(b)", 0.52, 1.00, 0.96, 0.04, 0)],
    "5.1": [("Initial", 0.00, 1.00, 0.98, 0.11, 6), ("Planar optimizer, fig 5.7(a)", 0.96, 1.00, 0.99, 0.01, 0),
            ("Surface optimizer, fig 5.7(b)", 0.96, 1.00, 0.99, 0.01, 0)],
    "5.3": [("Initial, fig 5.9(a)", 0.00, 1.00, 1.00, 0.04, 2), ("Randomized, fig 5.9(b)", 0.00, 0.23, 0.00, 0.01, 1372),
            ("Smoothed, fig 5.9(c)", 0.83, 1.00, 1.00, 0.01, 0)],
    "5.4": [("p = 1 straight-sided ideal, 5.10(b)", 1.00, 1.00, 1.00, 0.00, 0),
            ("p = 1 equilateral ideal, 5.10(a)", 0.21, 1.00, 0.93, 0.09, 0),
            ("p = 5 initial, 5.10(d)", 0.00, 1.00, 0.97, 0.14, 45), ("p = 5 initial (equilateral), 5.10(c)", 0.00, 1.00, 0.91, 0.16, 45),
            ("p = 5 optimized, 5.10(f)", 0.69, 1.00, 0.99, 0.01, 0), ("p = 5 optimized (equilateral), 5.10(e)", 0.24, 1.00, 0.93, 0.09, 0)],
    "5.6": [("Propeller p = 5 initial, 5.12(a)", -2.93, 1.00, 0.89, 0.18, 2), ("Propeller smoothed, 5.12(b)", 0.18, 1.00, 0.95, 0.08, 0),
            ("Falcon p = 5 initial, 5.12(c)", -0.75, 1.00, 0.85, 0.25, 50), ("Falcon smoothed, 5.12(d)", 0.09, 1.00, 0.92, 0.11, 0),
            ("Gear p = 10 initial, 5.12(e)", -5.55, 1.00, 0.36, 1.06, 130), ("Gear smoothed, 5.12(f)", 0.26, 1.00, 0.81, 0.16, 0)],
    "6.1": [("Initial, fig 6.3(a-d)", 0.00, 1.00, 0.91, 0.08, 3), ("Smoothed, fig 6.3(e-h)", 0.52, 1.00, 0.92, 0.08, 0)],
    "6.2": [("Straight-sided, fig 6.4(a)", 1.00, 1.00, 1.00, 0.00, 0), ("Initial, fig 6.4(b)", 0.00, 1.00, 0.99, 0.02, 12),
            ("Smoothed, fig 6.4(c)", 0.31, 1.00, 0.99, 0.01, 0)],
    "6.3": [("Initial", 0.00, 1.00, 0.99, 0.009, 11), ("Smoothed, fig 6.6", 0.85, 1.00, 0.99, 0.003, 0)],
    "6.4": [("p = 1 inviscid, 6.9(a)", 1.00, 1.00, 1.00, 0.00, 0), ("p = 1 layers inserted, 6.9(b)", 0.32, 1.00, 0.61, 0.34, 0),
            ("p = 1 smoothed, 6.9(c)", 0.97, 1.00, 1.00, 0.00, 0), ("p = 4 curved, 6.9(d)", 0.00, 1.00, 0.98, 0.09, 311),
            ("p = 4 smoothed, 6.9(e)", 0.44, 1.00, 0.99, 0.02, 0)],
    "6.5": [("p = 1 inviscid, 6.11(a)", 1.00, 1.00, 1.00, 0.00, 0), ("p = 1 layers inserted, 6.11(b)", 0.00, 1.00, 0.24, 0.18, 396),
            ("p = 1 smoothed, 6.11(c)", 0.70, 1.00, 0.96, 0.04, 0), ("p = 4 curved, 6.11(d)", 0.00, 1.00, 0.93, 0.17, 3590),
            ("p = 4 smoothed, 6.11(e)", 0.21, 1.00, 0.96, 0.04, 0)],
    "D.2": [("Initial, D.2(a)", 0.00, 1.00, 0.72, 0.19, 8), ("Smoothed, D.2(b)", 0.45, 0.98, 0.83, 0.09, 0)],
}

# Why a table has no hom column yet, and what will produce it.
MISSING = {
    "3.4": "bench_boundary_layer --case wing produces it (the final wing-section mesh against the equilateral and "
           "the straight-sided ideal); its run was skipped or failed.",
    "4.3": "bench_boundary_layer --case wing --p 2 produces it (the curved and smoothed wing-section mesh); its run "
           "was skipped or failed.",
    "5.4": "the thesis's Falcon CAD model is not public; bench_curve's real-CAD surface cases (t106_cascade, "
           "sphere_rhino, run in the full mode) are the nearest substitutes but are not the same geometry.",
    "6.3": "the Falcon simulation mesh (64992 elements) is not public and no harness builds an aircraft exterior "
           "domain; bench_curve's wing_domain (a lofted NACA 0012 half-wing in a box, p = 4, full mode) is the "
           "nearest case: see the chapter 6 section.",
    "6.4": "boundary layer around a sphere: bench_boundary_layer --case sphere produces it; it was not run.",
    "6.5": "boundary layer around an SD7003 airfoil: bench_boundary_layer --case wing produces it (NACA 0012 at p = 2 "
           "in the quick mode); its run was skipped or failed.",
    "D.2": "the motorbike brake CAD is not public; bench_curve's plate_tri / gear_face_tri (planar triangles) are "
           "substitutes of another geometry (see table 6.1 and the full mode's CAD cases).",
}

# Under each table: conditions that differ from the thesis in every mode.
CONDITIONS = {
    "3.2": "Mesh built analytically (bench/sphere_mesh.hpp, 160 tetrahedra as the thesis). The thesis does not say how "
           "it tangled the meshes: hom moves every free node by a seeded random vector whose amplitude was chosen so that "
           "the #inv of the initial mesh comes close to the thesis's 59, 16, 15.",
    "3.3": "Same meshes as table 3.2; quality against the regular tetrahedron.",
    "4.1": "Linear mesh by Gmsh 4.8.4 (OpenCASCADE box minus sphere; 1436 tetrahedra against the thesis's 1441). "
           "Random perturbation of the free nodes calibrated to the thesis's #inv; the solver of each run is named below the table.",
    "4.2": "Same linear mesh as table 4.1; hom untangles the vertex mesh first and regularizes the whole mesh while any "
           "element is invalid (bench_smooth's file comment: the literal reading does not untangle).",
    "4.4": "Cube meshed by Gmsh with the thesis's sizes (7425 tetrahedra against 7394); the thesis's node count "
           "(79429) fits p = 4, not 5.",
    "4.5": "Scaled Jacobian sampled at quadrature points and nodes; the optimized meshes are also certified (issue 8: "
           "det D phi > 0 everywhere, Bernstein bounds), folds between the quadrature points repaired by pulling the "
           "folded patch back towards the valid straight-sided start (optimize/certified.hpp); the thesis checks the "
           "quadrature points only.",
    "5.1": "The thesis's motorbike brake is not available: the degree-3 ring of appendix D (24 triangles) substitutes it.",
    "5.2": "Same structured mesh and parameterizations as the thesis (thesis_parameterizations.hpp).",
    "5.3": "Analogue: a degree-5 torus patch (72 triangles) tangled in (u, v), not the thesis's propeller.",
    "5.5": "The gear box CAD is not public: a gear-like extruded part built with OpenCASCADE (curve_models.hpp).",
    "5.6": "The thesis reports the p = 10 gear, the propeller and the Falcon; hom only has the gear-like part.",
    "6.1": "A planar part with holes and fillets (curve_models.hpp) instead of the Barcelona harbor.",
    "6.2": "The cube with a spherical cavity through the CAD pipeline instead of the Falcon aircraft.",
    "6.4": "The wall is the exact sphere as 8 rational B-spline octants (OpenCASCADE); the inviscid mesh is Gmsh's. "
           "Quality against the per-element stretched ideal (inserted, smoothed) and against the smoothed linear mesh "
           "(curved, optimized), as the thesis.",
    "6.5": "An extruded wing section in a box (the thesis meshes a wing); the thesis's 7 layers growing by 2.",
    "3.4": "The thesis's mesh (figure 3.9) is a degree-4 tetrahedral boundary layer around an SD7003 wing with 4 "
           "layers; hom's is the wing section of table 6.5 (an extruded profile in a box, 7 layers), its final "
           "mesh measured against the equilateral tetrahedron and against the smoothed linear mesh. The absolute "
           "quality of a stretched layer is low by design (section 3.3.2.2), and hom's layers are thinner than the "
           "thesis's (7 layers from 2e-4 chords), so its absolute row is lower.",
    "4.3": "The thesis's mesh is a degree-2 tetrahedral SD7003 boundary-layer mesh of 104522 elements; hom's is the "
           "wing section of table 6.5 at p = 2, far coarser: 'curved' is the initial curved mesh, 'optimized' the "
           "smoothed one.",
    "C": "Thesis numbers from the text of appendix C (82 iterations directly; 55 linear + 6 high-order with "
         "p-continuation; speed-up 2.21, counting a linear iteration as half a high-order one). hom's speed-up is "
         "given both ways: counted in iterations as the thesis counts them, and measured in wall time (in the quick mode "
         "one run per timing, on whatever load the machine had).",
    "D.1": "Ring built analytically (bench/ring_mesh.hpp), boundary nodes placed at the circle's angle.",
    "D.3": "The thesis's brake components are not public: bench_ring's quadrilateral ring and bench_curve's "
           "plate_quad substitute them.",
    "D.4": "A 270-degree thick ring of 68 hexahedra (the thesis's count), every free node perturbed.",
}

# What the quick mode leaves out, and why (times on the loaded 2-core development machine).
LEFT_OUT_OF_QUICK = [
    "table 4.1 at p = 10: about 2.5 minutes on 2 idle cores;",
    "table 4.2 (bench_smooth --case 4.2, the degree-5 cube): one to two minutes;",
    "table D.4 (bench_sphere --case hex): 60-80 Newton iterations, over two minutes; after the 15 iterations a "
    "quick run could afford all 68 elements are still inverted;",
    "table 5.3's analogue (bench_surface --case robustness): about a minute;",
    "table 3.2 / 3.3 at p = 6 and table D.1 at p = 5, 10;",
    "Gmsh's optimization modes 1, 2, 4 as peers and the unperturbed peer comparison: mode 1 does not finish in "
    "two minutes even on the quick p = 2 mesh;",
    "the gear at p = 5, 8, 10 (tables 5.5, 5.6) and the real CAD files of ../shared/data/cad;",
    "the kernel benchmarks at p = 10, with 2 threads and the Hessian setup, and the p-growth fit of the performance "
    "section.",
]

STAT_KEYS = ("min_q", "max_q", "mean_q", "std_q", "inverted")
STAT_NAMES = ("Min", "Max", "Mean", "Std", "#inv")


# ---------------------------------------------------------------------------------------------
# Running
# ---------------------------------------------------------------------------------------------

def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=30).stdout.strip()
    except Exception:
        return ""


def machine_description():
    model = sh("lscpu | sed -n 's/^Model name:[ \\t]*//p'") or platform.processor() or "unknown CPU"
    cores = os.cpu_count() or 0
    mem_kb = 0
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal:"):
                mem_kb = int(line.split()[1])
    except OSError:
        pass
    try:
        load = "%.1f, %.1f, %.1f" % os.getloadavg()
    except OSError:
        load = "?"
    return "%s, %d cores, %.1f GiB memory, %s %s; load average at start %s" % (
        model, cores, mem_kb / 1048576.0, platform.system(), platform.release(), load)


def git_commit():
    head = sh("git -C %s rev-parse HEAD" % shlex.quote(REPO)) or "unknown"
    dirty = sh("git -C %s status --porcelain --untracked-files=no" % shlex.quote(REPO))
    return head + (" (dirty: uncommitted changes in the tree)" if dirty else "")


def utc_now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")


def unrun_record(spec, status):
    """The record of a run that is listed but was not made (skipped, or not run yet)."""
    return dict(name=spec["name"], binary=spec["binary"], kind=spec.get("kind", "json"), status=status, conditions="",
                report=None, rc=None, command=spec["binary"] + " " + " ".join(spec["args"]))


def run_harness(spec, build, work, log):
    """Runs one harness; returns its record (command, wall time, status, report path)."""
    name, kind = spec["name"], spec.get("kind", "json")
    binary = os.path.join(build, "bench", spec["binary"])
    out = os.path.join(work, name)
    rec = dict(name=name, binary=spec["binary"], kind=kind, role=spec.get("role", "table"),
               conditions=spec.get("conditions", ""), report=None, rc=None, wall_s=None, status="not run",
               # Per run, because --only lets a report gather runs made at different commits and days.
               commit=git_commit(), started=utc_now(), load=os.getloadavg()[0])
    if not os.access(binary, os.X_OK):
        rec["status"] = "not built (%s missing)" % os.path.relpath(binary, REPO)
        log("%-26s %s" % (name, rec["status"]))
        return rec
    if os.path.isdir(out):
        shutil.rmtree(out)
    os.makedirs(out)
    report = os.path.join(work, name + ".json")
    if os.path.exists(report):  # a crash must not leave the previous run's report in its place
        os.remove(report)
    if kind == "gbench":
        cmd = [binary] + spec["args"] + ["--benchmark_out=" + report, "--benchmark_out_format=json"]
    else:
        cmd = [binary] + spec["args"] + ["--out", out, "--json", report]
    rec["command"] = " ".join(shlex.quote(os.path.relpath(c, REPO) if c == binary else c) for c in cmd)
    rec["command"] = rec["command"].replace(work + "/", "WORK/")
    log("%-26s running: %s" % (name, rec["command"]))
    t0 = time.time()
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(os.path.join(work, name + ".log"), "w") as f:
        try:
            # The repository root as working directory: bench_curve finds ../shared/data/cad from it.
            p = subprocess.run(cmd, cwd=REPO, stdout=f, stderr=subprocess.STDOUT, timeout=spec.get("timeout", 3600))
            rec["rc"] = p.returncode
        except subprocess.TimeoutExpired:
            rec["rc"] = "timeout"
    rec["wall_s"] = time.time() - t0
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    rec["cpu_s"] = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    if os.path.exists(report):
        rec["report"] = report
    if rec["rc"] == 0:
        rec["status"] = "ok"
    elif rec["rc"] == 1 and rec["report"]:
        rec["status"] = "finished with exit 1 (a claim or validity check failed)"
    elif rec["rc"] == "timeout":
        rec["status"] = "killed after %d s" % spec.get("timeout", 3600)
    else:
        rec["status"] = "failed (exit %s)" % rec["rc"]
    log("%-26s %s in %.1f s" % (name, rec["status"], rec["wall_s"]))
    return rec


# ---------------------------------------------------------------------------------------------
# Formatting helpers
# ---------------------------------------------------------------------------------------------

def num(v, prec=2):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if v != 0 and abs(v) < 10 ** (-prec):
            return "%.1e" % v
        return "%.*f" % (prec, v)
    return str(v)


def md_table(header, rows):
    def cell(c):  # a '|' inside a cell (a regex in a command) would end the cell
        return str(c).replace("|", "\\|")
    out = ["| " + " | ".join(cell(h) for h in header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(cell(c) for c in r) + " |")
    return "\n".join(out)


def cases_of(reports, *names):
    out = []
    for n in names:
        rep = reports.get(n)
        if rep:
            out.extend((n, c) for c in rep.get("cases", []))
    return out


def stat(v, prec=2):
    """A quality statistic: fixed decimals (the thesis prints two), tiny non-zero values in e-notation."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "-"
    if v != 0 and abs(v) < 0.5 * 10 ** (-prec):
        return "%.0e" % v
    return "%.*f" % (prec, v)


def as_stats(d):
    """Statistics under the report's keys (min_q, ...), from either naming (min, ...) of the harnesses."""
    if not d:
        return d
    return {k: d.get(k, d.get(k[:-2] if k.endswith("_q") else k)) for k in STAT_KEYS}


def stat_cells(d):
    if not d:
        return ["-"] * len(STAT_KEYS)
    return [stat(d.get("min_q")), stat(d.get("max_q")), stat(d.get("mean_q")), stat(d.get("std_q"), 3),
            num(d.get("inverted"))]


def sentence(text):
    text = text.strip()
    return text[:1].upper() + text[1:] + ("" if text.endswith(".") else ".")


def heading(tid, title):
    return "Appendix C: %s" % title if tid == "C" else "Table %s: %s" % (tid, title)


def worse_than_thesis(hom, th, final):
    """Plain statements where hom's row is worse than the thesis's (final stages only)."""
    if not th or not final:
        return []
    notes = []
    hi, ti = hom.get("inverted"), th.get("inverted")
    if isinstance(hi, (int, float)) and isinstance(ti, (int, float)) and hi > ti:
        notes.append("%d inverted elements left (thesis: %d)" % (hi, ti))
    for k, what in (("min_q", "minimum"), ("mean_q", "mean")):
        h, t = hom.get(k), th.get(k)
        if isinstance(h, (int, float)) and isinstance(t, (int, float)) and round(h, 2) < round(t, 2) - 1e-9:
            notes.append("%s %s below the thesis's %s" % (what, stat(h), "%g" % t))
    return notes


FINAL_STAGES = ("optimized", "smoothed", "non-linear", "optimized_planar", "optimized_surface")


class Section:
    """One table of the report: rows of (label, thesis stats, hom stats), conditions, notes."""

    def __init__(self, tid, title):
        self.tid, self.title = tid, title
        self.rows, self.notes, self.worse, self.extra = [], [], [], []
        self.runs = set()  # the runs whose rows the table shows
        self.failed_claims = []

    def add(self, label, thesis, hom, final=False, conditions=None, run=None, case=None):
        self.rows.append([label] + stat_cells(thesis) + stat_cells(hom))
        if run:
            self.runs.add(run)
        for w in worse_than_thesis(hom or {}, thesis or {}, final):
            self.worse.append("%s: %s." % (label, w))
        if conditions and all(conditions != text for _, text in self.notes):
            self.notes.append((run, conditions))

    def markdown(self):
        out = ["### %s" % heading(self.tid, self.title), ""]
        if self.rows:
            header = ["Row"] + ["thesis " + n for n in STAT_NAMES] + ["hom " + n for n in STAT_NAMES]
            out += [md_table(header, self.rows), ""]
        out += self.extra
        cond = [CONDITIONS[self.tid]] if self.tid in CONDITIONS else []
        # A table fed by several runs says which run each note belongs to.
        labelled = len({run for run, _ in self.notes if run}) > 1
        cond += ["run `%s`: %s" % (run, text) if labelled and run else text for run, text in self.notes]
        if cond:
            out += ["Conditions that differ: " + " ".join(sentence(c) for c in cond), ""]
        if self.failed_claims:
            out += ["**Claim checks of the harness that fail for this table:** " + "; ".join(self.failed_claims) + ".",
                    ""]
        if self.worse:
            out += ["**Where hom is worse than the thesis:** " + " ".join(self.worse), ""]
        elif self.rows:
            out += ["hom is not worse than the thesis on any final row of this table (to the printed two decimals).", ""]
        return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------------------------

def conditions_of(runs, name):
    r = runs.get(name)
    return r["conditions"] if r and r.get("conditions") else None


def label_of(c, *extra):
    parts = []
    if c.get("p") is not None:
        parts.append("p = %s" % c["p"])
    parts.append(str(c.get("stage")))
    parts.extend(e for e in extra if e)
    return ", ".join(parts)


def build_tables(reports, runs):
    sections = {}
    for tid, title, _ in TABLES:
        sections[tid] = Section(tid, title)

    # 3.2, 3.3, D.4 (bench_sphere)
    for run in ("sphere", "sphere_hex"):
        for _, c in cases_of(reports, run):
            tid = c.get("table")
            if tid in sections and c.get("thesis"):
                sections[tid].add(label_of(c, c.get("ideal") if tid == "D.4" else None), c["thesis"], c,
                                  c.get("stage") in FINAL_STAGES, conditions_of(runs, run), run=run)
    # Table 3.3's absolute quality is bounded by the shapes of the linear mesh's elements: the smoothed mesh
    # returns close to the valid curved mesh (relative quality 0.97-0.99), so that mesh's absolute quality is
    # the reference against which hom's smoothed rows should be read.
    curved = [c for _, c in cases_of(reports, "sphere")
              if c.get("table") == "3.3" and c.get("stage") == "curved" and c.get("min_q") is not None]
    if curved:
        sections["3.3"].extra += [
            "hom's valid curved mesh before tangling (the same 160 linear tetrahedra, curved onto the spheres) has "
            "absolute quality %s: the smoothed rows return to it, so their gap to the thesis is the linear mesh's "
            "element shapes, not the optimizer (the thesis's coarse mesh is not published)." % "; ".join(
                "min %s, mean %s at p = %s" % (num(c["min_q"], 2), num(c.get("mean_q"), 2), c.get("p")) for c in curved),
            ""]
    # 4.1 (bench_untangle; hom-only "curved" rows are left out)
    for run, c in cases_of(reports, "untangle", "untangle_p5"):
        if c.get("thesis"):
            sections["4.1"].add(label_of(c, "%d elements, %d nodes" % (c["elements"], c["nodes"])), c["thesis"], c,
                                c.get("stage") in FINAL_STAGES, conditions_of(runs, run), run=run)
        if c.get("stage") == "optimized":
            t = c.get("time_s")
            sections["4.1"].extra.append(
                "p = %s: %s, %s iterations, %s s (valid after %s s, min quality >= 0.96 after %s s), peak %s MB; "
                "stop: %s." % (c.get("p"), c.get("solver"), c.get("iterations"), num(t, 1),
                               num(c.get("time_to_valid_s"), 1), num(c.get("time_to_quality_096_s"), 1),
                               num(c.get("peak_rss_mb"), 0), c.get("stop_reason")))
    if sections["4.1"].extra:
        sections["4.1"].extra.append("")
    # 4.2, 4.4, 4.5 (bench_smooth)
    for _, c in cases_of(reports, "smooth"):
        th = c.get("thesis")
        name = c.get("name", "")
        if name.startswith("table_4.2") and th:
            sections["4.2"].add(label_of(c), th, c, c.get("stage") == "non-linear", conditions_of(runs, "smooth"), run="smooth")
        elif name.startswith("table_4.4"):
            if th:
                sections["4.4"].add(label_of(c, c.get("ideal") + " ideal"), th, c, c.get("stage") in FINAL_STAGES,
                                    conditions_of(runs, "smooth"), run="smooth")
            sj, tsj = c.get("scaled_jacobian"), (th or {}).get("scaled_jacobian")
            if sj and c.get("stage") in FINAL_STAGES:
                hom_sj = dict(as_stats(sj), inverted=c.get("inverted"))
                sections["4.5"].add(label_of(c, c.get("ideal") + " ideal, scaled Jacobian"), as_stats(tsj), hom_sj, True,
                                    conditions_of(runs, "smooth"), run="smooth")
                sections["4.5"].extra.append(
                    "- %s ideal: max relative volume error r_v thesis %s, hom %s; elements with mu = 1 thesis %s, hom %s "
                    "(of %s)" % (c.get("ideal"), num((th or {}).get("max_relative_volume_error"), 3),
                                 num(c.get("max_relative_volume_error"), 3), num((th or {}).get("mu_one")),
                                 num(c.get("mu_one")), c.get("elements")) +
                    ("; certified valid (Bernstein bounds) %s of %s, certified min scaled Jacobian >= %s, after %s "
                     "repair round(s)" % (c.get("certified_valid"), c.get("elements"),
                                          num(c.get("certified_min_scaled_jacobian"), 3), c.get("certify_rounds"))
                     if c.get("certified_valid") is not None else ""))
    if sections["4.5"].extra:
        sections["4.5"].extra.append("")
    # 5.1, 5.2, 5.3 (bench_surface)
    th51 = THESIS_ONLY["5.1"]
    for _, c in cases_of(reports, "surface"):
        name = c.get("name", "")
        if name.startswith("consistency"):
            i = {"initial": 0, "optimized_planar": 1, "optimized_surface": 2}.get(c.get("stage"))
            if i is not None:
                sections["5.1"].add("%s (thesis: %s)" % (c.get("stage"), th51[i][0]), dict(zip(STAT_KEYS, th51[i][1:])),
                                    c, i > 0, conditions_of(runs, "surface"), run="surface")
            if c.get("E") is not None and i == 2:
                sections["5.1"].extra += ["E (eq 5.28) between the planar and surface optimizers: thesis %s, hom %s." % (
                    num((c.get("thesis") or {}).get("E"), 6), num(c.get("E"), 6)), ""]
        elif name.startswith("table52") and c.get("thesis"):
            sections["5.2"].add("%s, %s (fig %s)" % (name[len("table52_"):].rsplit("_", 1)[0], c.get("stage"),
                                                      c.get("figure")), c["thesis"], c,
                                c.get("stage") in FINAL_STAGES, conditions_of(runs, "surface"), run="surface")
            if c.get("E_between_parameterizations") is not None and "phi^2" in name:
                sections["5.2"].extra.append("- E (eq 5.28) between phi^1 and phi^2 on %s: thesis %s, hom %s" % (
                    c.get("surface", name.split("_")[2]), num(c.get("thesis_E"), 6),
                    num(c.get("E_between_parameterizations"), 6)))
        elif name.startswith("robustness"):
            th53 = THESIS_ONLY["5.3"]
            start = 1 if c.get("start", "").startswith("perturbed") else 0
            how = "perturbed start, p-continuation" if c.get("p_continuation") else "%s start" % c.get("start")
            if c.get("initial") and not c.get("p_continuation"):
                sections["5.3"].add("%s start, before (thesis: %s)" % (c.get("start"), th53[start][0]),
                                    dict(zip(STAT_KEYS, th53[start][1:])), c["initial"])
            # The direct degree-5 solve from the scrambled start is a comparison row (without appendix C's
            # linear stage); the p-continuation and unperturbed rows are the method's results.
            final = c.get("p_continuation") or start == 0
            sections["5.3"].add("%s, optimized (thesis: %s)" % (how, th53[2][0]), dict(zip(STAT_KEYS, th53[2][1:])), c,
                                final, conditions_of(runs, "surface"), run="surface")
            if c.get("E_between_starts") is not None and start == 1:
                sections["5.3"].extra.append("- E between the meshes optimized from the %s and from the unperturbed "
                                             "start: thesis 1e-10, hom %s" % (how, num(c.get("E_between_starts"), 6)))
    for tid in ("5.2", "5.3"):
        if sections[tid].extra:
            sections[tid].extra.append("")
    # 5.5, 5.6, 6.1, 6.2, D.3 (bench_curve)
    for run in CURVE_RUNS:
        for _, c in cases_of(reports, run):
            th = c.get("thesis")
            if not th:
                continue
            final = c.get("stage") in FINAL_STAGES
            for tid in re.findall(r"[0-9A-D]\.[0-9]", th.get("table", "")):
                if tid not in sections:
                    continue
                if tid == "5.6":
                    hom_sj = dict(min_q=c.get("min_scaled_jacobian"), mean_q=c.get("mean_scaled_jacobian"),
                                  inverted=c.get("inverted"))
                    th_sj = dict(min_q=th.get("min_scaled_jacobian"), mean_q=th.get("mean_scaled_jacobian"),
                                 inverted=th.get("inverted"))
                    sections[tid].add("gear-like part, " + label_of(c, "scaled Jacobian"), th_sj, hom_sj, final,
                                      conditions_of(runs, run), run=run)
                else:
                    sections[tid].add("%s, %s" % (c.get("name"), label_of(c, c.get("part"))), th, c, final,
                                      conditions_of(runs, run), run=run)
    # 6.4, 6.5 (bench_boundary_layer: one case per stage of each wall). The p = 1 stages of the full run and of
    # boundary_layer_wing are the same meshes: each row once.
    seen_rows = set()
    for run, c in cases_of(reports, "boundary_layer", "boundary_layer_wing"):
        tid = (c.get("thesis") or {}).get("table")
        label = "%s, %s elements" % (label_of(c), c.get("elements"))
        if tid in ("6.4", "6.5") and (tid, label) not in seen_rows:
            seen_rows.add((tid, label))
            sections[tid].add(label, c["thesis"], c, c.get("stage") == "optimized", conditions_of(runs, run), run=run)
    # 3.4 and 4.3: the wing section (the thesis's figures 3.9 and 4.9 are tetrahedral SD7003 wing meshes).
    # 3.4 is the final mesh against two ideals, at the highest degree run; 4.3 is curved vs smoothed at p = 2.
    wing = [(run, c) for run, c in cases_of(reports, "boundary_layer", "boundary_layer_wing") if c.get("name") == "wing"]
    top_p = max([c.get("p") or 0 for _, c in wing], default=0)
    for run, c in wing:
        stage, absolute = c.get("stage"), c.get("ideal") == "equilateral"
        if stage == "optimized" and c.get("p") == top_p:
            th = THESIS_ONLY["3.4"][0 if absolute else 1]
            ideal = "equilateral ideal (absolute)" if absolute else "smoothed linear mesh as ideal (relative)"
            sections["3.4"].add("%s, %s elements, %s" % (label_of(c), c.get("elements"), ideal),
                                dict(zip(STAT_KEYS, th[1:])), c, True, conditions_of(runs, run), run=run)
        if not absolute and stage in ("curved", "optimized") and c.get("p") == 2:
            th = THESIS_ONLY["4.3"][0 if stage == "curved" else 1]
            sections["4.3"].add("%s, %s elements" % (label_of(c), c.get("elements")), dict(zip(STAT_KEYS, th[1:])), c,
                                stage == "optimized", conditions_of(runs, run), run=run)
    # D.1, D.3, appendix C (bench_ring)
    pcont = []
    for _, c in cases_of(reports, "ring"):
        name = c.get("name", "")
        if name == "ring_table_d1" and c.get("thesis"):
            sections["D.1"].add(label_of(c), c["thesis"], c, c.get("stage") in FINAL_STAGES, conditions_of(runs, "ring"), run="ring")
        elif name == "ring_quadrilaterals" and c.get("thesis"):
            sections["D.3"].add("quadrilateral ring, " + label_of(c), c["thesis"], c, c.get("stage") in FINAL_STAGES,
                                conditions_of(runs, "ring"), run="ring")
        elif name == "ring_pcontinuation":
            pcont.append(c)
    sec = sections["C"]
    if pcont:
        rows = []
        direct = {c.get("solver"): c.get("iterations") for c in pcont if c.get("continuation") == "none"}
        its_speedups = []
        for c in pcont:
            lin, ho, d = c.get("linear_iterations") or 0, c.get("iterations"), direct.get(c.get("solver"))
            its = d / (lin / 2 + ho) if d and ho is not None and (lin / 2 + ho) > 0 else None
            if its and c.get("continuation") != "none":
                its_speedups.append(its)
            rows.append([c.get("solver"), c.get("continuation"), num(lin), num(ho), num(its, 2),
                         num(c.get("linear_time_s"), 4), num(c.get("time_s"), 4), num(c.get("speedup"), 2),
                         num(c.get("min_q"), 3), num(c.get("inverted"))])
        sec.extra += ["Thesis (text of appendix C, degree-4 ring): direct high-order optimization 82 iterations; with "
                      "p-continuation 55 linear + 6 high-order iterations; speed-up about 2.21.", "",
                      md_table(["hom solver", "continuation", "linear its", "high-order its",
                                "speed-up in iterations (a linear one counted half, as the thesis)", "linear s",
                                "total s", "measured speed-up (wall time)", "min q", "#inv"], rows), ""]
        best = max((c.get("speedup") or 0) for c in pcont)
        best_its = max(its_speedups) if its_speedups else 0
        sec.extra += ["hom's best speed-up: %.2f counted in iterations as the thesis counts, %.2f measured in wall time "
                      "(thesis: 2.21)%s" % (best_its, best, "; **the measured speed-up is below the thesis's**."
                                           if best < 2.21 else "."), ""]
        sec.rows = []
        sec.has_numbers = True
    # The harnesses' failed claim checks, under the tables whose rows they concern (a claim names its
    # case, e.g. "plate_tri p = 7: valid ...", or its table, e.g. "D.4: ...").
    for run, rep in reports.items():
        _, failed = claim_summary(rep)
        for sec in sections.values():
            keys = set()
            for label in (r[0] for r in sec.rows):
                keys.add(label.split(",")[0] + " p")
            keys |= {"table " + sec.tid, sec.tid + ":", sec.tid + " "}
            keys |= {{"5.1": "consistency:", "5.2": "table52:", "5.3": "robustness:"}.get(sec.tid, "table " + sec.tid)}
            if not sec.rows or run not in sec.runs:
                continue
            sec.failed_claims += [f for f in failed if any(k in f for k in keys)]
    return sections


def thesis_only_section(sec, tid, reason):
    rows = THESIS_ONLY.get(tid, [])
    out = ["### %s" % heading(tid, sec.title), ""]
    out.append("**Not reproduced yet:** %s" % reason)
    out.append("")
    if rows:
        out.append("The thesis's rows, for reference (no hom column: never filled with invented numbers):")
        out.append("")
        out.append(md_table(["Row"] + ["thesis " + n for n in STAT_NAMES],
                            [[r[0]] + [num(v) for v in r[1:]] for r in rows]))
        out.append("")
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# Figures: PNGs of the harnesses, quality histograms from the VTU files
# ---------------------------------------------------------------------------------------------

FIGURES = [
    ("measures", "fig3_4.png", "Figure 3.4 / table 3.1: quality of a cubic triangle as one node moves"),
    ("measures", "fig3_5.png", "Figure 3.5: level sets, cubic triangle, equispaced nodes"),
    ("measures", "fig3_6.png", "Figure 3.6: level sets, cubic triangle, warp & blend nodes"),
    ("measures", "fig4_5.png", "Figure 4.5: regularized distortion, x2 = (x, 0)"),
    ("measures", "fig4_6.png", "Figure 4.6: regularized distortion, x2 free in the plane"),
    ("measures", "figD_3.png", "Figure D.3: level sets, quadrilateral of degree 2"),
    ("ring", "figD_1.png", "Figure D.1: the ring, initial and smoothed"),
    ("ring", "figC_2.png", "Figure C.2: p-continuation on the degree-4 ring"),
    ("ring", "figD_4.png", "Figure D.4 analogue: quadrilateral ring, initial and smoothed"),
    ("surface_appendixF", "appendixF_cylinder_triangle.png", "Figure F.1: cylinder, triangle"),
    ("surface_appendixF", "appendixF_cylinder_quadrilateral.png", "Figure F.2: cylinder, quadrilateral"),
    ("surface_appendixF", "appendixF_paraboloid_triangle.png", "Figure F.3: hyperbolic paraboloid, triangle"),
    ("surface_appendixF", "appendixF_paraboloid_quadrilateral.png", "Figure F.4: hyperbolic paraboloid, quadrilateral"),
    ("surface", "table52.png", "Figure 5.8: meshes of table 5.2"),
    ("untangle", "untangle_p2_cut.png",
     "Figure 4.7 (a, d) analogue: cube with a spherical cavity at p = 2, initial and untangled (and Gmsh's result), "
     "cut through the cavity's centre"),
    ("untangle_p5", "untangle_p5_cut.png",
     "Figure 4.7 (b, e) analogue: cube with a spherical cavity at p = 5, initial and untangled, cut through the "
     "cavity's centre"),
    ("untangle", "untangle_p5_cut.png",
     "Figure 4.7 (b, e) analogue: cube with a spherical cavity at p = 5, initial and untangled (and Gmsh's result), "
     "cut through the cavity's centre"),
    ("untangle", "untangle_p10_cut.png",
     "Figure 4.7 (c, f) analogue: cube with a spherical cavity at p = 10, initial and untangled (and Gmsh's result), "
     "cut through the cavity's centre"),
    ("smooth", "smooth_4.2_cut.png",
     "Figure 4.8 analogue: the cavity moved (table 4.2, p = 5): initial, non-linear method, linear formulation, "
     "cut through the cube's centre"),
    ("smooth", "smooth_4.4_cut.png",
     "Figure 4.10 analogue: graded cube (tables 4.4, 4.5): initial, smoothed against the equilateral and against "
     "the straight-sided ideal, cut through the centre"),
    ("boundary_layer", "cut_sphere.png",
     "Figure 6.9 analogue: cut through the curved boundary layer around the sphere (table 6.4), whole and at the wall"),
    ("boundary_layer", "cut_wing.png",
     "Figure 6.11 analogue: cut through the wing section's boundary layer (table 6.5), whole and at the leading edge"),
    ("boundary_layer_wing", "cut_wing.png",
     "Figure 4.9 / 6.11 analogue: cut through the wing section's boundary layer at p = 2 (tables 3.4, 4.3), whole "
     "and at the leading edge"),
]


def kept_beside_report(work, out, run):
    """Whether run's figures are to be taken from OUT/figures/RUN: its work directory is gone (a report
    gathered again on a fresh checkout, whose earlier runs left only what is beside the report)."""
    return not os.path.isdir(os.path.join(work, run)) and os.path.isdir(os.path.join(out, "figures", run))


def copy_figures(work, out, runs):
    """Copies every PNG a harness wrote into OUT/figures/NAME/; returns [(caption, relative path)]. A run
    without a work directory keeps the figures already beside the report (kept_beside_report)."""
    def source(run, png):
        if kept_beside_report(work, out, run):
            return os.path.join(out, "figures", run, png)
        return os.path.join(work, run, png)

    pngs = glob.glob(os.path.join(work, "*", "*.png")) + [
        path for path in glob.glob(os.path.join(out, "figures", "*", "*.png"))
        if kept_beside_report(work, out, os.path.basename(os.path.dirname(path)))]
    listed, seen = [], set()
    for run, png, caption in FIGURES:
        if os.path.exists(source(run, png)):
            listed.append((caption, os.path.join("figures", run, png)))
            seen.add((run, png))
    for path in sorted(pngs, key=lambda path: (os.path.basename(os.path.dirname(path)), os.path.basename(path))):
        run, png = os.path.basename(os.path.dirname(path)), os.path.basename(path)
        if (run, png) not in seen and run in runs:
            seen.add((run, png))
            listed.append((png, os.path.join("figures", run, png)))
    for caption, rel in listed:
        run, png = rel.split(os.sep)[1:]
        src, dst = source(run, png), os.path.join(out, rel)
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if os.path.abspath(src) != os.path.abspath(dst):
            shutil.copyfile(src, dst)
    return listed


def vtu_cell_array(path, wanted):
    """A Float64 cell-data array of a hom VTU (ASCII or appended base64 with UInt64 headers)."""
    text = open(path, "rb").read().decode("latin-1")
    cell = re.search(r"<CellData[^>]*>(.*?)</CellData>", text, re.S)
    if not cell:
        return None
    offsets = sorted(int(m) for m in re.findall(r'offset="(\d+)"', text))
    m = re.search(r'<DataArray type="Float64" Name="%s"([^>]*?)/?>' % re.escape(wanted), cell.group(1))
    if not m:
        return None
    attrs = m.group(1)
    if 'format="ascii"' in attrs:
        body = cell.group(1)[m.end():]
        body = body[:body.index("</DataArray>")]
        return [float(x) for x in body.split()]
    off = int(re.search(r'offset="(\d+)"', attrs).group(1))
    app = text[text.index("<AppendedData"):]
    app = app[app.index("_") + 1:]
    nxt = [o for o in offsets if o > off]
    chunk = app[off:nxt[0]] if nxt else app[off:app.index("</AppendedData>")].rstrip()
    raw = base64.b64decode(chunk.strip())
    n = struct.unpack("<Q", raw[:8])[0] // 8
    return list(struct.unpack("<%dd" % n, raw[8:8 + 8 * n]))


def pyplot():
    """matplotlib.pyplot with a file backend, or None without matplotlib (the report then has no drawn figures)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        return plt
    except ImportError:
        return None


def save_figure(fig, out_dir, rel):
    os.makedirs(os.path.join(out_dir, os.path.dirname(rel)), exist_ok=True)
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, rel), dpi=100)
    pyplot().close(fig)
    return rel


def histograms(work, out, runs):
    """Element-quality histograms, initial against final (and Gmsh's result), from the VTU files."""
    plt = pyplot()
    if plt is None:
        return []
    made = []
    groups = {}
    for path in sorted(glob.glob(os.path.join(work, "*", "*.vtu"))):
        if os.path.getsize(path) > 200 * 1024 * 1024:
            continue
        m = re.match(r"(.*)_(initial|optimized|smoothed|nonlinear|gmsh)\.vtu$", os.path.basename(path))
        if m and os.path.basename(os.path.dirname(path)) in runs:
            groups.setdefault((os.path.basename(os.path.dirname(path)), m.group(1)), {})[m.group(2)] = path
    for (run, prefix), files in sorted(groups.items()):
        if "initial" not in files or len(files) < 2:
            continue
        fig, ax = plt.subplots(figsize=(6, 3.2))
        bins = [i / 40 for i in range(41)]
        drawn = False
        for stage in ("initial", "optimized", "smoothed", "nonlinear", "gmsh"):
            if stage not in files:
                continue
            q = None
            for name in ("quality", "quality_relative"):
                try:
                    q = vtu_cell_array(files[stage], name)
                except Exception:
                    q = None
                if q:
                    break
            if not q:
                continue
            label = "Gmsh HighOrderOptimize" if stage == "gmsh" else stage
            ax.hist(q, bins=bins, histtype="step", linewidth=1.6, label="%s (%d elements)" % (label, len(q)))
            drawn = True
        if not drawn:
            plt.close(fig)
            continue
        ax.set_yscale("log")
        ax.set_xlabel("element shape quality (straight-sided ideal)")
        ax.set_ylabel("elements")
        ax.set_title("%s: %s" % (run, prefix))
        ax.legend(fontsize=8, loc="upper left")
        rel = save_figure(fig, out, os.path.join("figures", "histograms", "%s_%s.png" % (run, prefix)))
        made.append(((run, prefix), rel))
    # A run without a work directory (its VTU files gone with it) keeps the histograms beside the report.
    for path in glob.glob(os.path.join(out, "figures", "histograms", "*.png")):
        name = os.path.basename(path)[:-len(".png")]
        run = max((r for r in runs if name.startswith(r + "_")), key=len, default=None)
        if run and not os.path.isdir(os.path.join(work, run)) and (run, name[len(run) + 1:]) not in dict(made):
            made.append(((run, name[len(run) + 1:]), os.path.join("figures", "histograms", os.path.basename(path))))
    return [("Element quality histogram, %s %s" % key, rel) for key, rel in sorted(made)]


# ---------------------------------------------------------------------------------------------
# Peers and performance
# ---------------------------------------------------------------------------------------------

def ratio(a, b):
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and b:
        return "%.2f" % (a / b)
    return "-"


PEER_COLUMNS = ["#inv before", "#inv hom", "#inv Gmsh", "min q hom", "min q Gmsh", "mean q hom", "mean q Gmsh",
                "min SJ hom", "min SJ Gmsh", "time hom s", "time Gmsh s", "time ratio Gmsh/hom"]


def peer_cells(case, initial, peer):
    """The PEER_COLUMNS cells of one peer row: hom's optimized case, its initial case and Gmsh's entry."""
    r = ratio(peer.get("time_s"), case.get("time_s"))
    return [num(initial.get("inverted")), num(case.get("inverted")), num(peer.get("inverted")),
            num(case.get("min_q"), 3), num(peer.get("min_q"), 3), num(case.get("mean_q"), 3),
            num(peer.get("mean_q"), 3), num(case.get("min_scaled_jacobian"), 3),
            num(peer.get("min_scaled_jacobian"), 3), num(case.get("time_s"), 1), num(peer.get("time_s"), 1),
            time_ratio_cell(r, peer.get("status"))]


def time_ratio_cell(r, status):
    """A peer's time ratio: a lower bound where Gmsh ran out of time, none where it crashed or failed."""
    if status == "ok":
        return r
    if status == "timeout":
        return "> %s (timeout)" % r
    return "- (%s)" % status


def peer_verdicts(rows, first, mode):
    """What a peer table's rows say plainly (their PEER_COLUMNS cells start at column `first`; each row is
    named by its case and its Gmsh mode, column `mode`)."""
    tests = [("**hom's minimum quality is below Gmsh's** for: %s.",
              lambda c: c[3] != "-" and c[4] != "-" and float(c[3]) < float(c[4])),
             ("Gmsh leaves inverted elements where hom leaves none: %s.",
              lambda c: c[2] not in ("0", "-") and c[1] == "0"),
             ("**hom leaves inverted elements** for: %s.", lambda c: c[1] not in ("0", "-")),
             ("**hom's result folds at a node** (min scaled Jacobian <= 0, no quadrature point inverted) for: %s.",
              lambda c: c[1] == "0" and c[7] != "-" and float(c[7]) <= 0),
             ("Gmsh gives no mesh (it ran out of time, crashed or failed) for: %s.",
              lambda c: c[11].startswith(("> ", "- ("))),
             ("**hom is slower than Gmsh** (where Gmsh leaves no element inverted) for: %s.",
              lambda c: c[2] == "0" and re.match(r"^[0-9.]+$", c[11]) and float(c[11]) < 1)]
    out = []
    for text, test in tests:
        names = ["%s (Gmsh %s)" % (r[0], r[mode]) for r in rows if test(r[first:first + len(PEER_COLUMNS)])]
        if names:
            out += [text % ", ".join(names), ""]
    return out


def peers_of(case, key):
    """A case's peer entries: the list under KEY + "s" (one per Gmsh mode of a multi-mode run), else KEY's."""
    return case.get(key + "s") or ([case[key]] if case.get(key) else [])


def cad_peer_rows(reports):
    """Chapter 6's volume stage against Gmsh's optimizer on real CAD (bench_curve --optimizer-peer gmsh)."""
    keyed = []
    for run in ("curve_peer", "curve_peer_modes"):
        initial = {}
        for _, c in cases_of(reports, run):
            if c.get("part") != "volume":
                continue
            if c.get("stage") == "initial":
                initial[(c.get("name"), c.get("p"))] = c
            if c.get("stage") != "optimized":
                continue
            i = initial.get((c.get("name"), c.get("p")), {})
            for peer in peers_of(c, "optimizer_peer"):
                keyed.append(((c.get("name"), peer.get("mode"), c.get("p")),
                              ["%s p = %s" % (c.get("name"), c.get("p")), num(c.get("elements")),
                               "mode %s" % peer.get("mode"), peer.get("status")] + peer_cells(c, i, peer) +
                              [num(peer.get("peak_rss_mb"), 0)]))
    rows = [row for _, row in sorted(keyed, key=lambda kr: kr[0])]
    if not rows:
        return ["Gmsh on the CAD cases of chapter 6: not in this report (the full mode's run curve_peer, "
                "bench_curve --optimizer-peer gmsh, did not run or found no CAD files).", ""]
    return ["Chapter 6's volume stage on real CAD: the curved mesh that hom's volume stage starts from (the same "
            "linear mesh, degree and boundary nodes on the CAD, held) through hom and through Gmsh's optimizer, "
            "both judged by hom's shape quality. hom's time is its volume stage's (with --certify, the certification "
            "and repair included). Gmsh's modes as above (run curve_peer: mode 1 at p = 2 to 5; run "
            "curve_peer_modes: modes 2, 3 and 4 at p = 2 and 3, each from the same initial mesh, hom's volume stage "
            "run once for the three). Gmsh's optimizer works only on patches around the elements whose scaled "
            "Jacobian lies outside [Mesh.HighOrderThresholdMin, Max] = [0.1, 2]: where the initial mesh has none it "
            "returns at once, with the initial quality.", "",
            md_table(["case", "tetrahedra", "Gmsh", "Gmsh status"] + PEER_COLUMNS + ["peak MB Gmsh"], rows),
            ""] + peer_verdicts(rows, 4, 2)


def peer_section(reports, runs):
    out = ["## Peer comparison: Gmsh 4.8.4 on identical inputs", ""]
    keyed = []
    runs_with_peer = (["untangle", "untangle_unperturbed_peer"] + ["untangle_peer_mode%d" % m for m in (2, 3, 4)] +
                      ["untangle_p10_peer_modes", "untangle_p10_unperturbed_peer_modes"])
    for run in runs_with_peer:
        init = {}
        input_name = "unperturbed" if "unperturbed" in run else "perturbed"
        for _, c in cases_of(reports, run):
            if c.get("stage") == "initial":
                init[c.get("p")] = c
            if c.get("stage") != "optimized":
                continue
            for peer in peers_of(c, "peer"):
                keyed.append(((input_name == "unperturbed", peer.get("mode"), c.get("p")),
                              ["%s p = %s" % (input_name, c.get("p")), "mode %s" % peer.get("mode"),
                               peer.get("status")] + peer_cells(c, init.get(c.get("p"), {}), peer) +
                              [num(c.get("peak_rss_mb"), 0), num(peer.get("peak_rss_mb"), 0)]))
    rows = [row for _, row in sorted(keyed, key=lambda kr: kr[0])]
    if rows:
        out += ["Untangling (table 4.1's pipeline): the same curved mesh, randomly perturbed or not (the case says), "
                "through hom (its default solver, without p-continuation) and through Gmsh's high-order "
                "optimizer (Mesh.HighOrderOptimize, child process), both judged by hom's shape quality. hom's peak "
                "memory is the whole harness process's. Gmsh's modes: 1 optimization, 2 elastic analogy then "
                "optimization, 3 elastic analogy, 4 fast curving. Its optimization works on patches around the elements whose scaled "
                "Jacobian lies outside [Mesh.HighOrderThresholdMin, Max] = [0.1, 2]: where none is (mode 1 on the "
                "unperturbed mesh at p = 2, mode 2 after its elastic step at p = 2) it returns at once.", "",
                md_table(["case", "Gmsh", "Gmsh status"] + PEER_COLUMNS + ["peak MB hom", "peak MB Gmsh"], rows),
                ""] + peer_verdicts(rows, 3, 1)
    else:
        out += ["No untangling peer run in this report (bench_untangle --peer gmsh not run or Gmsh not built).", ""]
    out += cad_peer_rows(reports)
    rows = []
    for _, c in cases_of(reports, "certify"):
        peer = c.get("peer")
        if not peer:
            continue
        hom_invalid = c.get("certified_invalid")
        rows.append(["p = %s %s" % (c.get("p"), c.get("stage")), c.get("elements"), num(c.get("inverted")),
                     num(c.get("certified_valid")),
                     num(hom_invalid), num(c.get("undecided")), num(peer.get("certified_valid")),
                     num(peer.get("certified_invalid")), num(peer.get("disagreements")),
                     num(c.get("certified_min_scaled_jacobian"), 3), num(peer.get("min_jacobian_ratio"), 3),
                     num(c.get("time_s"), 2), num(peer.get("time_s"), 2), ratio(peer.get("time_s"), c.get("time_s"))])
    if rows:
        out += ["Certified validity (issue 8): hom's Bernstein-bound certification against Gmsh's "
                "Plugin(AnalyseMeshQuality) on the same meshes. The same element-by-element agreement is "
                "a unit test for every family (test/test_gmsh_validity.cpp: planar triangles and "
                "quadrilaterals at p = 2 and 7, tetrahedra and hexahedra at p = 2 and 5, straight-sided, "
                "randomly folded and mirrored meshes), and bench_curve --certify checks it on the CAD "
                "cases' tetrahedral and planar results.", "",
                md_table(["mesh", "elements", "#inv (quadrature check)", "hom valid", "hom invalid", "hom undecided",
                          "Gmsh valid", "Gmsh invalid",
                          "disagreements", "hom certified min SJ", "Gmsh min J ratio", "hom s", "Gmsh s",
                          "time ratio Gmsh/hom"], rows), ""]
        if any(r[8] not in ("0", "-") for r in rows):
            out += ["**hom and Gmsh disagree on some elements** (see the disagreements column).", ""]
        hidden = [r[0] for r in rows if r[2] == "0" and r[4] not in ("0", "-")]
        if hidden:
            out += ["**Certification finds invalid elements that the quadrature-point check misses** in: %s (the "
                    "optimizer's validity is judged at quadrature points; such an element has det J <= 0 elsewhere)."
                    % ", ".join(hidden), ""]
    return "\n".join(out)


def loglog_slope(xs, ys):
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x and y and x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx else None


def performance_section(reports, runs, out_dir, full):
    out = ["## Performance", ""]
    kern = reports.get("kernel")
    if kern:
        ctx = kern.get("context", {})
        peak = float(ctx.get("hom_peak_gflops_per_cpu_s_1thread", "nan"))
        peak_wall = float(ctx.get("hom_peak_gflops_1thread", "nan"))
        out += ["Element kernels (bench_kernel, Google Benchmark). Machine FMA peak measured by the harness at start-up "
                "(%s, 1 thread): %.1f GFLOP/s per CPU second (%.1f GFLOP/s wall). On a loaded machine the per-CPU-second "
                "rates are the meaningful ones." % (ctx.get("hom_isa", "?"), peak, peak_wall), ""]
        rows = []
        for b in kern.get("benchmarks", []):
            if b.get("run_type") == "aggregate":
                continue
            name = b.get("name", "").replace("/process_time", "").replace("/real_time", "")
            g = b.get("GFLOPs_per_cpu_s")
            rows.append([name, num(b.get("points_per_s"), 0) if b.get("points_per_s") else "-",
                         num(b.get("elements_per_s"), 0) if b.get("elements_per_s") else "-", num(g, 2),
                         num(b.get("GFLOPs"), 2), "%.0f%%" % (100 * g / peak) if g and math.isfinite(peak) and
                         not name.startswith("fma_peak") else "-"])
        out += [md_table(["benchmark", "points/s", "elements/s", "GFLOP/s per CPU s", "GFLOP/s wall",
                          "fraction of the FMA peak (CPU s)"], rows), ""]
    # Solver comparison and p-continuation from bench_untangle's runs.
    rows = []
    for run in ("untangle", "untangle_newton", "untangle_gs", "untangle_pcont", "untangle_1thread"):
        for _, c in cases_of(reports, run):
            if c.get("stage") != "optimized":
                continue
            if run == "untangle" and any(r.startswith("untangle_") for r in reports) and \
                    c.get("p") not in [cc.get("p") for _, cc in cases_of(reports, "untangle_newton")]:
                continue
            rows.append([run, "p = %s" % c.get("p"), c.get("solver"), num(c.get("threads")), num(c.get("iterations")),
                         num(c.get("time_s"), 2), num(c.get("time_to_valid_s"), 2), num(c.get("inverted")),
                         num(c.get("min_q"), 3), num(c.get("peak_rss_mb"), 0)])
    if rows:
        out += ["Solver comparison on table 4.1's pipeline (bench_untangle: matrix-free Newton is the default; Newton "
                "with the assembled Hessian, non-linear Gauss-Seidel, p-continuation, one thread against the default):",
                "", md_table(["run", "p", "solver", "threads", "iterations", "time s", "valid after s", "#inv",
                              "min q", "peak MB"], rows), ""]
        base = [r for r in rows if r[0] == "untangle"]
        pc = [r for r in rows if r[0] == "untangle_pcont"]
        one = [r for r in rows if r[0] == "untangle_1thread"]
        if base and pc:
            r = float(base[0][5]) / float(pc[0][5])
            out += ["p-continuation speed-up on the cube (%s): %.2f (time without / with)%s" % (
                pc[0][1], r, "; **p-continuation is slower than the direct solve here**." if r < 1 else ".")]
        if base and one:
            out += ["Two threads against one (%s): speed-up %s (a loaded 2-core machine: the second core is rarely "
                    "free)." % (one[0][1], ratio(float(one[0][5]), float(base[0][5])))]
        out += [""]
    # Time and memory growth with p (full mode: p = 2, 5, 10).
    all_opt = [c for _, c in cases_of(reports, "untangle") if c.get("stage") == "optimized"]
    opt = [c for c in all_opt if c.get("inverted") == 0]  # a run stopped with inverted elements has no comparable time
    if len(all_opt) > len(opt):
        out += ["Left out of the growth fit: %s (stopped with inverted elements)." % ", ".join(
            "p = %s" % c.get("p") for c in all_opt if c not in opt), ""]
    if len(opt) >= 2:
        ps = [c["p"] for c in opt]
        ts = [c.get("time_s") for c in opt]
        ns = [c.get("nodes") for c in opt]
        ms = [c.get("peak_rss_mb") for c in opt]
        s_tp, s_tn, s_mp = loglog_slope(ps, ts), loglog_slope(ns, ts), loglog_slope(ps, ms)
        out += ["Growth with p (bench_untangle, optimized stage): log-log slope of time against p %s, of time against "
                "#nodes %s, of peak memory against p %s." % (num(s_tp), num(s_tn), num(s_mp)), ""]
        plt = pyplot()
        if plt:
            fig, ax = plt.subplots(figsize=(5, 3.5))
            ax.loglog(ps, ts, "o-", label="time s (slope %s)" % num(s_tp))
            ax.loglog(ps, ms, "s--", label="peak MB (slope %s)" % num(s_mp))
            ax.set_xlabel("p")
            ax.legend(fontsize=8)
            ax.set_title("table 4.1 pipeline: growth with p")
            rel = save_figure(fig, out_dir, os.path.join("figures", "performance", "time_vs_p.png"))
            out += ["![time and memory against p](%s)" % rel, ""]
    elif not full:
        out += ["Time and memory growth with p (log-log slope) is measured in the full mode only (p = 2, 5, 10).", ""]
    ring = [c for _, c in cases_of(reports, "ring") if c.get("name") == "ring_pcontinuation"]
    if ring:
        out += ["Solver comparison and p-continuation on the degree-4 ring: see the appendix C section.", ""]
    ref = reports.get("reference")
    if ref:
        rows = [[b["name"], num(b.get("real_time"), 3), b.get("time_unit", ""), num(b.get("items_per_second"), 0)]
                for b in ref.get("benchmarks", []) if b.get("run_type") != "aggregate"]
        out += ["Reference-element tabulation (bench_reference):", "",
                md_table(["benchmark", "time", "unit", "points/s"], rows), ""]
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# The report
# ---------------------------------------------------------------------------------------------

CURVE_RUNS = ("curve", "curve_plate", "curve_cube", "curve_p10", "curve_models", "curve_cad", "curve_wing_merged")


def cad_cases_section(reports):
    """Every bench_curve case and degree, thesis rows or not (the models of curve_models.hpp and the real CAD
    files included): the optimized stage of each part beside the initial curved one's #inv, and the claims that
    failed."""
    cases = cases_of(reports, *CURVE_RUNS)
    if not cases:
        return ""
    initial = {(run, c.get("name"), c.get("p"), c.get("part")): c for run, c in cases if c.get("stage") == "initial"}
    rows = []
    for run, c in cases:
        if c.get("stage") != "optimized":
            continue
        c0 = initial.get((run, c.get("name"), c.get("p"), c.get("part"))) or {}
        rows.append([c.get("name"), run, num(c.get("p")), "%s %s" % (c.get("part"), c.get("family")),
                     num(c.get("elements")), num(c.get("nodes")), num(c.get("mesh_tries")),
                     num(c0.get("inverted")), num(c.get("inverted")),
                     stat(c.get("min_q")), stat(c.get("mean_q")), stat(c.get("min_scaled_jacobian")),
                     "%.2f" % c["time_s"] if isinstance(c.get("time_s"), (int, float)) else "-"])
    out = ["## Chapter 6: every CAD case", "",
           "Each bench_curve case of this report at each degree: the optimized stage of each part (surface, then volume "
           "or planar domain), with the #inv of the initial curved stage before it (quadrature-point check; shape "
           "quality against the straight-sided ideal). Only some of these cases have thesis rows (tables 5.5, 5.6, 6.1, "
           "6.2, D.3); the others are here so that no case is left out. meshes: the linear meshes the case took; more "
           "than 1 where the run's --refine-invalid meshed the model again finer around the failing elements of an "
           "invalid or uncertified result (the row is the last mesh's; '-': a run from before the option).", "",
           md_table(["case", "run", "p", "part", "elements", "nodes", "meshes", "#inv initial", "#inv optimized", "min q",
                     "mean q", "min SJ", "time s"], rows), ""]
    for run in CURVE_RUNS:
        n, failed = claim_summary(reports.get(run))
        if failed:
            out += ["**%s: %d of %d claims failed:** %s." % (run, len(failed), n, "; ".join(failed)), ""]
    return "\n".join(out)


def claim_summary(rep):
    checks = (rep or {}).get("checks") or []
    for c in (rep or {}).get("cases", []):
        if c.get("stage") == "checks":
            checks = checks + c.get("claims", [])
        elif isinstance(c.get("checks"), list):  # bench_sphere: a case's own checks
            checks = checks + c["checks"]
    failed = [c.get("claim") for c in checks if not c.get("holds", c.get("passed", True))]
    return len(checks), failed


def checks_cell(rep):
    n, failed = claim_summary(rep)
    if not n:
        return "-"
    return "%d, all hold" % n if not failed else "%d, **failed**: %s" % (n, "; ".join(failed))


def run_at_cell(rec):
    """Commit, start and 1-minute load average of one run (records older than these fields: "-")."""
    if not rec.get("commit"):
        return "-"
    commit = rec["commit"][:7] + (" (dirty)" if "dirty" in rec["commit"] else "")
    return "%s, %s, load %.1f" % (commit, rec["started"][:16], rec.get("load", float("nan")))


def write_report(args, meta, runs, reports, out_dir, work, total_s):
    full = args.mode == "full"
    lines = ["# hom: reproduction report of Gargallo-Peiró (2014)", "",
             "Generated by `paper/make`; do not edit by hand.", "",
             "- command: `%s`" % meta["command"]] + (
                 ["- report rebuilt from that command's runs by: `%s`" % args.rebuilt_by] if args.rebuilt_by else []) + (
                 ["- runs not named by --only are the work directory's earlier results"] if args.only else []) + [
             "- commit: %s" % meta["commit"],
             "- date: %s" % meta["started"],
             "- machine: %s" % meta["machine"],
             "- mode: %s%s" % (args.mode, " (small cases; see the conditions under each table)" if not full else
                               " (the thesis's sizes)"),
             "- build: `%s`" % os.path.relpath(args.build, REPO),
             "- total wall time of the runs: %.0f s, CPU time of the harnesses %.0f s (every timing in this report "
             "was taken on this machine as it was: where the CPU time is well below wall time x cores the machine "
             "was shared with other work, and wall times are pessimistic)" % (total_s, sum(r.get("cpu_s") or 0 for r in runs.values())),
             ""]
    lines += ["## Runs", "",
              md_table(["part", "command", "wall s", "CPU s", "status", "claim checks", "run at"],
                       [[r["name"], "`%s`" % r.get("command", r["binary"]), num(r.get("wall_s"), 1),
                         num(r.get("cpu_s"), 1), r["status"],
                         checks_cell(reports.get(r["name"])), run_at_cell(r)]
                        for r in runs.values()]), ""]
    if not full:
        lines += ["Left out of the quick mode (too slow for CI even in their smallest setting; `paper/make --full` "
                  "runs them):", ""] + ["- %s" % t for t in LEFT_OUT_OF_QUICK] + [""]
    lines += ["## Thesis tables", "",
              "Every thesis table in order. Columns: the thesis's Min, Max, Mean, Std.Dev. and #inv of the element "
              "quality, then hom's for the same row. Rows and thesis numbers come from the harnesses' JSON; tables no "
              "harness reproduces give the thesis's rows only, with the reason.", ""]
    sections = build_tables(reports, runs)
    for tid, title, source in TABLES:
        sec = sections[tid]
        if sec.rows or getattr(sec, "has_numbers", False):
            lines += [sec.markdown()]
        elif tid in MISSING:
            lines += [thesis_only_section(sec, tid, MISSING[tid])]
        else:
            mode_note = "this table's rows need the full mode (paper/full/report.md has them once its run is made), " \
                "or its run was skipped or failed" if not full else \
                "its run was skipped or did not produce these rows"
            lines += [thesis_only_section(sec, tid, "no rows in this report: %s produces this table, "
                                                    "but %s (see the runs above)." % (source, mode_note))]
    figs = copy_figures(work, out_dir, runs)
    hists = histograms(work, out_dir, runs)
    lines += ["## Figures", "",
              "PNG figures drawn by the harnesses (copied beside this report) and element-quality histograms drawn "
              "from their VTU files. The 3D curved meshes are shown by planar cuts (bench/mesh_cut.hpp): each element's "
              "degree-p map is cut, not its vertices, so curved elements show curved; polygons are coloured by "
              "element quality and inverted elements hatched in red. The VTU files in the work directory open in "
              "ParaView.", ""]
    if figs or hists:
        for caption, rel in figs + hists:
            lines += ["**%s**" % caption, "", "![%s](%s)" % (caption, rel), ""]
    else:
        lines += ["No figures (matplotlib missing or the plotting harnesses did not run).", ""]
    lines += [cad_cases_section(reports), peer_section(reports, runs), performance_section(reports, runs, out_dir, full)]
    lines += ["## Data", "",
              "The harnesses' JSON reports of this run are in `data/` beside this file; CSV and VTU files stay in the work "
              "directory (`%s`)." % os.path.relpath(work, REPO), ""]
    text = "\n".join(lines).rstrip() + "\n"
    os.makedirs(os.path.join(out_dir, "data"), exist_ok=True)
    for r in runs.values():
        dst = os.path.join(out_dir, "data", r["name"] + ".json")
        if r.get("report") and os.path.abspath(r["report"]) != os.path.abspath(dst):
            shutil.copyfile(r["report"], dst)
    tmp = os.path.join(out_dir, "report.md.tmp")
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, os.path.join(out_dir, "report.md"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", dest="mode", action="store_const", const="quick", help="small cases (default)")
    g.add_argument("--full", dest="mode", action="store_const", const="full", help="the thesis's sizes (hours)")
    ap.set_defaults(mode="quick")
    ap.add_argument("--build", default=os.path.join(REPO, "build"), help="meson build directory (default: build)")
    ap.add_argument("--out", default=os.path.join(REPO, "paper"), help="where report.md goes (default: paper)")
    ap.add_argument("--work", help="work directory of the harness runs (default: BUILD/paper-work-MODE)")
    ap.add_argument("--only", help="comma-separated run names (see --list); the others are not run")
    ap.add_argument("--skip", help="comma-separated run names not to run (the report lists them as skipped)")
    ap.add_argument("--no-run", action="store_true", help="rebuild the report from the work directory's JSON")
    ap.add_argument("--list", action="store_true", help="list the runs of the mode and exit")
    ap.add_argument("--command", help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.build = os.path.abspath(args.build)
    out_dir = os.path.abspath(args.out)
    work = os.path.abspath(args.work or os.path.join(args.build, "paper-work-" + args.mode))
    args.command = args.command or " ".join(shlex.quote(a) for a in ["paper/make_report.py"] + sys.argv[1:])
    specs = FULL if args.mode == "full" else QUICK
    if args.list:
        for s in specs:
            print("%-26s %s %s" % (s["name"], s["binary"], " ".join(s["args"])))
        return 0
    only = set(args.only.split(",")) if args.only else None
    skip = set(args.skip.split(",")) if args.skip else set()
    for opt, names in (("--only", only or set()), ("--skip", skip)):
        if not names <= {s["name"] for s in specs}:
            ap.error("%s: unknown run(s) %s (see --list)" % (opt, ", ".join(sorted(names - {s["name"] for s in specs}))))
    if not os.path.isdir(args.build):
        ap.error("--build: no directory %s" % args.build)
    os.makedirs(work, exist_ok=True)
    os.makedirs(out_dir, exist_ok=True)
    started = utc_now()
    commit, machine = git_commit(), machine_description()  # before the runs: the load they started under

    def log(msg):
        print("paper: " + msg, flush=True)

    t0 = time.time()
    runs, reports = {}, {}
    state = os.path.join(work, "runs.json")
    # The earlier runs: the work directory's record or, in a new work directory (a fresh checkout), the
    # copy kept beside the report, whose JSON reports are in OUT/data.
    kept_state = os.path.join(out_dir, "data", "runs.json")
    previous = {}
    for path in (state, kept_state):
        if os.path.exists(path):
            previous = json.load(open(path))
            break
    previous_meta = previous.get("meta") if "runs" in previous else None
    previous = previous.get("runs", previous)
    for spec in specs:
        name = spec["name"]
        if name in skip:
            rec = unrun_record(spec, "skipped (--skip)")
        elif args.no_run or (only and name not in only):
            rec = previous.get(name)
            if not rec:  # listed, so that a partial report shows what it lacks
                rec = unrun_record(spec, "not run yet")
            elif rec.get("report") and not os.path.exists(rec["report"]):
                # Gone with its work directory, or relative to OUT (the kept copy): the JSON beside the report.
                kept = os.path.join(out_dir, rec["report"])
                if not os.path.exists(kept):
                    kept = os.path.join(out_dir, "data", name + ".json")
                rec["report"] = kept if os.path.exists(kept) else None
        else:
            rec = run_harness(spec, args.build, work, log)
        runs[name] = rec
        if rec.get("report") and os.path.exists(rec["report"]):
            try:
                reports[name] = json.load(open(rec["report"]))
            except ValueError as e:
                rec["status"] += "; unreadable JSON (%s)" % e
    # What produced the runs: this command, or (with --no-run) the command that ran them.
    meta = dict(command=args.command, started=started, commit=commit, machine=machine)
    args.rebuilt_by = None
    if args.no_run and previous_meta:
        args.rebuilt_by = args.command
        meta = previous_meta
    with open(state, "w") as f:
        json.dump(dict(meta=meta, runs=runs), f, indent=1)
    # The runs' own times: with --only or --no-run most runs are earlier ones.
    total = sum(r.get("wall_s") or 0 for r in runs.values())
    write_report(args, meta, runs, reports, out_dir, work, total)
    # The runs' record travels with the report (a fresh checkout has no work directory), its JSON
    # reports named relative to OUT.
    kept = {n: dict(r, report=os.path.join("data", n + ".json") if r.get("report") else None) for n, r in runs.items()}
    with open(kept_state, "w") as f:
        json.dump(dict(meta=meta, runs=kept), f, indent=1)
    log("wrote %s (%.0f s)" % (os.path.join(out_dir, "report.md"), time.time() - t0))
    # A harness that is built but wrote no report crashed or timed out: the report says so, and
    # the exit status too (claim checks that fail are the report's business, not an error).
    broken = [r["name"] for r in runs.values() if r.get("rc") is not None and not r.get("report")]
    if broken:
        log("no report from: " + ", ".join(broken))
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
