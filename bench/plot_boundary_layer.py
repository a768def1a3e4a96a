#!/usr/bin/python3
"""Planar cuts through the final curved boundary-layer meshes, from the CSV
files of bench_boundary_layer (bench/mesh_cut.hpp writes them).

Usage: plot_boundary_layer.py [DIR [CASE ...]]
       (default DIR results/boundary_layer, default cases every cut_*.csv there)

  cut_<case>.png   left: the whole cut; right: the wall region, a window four
                   layer heights wide at a wall point (sphere: 45 degrees on
                   the circle; wing: the leading edge)

The panels are plot_cut.py's (its reader and drawing, shared): polygons
filled with their element's quality (shape measure, the ideal of the table's
last stage), element outlines over them, inverted elements hatched in red.

Needs numpy and matplotlib only (Debian's python3-numpy, python3-matplotlib).
"""

import glob
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_cut import Cut, draw, save_figure  # noqa: E402

TITLES = {
    "sphere": ("sphere (table 6.4): cut through the centre, normal z", "wall at 45 degrees"),
    "wing": ("wing section (table 6.5): mid-span cut z = span / 2", "leading edge"),
}


def wall_point(case, cut):
    """The zoom's wall point: on the sphere, 45 degrees on the wall circle
    (the plane goes through the centre, the in-plane origin); elsewhere the
    wall's upstream-most point (the wing's leading edge)."""
    wall = cut.xy[cut.row_level == 0]
    if case == "sphere":
        radius = np.sqrt((wall ** 2).sum(axis=1)).min()
        return radius * np.array([np.cos(np.pi / 4), np.sin(np.pi / 4)])
    return wall[np.argmin(wall[:, 0])]


def zoom_window(case, cut):
    """(x0, x1, y0, y1) around the wall point, four layer heights wide; the
    layer's height there is the distance to the nearest point off the layer
    (level -1), which lies on the layer's top. None without a layer."""
    if not np.any(cut.row_level == 0) or not np.any(cut.row_level < 0):
        return None
    w = wall_point(case, cut)
    outside = cut.xy[cut.row_level < 0]
    distance = np.sqrt(((outside - w) ** 2).sum(axis=1))
    top = outside[np.argmin(distance)]
    height = distance.min()
    centre = 0.5 * (w + top)
    return centre[0] - 2 * height, centre[0] + 2 * height, centre[1] - 2 * height, centre[1] + 2 * height


def plot_case(out_dir, case):
    path = os.path.join(out_dir, f"cut_{case}.csv")
    cut = Cut(path)
    if len(cut.start) == 0:
        print(f"plot_boundary_layer: {path} has no polygons; no figure")
        return
    title, zoom_title = TITLES.get(case, (f"{case}: planar cut", "wall region"))
    outline = cut.outline()
    window = zoom_window(case, cut)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.4))
    face = draw(axes[0], cut, outline, None, "whole cut", 0.15)
    if window is not None:
        x0, x1, y0, y1 = window
        axes[0].add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor="red", linewidth=1.0))
        draw(axes[1], cut, outline, window, f"{zoom_title} (red box on the left)", 0.5)
    else:
        axes[1].axis("off")
        axes[1].set_title("no layer elements in the cut", fontsize=9)
    save_figure(fig, axes, face, title, "element quality (shape measure, last stage's ideal)",
                os.path.join(out_dir, f"cut_{case}.png"))


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "results/boundary_layer"
    cases = sys.argv[2:]
    if not cases:
        cases = sorted(os.path.basename(p)[4:-4] for p in glob.glob(os.path.join(out_dir, "cut_*.csv")))
    for case in cases:
        plot_case(out_dir, case)
    return 0


if __name__ == "__main__":
    sys.exit(main())
