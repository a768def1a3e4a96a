#!/usr/bin/python3
"""Figures of the ring cases, from the CSV files of bench_ring.

Usage: plot_ring.py [DIR]   (default results/ring; PNGs are written there)

  figD_1.png   the triangle ring, initial and smoothed, per degree (thesis figure D.1)
  figC_2.png   p-continuation at p = 4: (a) initial mesh, (b) after the linear
               stage, (c) initial linear sub-mesh, (d) optimized linear sub-mesh
               (thesis figure C.2)
  figD_4.png   the quadrilateral ring, initial and smoothed, p = 3 and 4
               (the counterpart of thesis figure D.4)

Elements are drawn as their curved outlines (edges sampled by bench_ring) and
filled with their element quality (shape measure, straight-sided ideal);
inverted elements are drawn with a red outline and hatched.

Needs numpy and matplotlib only (Debian's python3-matplotlib).
"""

import csv
import os
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402

CMAP = plt.get_cmap("viridis")
NORM = mcolors.Normalize(vmin=0.0, vmax=1.0)

PANEL_TITLES = {
    "a_initial": "(a) initial high-order mesh",
    "b_after_linear": "(b) after the linear sub-mesh stage",
    "c_sub_initial": "(c) initial linear sub-mesh",
    "d_sub_optimized": "(d) optimized linear sub-mesh",
}


def read_outlines(path):
    """{figure: {panel: {element: (quality, inverted, [(x, y), ...])}}} in file order."""
    figs = OrderedDict()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            panels = figs.setdefault(row["figure"], OrderedDict())
            elems = panels.setdefault(row["panel"], OrderedDict())
            e = int(row["element"])
            if e not in elems:
                elems[e] = (float(row["quality"]), int(row["inverted"]), [])
            elems[e][2].append((float(row["x"]), float(row["y"])))
    return figs


def read_nodes(path):
    nodes = defaultdict(list)
    if not os.path.exists(path):
        return nodes
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            nodes[(row["figure"], row["panel"])].append((float(row["x"]), float(row["y"]), int(row["free"])))
    return nodes


def draw_panel(ax, elems, nodes, title, show_nodes):
    polys = [pts for (_, _, pts) in elems.values()]
    quality = [q for (q, _, _) in elems.values()]
    face = PolyCollection(polys, array=quality, cmap=CMAP, norm=NORM, edgecolors="black", linewidths=0.6)
    ax.add_collection(face)
    bad = [pts for (_, inv, pts) in elems.values() if inv]
    if bad:
        ax.add_collection(PolyCollection(bad, facecolors="none", edgecolors="red", linewidths=1.4, hatch="///"))
    if show_nodes and nodes:
        xs = [x for (x, _, _) in nodes]
        ys = [y for (_, y, _) in nodes]
        ax.plot(xs, ys, ".", color="white", markersize=2.0, markeredgecolor="black", markeredgewidth=0.2)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xticks([])
    ax.set_yticks([])
    n_bad = len(bad)
    qmin = min(quality) if quality else float("nan")
    ax.set_title(f"{title}\nmin q = {qmin:.2f}, #inv = {n_bad}", fontsize=9)
    return face


def panel_title(figure, panel):
    if figure == "C2":
        return PANEL_TITLES.get(panel, panel)
    degree, _, stage = panel.partition("_")
    return f"p = {degree[1:]}, {stage}"


def plot_figure(figure, panels, nodes, out, ncols, show_nodes, suptitle):
    names = list(panels.keys())
    if figure == "C2":
        names = sorted(names)
    nrows = (len(names) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.2 * ncols, 3.3 * nrows), squeeze=False)
    mappable = None
    for k, name in enumerate(names):
        ax = axes[k // ncols][k % ncols]
        mappable = draw_panel(ax, panels[name], nodes.get((figure, name), []), panel_title(figure, name), show_nodes)
    for k in range(len(names), nrows * ncols):
        axes[k // ncols][k % ncols].axis("off")
    if mappable is not None:
        fig.colorbar(mappable, ax=axes.ravel().tolist(), shrink=0.8, label="element quality (shape, straight-sided ideal)")
    fig.suptitle(suptitle, fontsize=11)
    fig.savefig(out, dpi=150)
    plt.close(fig)
    print(f"plot_ring: wrote {out}")


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "results/ring"
    figs = read_outlines(os.path.join(out_dir, "ring_outlines.csv"))
    nodes = read_nodes(os.path.join(out_dir, "ring_nodes.csv"))
    if "D1" in figs:
        # Initial and smoothed side by side, one row per degree.
        plot_figure("D1", figs["D1"], nodes, os.path.join(out_dir, "figD_1.png"), 2, False,
                    "Ring of 24 triangles (thesis figure D.1): initial and smoothed")
    if "C2" in figs:
        plot_figure("C2", figs["C2"], nodes, os.path.join(out_dir, "figC_2.png"), 2, True,
                    "p-continuation, degree 4 (thesis figure C.2)")
    if "D4" in figs:
        plot_figure("D4", figs["D4"], nodes, os.path.join(out_dir, "figD_4.png"), 2, False,
                    "Quadrilateral ring, 4 x 2 cells (appendix D.2)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
