#!/usr/bin/python3
"""Planar cuts through curved tetrahedral meshes, from the CSV files that
bench/mesh_cut.hpp writes (write_cut_csv): the shared reader and panel of
plot_boundary_layer.py, and a figure of one case's stages side by side.

Usage: plot_cut.py DIR NAME [TITLE]
  reads DIR/NAME_<stage>_cut.csv for the stages of STAGE_ORDER (those
  present, in that order, then any other) and writes
  DIR/NAME_cut.png, one panel per stage.

The cut is the union of small polygons, the sections of the linear
sub-tetrahedra the harness splits each curved element into; they are filled
with their element's quality and each element's outline, the polygon edges
that no other polygon of the same element shares, is drawn over them.
Inverted elements are hatched and outlined in red.

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

CMAP = plt.get_cmap("viridis")
NORM = mcolors.Normalize(vmin=0.0, vmax=1.0)
STAGE_ORDER = ["initial", "smoothed", "nonlinear", "linear", "optimized", "equilateral", "straight-sided", "gmsh"]


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


def save_figure(fig, axes, face, title, colour_label, out):
    """The colour bar of `face` (if any panel was drawn) beside `axes`, the
    title, and the PNG `out`."""
    if face is not None:
        fig.colorbar(face, ax=axes.ravel().tolist(), shrink=0.8, label=colour_label)
    fig.suptitle(title, fontsize=11)
    fig.savefig(out, dpi=150)
    plt.close(fig)
    print(f"{os.path.basename(sys.argv[0])}: wrote {out}")


def stage_files(out_dir, name):
    """[(stage, path)] of NAME's cut CSVs, known stages first."""
    found = {}
    for path in glob.glob(os.path.join(out_dir, f"{glob.escape(name)}_*_cut.csv")):
        found[os.path.basename(path)[len(name) + 1:-len("_cut.csv")]] = path
    order = [s for s in STAGE_ORDER if s in found] + sorted(s for s in found if s not in STAGE_ORDER)
    return [(s, found[s]) for s in order]


def plot_stages(out_dir, name, title):
    files = stage_files(out_dir, name)
    if not files:
        print(f"plot_cut: no {name}_*_cut.csv in {out_dir}; no figure")
        return 1
    fig, axes = plt.subplots(1, len(files), figsize=(5.2 * len(files) + 1.0, 5.4), squeeze=False)
    face = None
    for ax, (stage, path) in zip(axes[0], files):
        cut = Cut(path)
        if len(cut.start) == 0:
            ax.axis("off")
            ax.set_title(f"{stage}: the plane meets no element", fontsize=9)
            continue
        face = draw(ax, cut, cut.outline(), None, stage, 0.2)
    save_figure(fig, axes, face, title, "element quality (shape measure)", os.path.join(out_dir, f"{name}_cut.png"))
    return 0


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    out_dir, name = sys.argv[1], sys.argv[2]
    title = sys.argv[3] if len(sys.argv) > 3 else f"{name}: planar cut"
    return plot_stages(out_dir, name, title)


if __name__ == "__main__":
    sys.exit(main())
