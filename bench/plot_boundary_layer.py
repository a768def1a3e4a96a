#!/usr/bin/python3
"""Planar cuts through the final curved boundary-layer meshes, from the CSV
files of bench_boundary_layer (bench/mesh_cut.hpp writes them).

Usage: plot_boundary_layer.py [DIR [CASE ...]]
       (default DIR results/boundary_layer, default cases every cut_*.csv there)

  cut_<case>.png   left: the whole cut; right: the wall region, a window four
                   layer heights wide at a wall point (sphere: 45 degrees on
                   the circle; wing: the leading edge)

The cut is the union of small polygons, the sections of the linear
sub-tetrahedra the harness splits each curved element into; they are filled
with their element's quality (shape measure, the ideal of the table's last
stage) and each element's outline, the polygon edges that no other polygon of
the same element shares, is drawn over them. Inverted elements are hatched
and outlined in red.

Needs numpy and matplotlib only (Debian's python3-numpy, python3-matplotlib).
"""

import glob
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

CMAP = plt.get_cmap("viridis")
NORM = mcolors.Normalize(vmin=0.0, vmax=1.0)

TITLES = {
    "sphere": ("sphere (table 6.4): cut through the centre, normal z", "wall at 45 degrees"),
    "wing": ("wing section (table 6.5): mid-span cut z = span / 2", "leading edge"),
}


class Cut:
    """The polygons of one cut and, per polygon, its element's data."""

    def __init__(self, path):
        rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        if rows.shape[0] == 0:
            rows = np.zeros((0, 7))
        self.xy = rows[:, 2:4]
        polygon = rows[:, 1].astype(int)
        # A polygon's vertices are consecutive rows.
        self.start = np.flatnonzero(np.r_[True, polygon[1:] != polygon[:-1]]) if len(polygon) else np.zeros(0, int)
        self.end = np.r_[self.start[1:], len(polygon)].astype(int)
        first = self.start
        self.element = rows[first, 0].astype(int)
        self.quality = rows[first, 4]
        self.bad = (rows[first, 5] > 0) | (rows[first, 4] < 0)
        self.level = rows[first, 6].astype(int)
        self.row_level = rows[:, 6].astype(int)
        self.row_element = rows[:, 0].astype(int)

    def polygons(self, keep):
        return [self.xy[s:e] for s, e in zip(self.start[keep], self.end[keep])]

    def outline(self):
        """Element outlines as segments (a, b), with each one's element: the
        polygon edges that occur once within their element (the harness
        computes shared points bit for bit alike, so inner edges pair up)."""
        n = len(self.xy)
        following = np.arange(1, n + 1)
        following[self.end - 1] = self.start
        a, b = self.xy, self.xy[following]
        swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
        a, b = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)
        edges = np.column_stack([self.row_element, a, b])
        unique, count = np.unique(edges, axis=0, return_counts=True)
        once = unique[(count == 1) & np.any(unique[:, 1:3] != unique[:, 3:5], axis=1)]
        return once[:, 0].astype(int), once[:, 1:].reshape(-1, 2, 2)


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


def draw(ax, cut, outline, window, title, line_width):
    """One panel: the polygons (inside `window` if given) coloured by quality,
    the element outlines over them, inverted elements hatched in red."""
    keep = np.ones(len(cut.start), bool)
    if window is not None:
        x0, x1, y0, y1 = window
        lo = np.minimum.reduceat(cut.xy, cut.start, axis=0)
        hi = np.maximum.reduceat(cut.xy, cut.start, axis=0)
        keep = (hi[:, 0] >= x0) & (lo[:, 0] <= x1) & (hi[:, 1] >= y0) & (lo[:, 1] <= y1)
    # Edges in the face colour close the hairline gaps between the polygons.
    face = PolyCollection(cut.polygons(keep), array=cut.quality[keep], cmap=CMAP, norm=NORM, edgecolors="face",
                          linewidths=0.2)
    ax.add_collection(face)
    bad = keep & cut.bad
    if np.any(bad):
        ax.add_collection(PolyCollection(cut.polygons(bad), facecolors="none", edgecolors="red", linewidths=0.0,
                                         hatch="///"))
    elements, segments = outline
    inverted = np.isin(elements, np.unique(cut.element[cut.bad]))
    ax.add_collection(LineCollection(segments[~inverted], colors="black", linewidths=line_width))
    ax.add_collection(LineCollection(segments[inverted], colors="red", linewidths=3 * line_width))
    ax.set_aspect("equal")
    if window is not None:
        ax.set_xlim(window[0], window[1])
        ax.set_ylim(window[2], window[3])
    else:
        ax.autoscale_view()
    ax.tick_params(labelsize=7)
    elems = np.unique(cut.element[keep])
    n_bad = len(np.unique(cut.element[bad]))
    qmin = cut.quality[keep].min() if np.any(keep) else float("nan")
    ax.set_title(f"{title}\n{len(elems)} elements, min q = {qmin:.3f}, #inv = {n_bad}", fontsize=9)
    return face


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
    fig.colorbar(face, ax=axes.ravel().tolist(), shrink=0.8, label="element quality (shape measure, last stage's ideal)")
    fig.suptitle(title, fontsize=11)
    out = os.path.join(out_dir, f"cut_{case}.png")
    fig.savefig(out, dpi=150)
    plt.close(fig)
    print(f"plot_boundary_layer: wrote {out}")


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
