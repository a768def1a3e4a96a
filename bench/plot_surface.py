#!/usr/bin/python3
"""Figures of the surface studies, from the CSV files of bench_surface.

Usage: plot_surface.py [DIR]   (default results/surface; PNGs are written there)

Appendix F (appendixF_levelsets.csv, appendixF_elements.csv):
  appendixF_<surface>_<family>.png     the surface around the element colored by the
                                       element quality when the free node sits at each
                                       point, black line: boundary of the feasible
                                       region; rows shape / Oddy, columns vertex / edge /
                                       face (the layout of figures F.1-F.4)
  appendixF_<surface>_<family>_uv.png  the same in the parameter plane (u, v), with the
                                       element's parameter nodes and the free node

Table 5.2 / figure 5.8 (table52_meshes.csv):
  table52.png                          rows Sigma_1 / Sigma_2, columns phi^1 initial /
                                       optimized, phi^2 initial / optimized; each panel the
                                       parametric mesh (left) and the physical mesh (right),
                                       elements colored by their shape quality

Needs numpy and matplotlib only (Debian's python3-matplotlib).
"""

import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

FREE_NODES = ["vertex", "edge", "face"]
MEASURES = [("shape", "shape"), ("oddy", "Oddy")]
FIGURES = {("cylinder", "triangle"): "F.1", ("cylinder", "quadrilateral"): "F.2",
           ("paraboloid", "triangle"): "F.3", ("paraboloid", "quadrilateral"): "F.4"}
CMAP = plt.get_cmap("viridis")


def read_csv(path):
    """Columns of a CSV file as numpy arrays (float where every entry parses)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    cols = {}
    for k, name in enumerate(header):
        values = [r[k] for r in body]
        try:
            cols[name] = np.array([float(v) for v in values])
        except ValueError:
            cols[name] = np.array(values)
    return cols


def select(cols, **conditions):
    mask = np.ones(len(next(iter(cols.values()))), dtype=bool)
    for key, value in conditions.items():
        mask &= cols[key] == value
    return {k: v[mask] for k, v in cols.items()}


def grid(cols, name):
    """A column reshaped to the (j, i) grid (i fastest)."""
    ni, nj = int(cols["i"].max()) + 1, int(cols["j"].max()) + 1
    order = np.lexsort((cols["i"], cols["j"]))
    return cols[name][order].reshape(nj, ni)


def bilinear(a, jj, ii):
    """a sampled at fractional grid indices (jj, ii)."""
    j0 = np.clip(np.floor(jj).astype(int), 0, a.shape[0] - 2)
    i0 = np.clip(np.floor(ii).astype(int), 0, a.shape[1] - 2)
    tj, ti = jj - j0, ii - i0
    return ((1 - tj) * (1 - ti) * a[j0, i0] + (1 - tj) * ti * a[j0, i0 + 1] + tj * (1 - ti) * a[j0 + 1, i0]
            + tj * ti * a[j0 + 1, i0 + 1])


def feasible_boundary(mask):
    """Segments of the boundary of {mask} in fractional grid indices (jj, ii)."""
    fig = plt.figure()
    ax = fig.add_subplot()
    cs = ax.contour(np.arange(mask.shape[1]), np.arange(mask.shape[0]), mask.astype(float), levels=[0.5])
    segs = [s for s in cs.allsegs[0] if len(s) > 1]
    plt.close(fig)
    return [(s[:, 1], s[:, 0]) for s in segs]


def draw_element_3d(ax, elements, free_node):
    e = select(elements, free_node=free_node)
    b = select(e, kind="boundary")
    ax.plot(b["x"], b["y"], b["z"], color="white", lw=1.6, zorder=10)
    n = select(e, kind="node")
    ax.scatter(n["x"], n["y"], n["z"], color="white", s=6, depthshade=False, zorder=11)
    f = select(e, kind="free")
    ax.scatter(f["x"], f["y"], f["z"], color="red", marker="*", s=60, depthshade=False, zorder=12)


def draw_element_uv(ax, elements, free_node):
    e = select(elements, free_node=free_node)
    b = select(e, kind="boundary")
    ax.plot(b["u"], b["v"], color="white", lw=1.4)
    n = select(e, kind="node")
    ax.plot(n["u"], n["v"], "o", color="white", ms=2.5)
    f = select(e, kind="free")
    ax.plot(f["u"], f["v"], "*", color="red", ms=9, mec="k", mew=0.5)


def plot_appendix_f(directory):
    path = os.path.join(directory, "appendixF_levelsets.csv")
    if not os.path.exists(path):
        return
    levels = read_csv(path)
    elements = read_csv(os.path.join(directory, "appendixF_elements.csv"))
    norm = matplotlib.colors.Normalize(0.0, 1.0)
    for surface in np.unique(levels["surface"]):
        for family in np.unique(levels["family"]):
            data = select(levels, surface=surface, family=family)
            if len(data["u"]) == 0:
                continue
            els = select(elements, surface=surface, family=family)
            title = "figure %s analogue: degree-3 %s on the %s" % (
                FIGURES.get((surface, family), "?"), family, "cylinder" if surface == "cylinder" else
                "hyperbolic paraboloid")
            fig3d = plt.figure(figsize=(15, 9.5))
            fig2d, axes2d = plt.subplots(2, 3, figsize=(14, 8.5), constrained_layout=True)
            for col, free in enumerate(FREE_NODES):
                d = select(data, free_node=free)
                if len(d["u"]) == 0:
                    continue
                X, Y, Z = grid(d, "x"), grid(d, "y"), grid(d, "z")
                U, V = grid(d, "u"), grid(d, "v")
                for row, (key, label) in enumerate(MEASURES):
                    Q = grid(d, key)
                    mask = Q > 0
                    segs = feasible_boundary(mask)
                    # 3D: the surface colored by the quality of the element with the free node there.
                    # computed_zorder=False: the element and the feasible-region boundary
                    # are drawn over the surface (matplotlib's depth sorting would hide them).
                    ax = fig3d.add_subplot(2, 3, 3 * row + col + 1, projection="3d", computed_zorder=False)
                    step = max(1, X.shape[0] // 50)
                    ax.plot_surface(X[::step, ::step], Y[::step, ::step], Z[::step, ::step],
                                    facecolors=CMAP(norm(Q[::step, ::step])), shade=False, linewidth=0,
                                    antialiased=False, rstride=1, cstride=1)
                    for jj, ii in segs:
                        ax.plot(bilinear(X, jj, ii), bilinear(Y, jj, ii), bilinear(Z, jj, ii), color="k", lw=1.3, zorder=9)
                    draw_element_3d(ax, els, free)
                    ax.set_title("%s quality, free %s node" % (label, free), fontsize=10)
                    ax.set_box_aspect((np.ptp(X), np.ptp(Y), max(np.ptp(Z), 0.3 * max(np.ptp(X), np.ptp(Y)))))
                    ax.tick_params(labelsize=7)
                    # Parameter plane.
                    a2 = axes2d[row, col]
                    cf = a2.contourf(U, V, Q, levels=np.linspace(0, 1, 21), cmap=CMAP, vmin=0, vmax=1)
                    for jj, ii in segs:
                        a2.plot(bilinear(U, jj, ii), bilinear(V, jj, ii), color="k", lw=1.2)
                    draw_element_uv(a2, els, free)
                    a2.set_aspect("equal")
                    a2.set_xlabel("u")
                    a2.set_ylabel("v")
                    a2.set_title("%s quality, free %s node" % (label, free), fontsize=10)
            fig3d.suptitle(title + " (black: boundary of the feasible region)")
            sm = plt.cm.ScalarMappable(norm=norm, cmap=CMAP)
            fig3d.colorbar(sm, ax=fig3d.axes, shrink=0.6, label="element quality")
            out = os.path.join(directory, "appendixF_%s_%s.png" % (surface, family))
            fig3d.savefig(out, dpi=110)
            plt.close(fig3d)
            fig2d.suptitle(title + ", parameter plane")
            fig2d.colorbar(cf, ax=axes2d, shrink=0.6, label="element quality")
            out_uv = os.path.join(directory, "appendixF_%s_%s_uv.png" % (surface, family))
            fig2d.savefig(out_uv, dpi=110)
            plt.close(fig2d)
            print("wrote", out, "and", out_uv)


def plot_table52(directory):
    path = os.path.join(directory, "table52_meshes.csv")
    if not os.path.exists(path):
        return
    from matplotlib.collections import PolyCollection
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    data = read_csv(path)
    norm = matplotlib.colors.Normalize(0.0, 1.0)
    fig = plt.figure(figsize=(20, 10.5))
    letters = iter("abcdefghijklmnop")
    for row, surface in enumerate(["Sigma1", "Sigma2"]):
        col = 0
        for k in (1, 2):
            for stage in ("initial", "optimized"):
                d = select(data, surface=surface, k=float(k), stage=stage)
                if len(d["u"]) == 0:
                    continue
                elements = np.unique(d["element"])
                polys_uv, polys_x, colors = [], [], []
                for e in elements:
                    m = d["element"] == e
                    order = np.argsort(d["index"][m])
                    polys_uv.append(np.column_stack([d["u"][m][order], d["v"][m][order]]))
                    polys_x.append(np.column_stack([d["x"][m][order], d["y"][m][order], d["z"][m][order]]))
                    colors.append(CMAP(norm(d["quality"][m][0])))
                ax = fig.add_subplot(2, 8, 8 * row + col + 1)
                ax.add_collection(PolyCollection(polys_uv, facecolors=colors, edgecolors="k", linewidths=0.3))
                ax.set_xlim(-1.05, 1.05)
                ax.set_ylim(-1.05, 1.05)
                ax.set_aspect("equal")
                ax.set_title("(%s) %s, phi^%d, %s\nparametric" % (next(letters), surface, k, stage), fontsize=8)
                ax.tick_params(labelsize=6)
                if surface == "Sigma1":
                    ax2 = fig.add_subplot(2, 8, 8 * row + col + 2)
                    ax2.add_collection(PolyCollection([p[:, :2] for p in polys_x], facecolors=colors, edgecolors="k",
                                                      linewidths=0.3))
                    ax2.set_xlim(-1.05, 1.05)
                    ax2.set_ylim(-1.05, 1.05)
                    ax2.set_aspect("equal")
                else:
                    ax2 = fig.add_subplot(2, 8, 8 * row + col + 2, projection="3d")
                    ax2.add_collection3d(Poly3DCollection(polys_x, facecolors=colors, edgecolors="k", linewidths=0.2))
                    ax2.set_xlim(-1, 1)
                    ax2.set_ylim(-1, 1)
                    ax2.set_zlim(-1, 1)
                    ax2.view_init(elev=35, azim=-60)
                ax2.set_title("(%s) physical" % next(letters), fontsize=8)
                ax2.tick_params(labelsize=6)
                col += 2
    sm = plt.cm.ScalarMappable(norm=norm, cmap=CMAP)
    fig.colorbar(sm, ax=fig.axes, shrink=0.5, label="element shape quality")
    fig.suptitle("figure 5.8 analogue: degree-3 meshes on Sigma_1 and Sigma_2 through phi^1 and phi^2, "
                 "initial and optimized")
    out = os.path.join(directory, "table52.png")
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print("wrote", out)


def main():
    directory = sys.argv[1] if len(sys.argv) > 1 else "results/surface"
    plot_appendix_f(directory)
    plot_table52(directory)


if __name__ == "__main__":
    main()
