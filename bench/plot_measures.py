#!/usr/bin/python3
"""Figures of the quality-measure studies, from the CSV files of bench_measures.

Usage: plot_measures.py [DIR]   (default results/measures; PNGs are written there)

  fig3_4.png  configurations of table 3.1 and quality along the sweeps (thesis figure 3.4)
  fig3_5.png  level sets, cubic triangle, equispaced nodes (figure 3.5)
  fig3_6.png  level sets, cubic triangle, warp & blend nodes (figure 3.6)
  fig4_5.png  linear triangle, x2 = (x, 0): distortion and quality, plain and regularized (figure 4.5)
  fig4_6.png  the same with x2 free in the plane (figure 4.6)
  figD_3.png  level sets, quadrilateral of degree 2 (figure D.3)

Needs numpy and matplotlib only (Debian's python3-matplotlib).
"""

import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

FREE_NODES = ["vertex", "edge", "face"]
LOCATION_COLORS = {1: "tab:blue", 2: "tab:red", 3: "tab:green"}
QUALITY_LEVELS = np.linspace(0.0, 1.0, 11)


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
        column = cols[key]
        mask &= (column == value) if column.dtype.kind in "US" else np.isclose(column, value)
    return {k: v[mask] for k, v in cols.items()}


def grid(cols, value):
    """Reshape scattered grid rows (x fastest) into 2D arrays X, Y, V."""
    xs, ys = np.unique(cols["x"]), np.unique(cols["y"])
    shape = (len(ys), len(xs))
    return (cols["x"].reshape(shape), cols["y"].reshape(shape), cols[value].reshape(shape))


def draw_element(ax, elements, figure, node_set, free_node, location, color="k", lw=1.2, nodes=True, label=None,
                 lines_alpha=0.0):
    """The curved element: boundary, images of the reference grid lines (they
    cross where the element folds), nodes and the free node (star)."""
    e = select(elements, figure=figure, node_set=node_set, free_node=free_node, location=location)
    b = select(e, kind="boundary")
    if len(b["x"]) == 0:
        return
    if lines_alpha > 0:
        lines = select(e, kind="line")
        for c in np.unique(lines["curve"]):
            seg = select(lines, curve=c)
            ax.plot(seg["x"], seg["y"], color=color, lw=0.5, alpha=lines_alpha)
    ax.plot(b["x"], b["y"], color=color, lw=lw, label=label)
    if nodes:
        n = select(e, kind="node")
        ax.plot(n["x"], n["y"], "o", color=color, ms=3)
        f = select(e, kind="free")
        ax.plot(f["x"], f["y"], "*", color=color if color != "k" else "tab:red", ms=10, mec="k", mew=0.5)


def figure_3_4(d, elements):
    curves = read_csv(os.path.join(d, "fig3_4_curves.csv"))
    configs = read_csv(os.path.join(d, "fig3_4_configs.csv"))
    labels = {"vertex": r"vertex node $x_3$ (moves along x)", "edge": r"edge node $x_4$ (moves along y)",
              "face": r"face node $x_{10}$ (moves along y)"}
    fig, axes = plt.subplots(2, 3, figsize=(15, 10), gridspec_kw={"height_ratios": [1.25, 1]})
    for c, free in enumerate(FREE_NODES):
        ax = axes[0, c]
        for loc in (1, 3, 2):  # the ideal (red) on top
            q = select(configs, node_set="equispaced", free_node=free, location=loc)
            draw_element(ax, elements, "fig3_4", "equispaced", free, loc, color=LOCATION_COLORS[loc],
                         label=f"location {loc}: q_shape={q['shape'][0]:.3f}, q_oddy={q['oddy'][0]:.3f}",
                         lines_alpha=0.0 if loc == 2 else 0.35)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"({'abc'[c]}) {labels[free]}")
        handles, names = ax.get_legend_handles_labels()
        order = sorted(range(len(names)), key=lambda k: names[k])
        ax.legend([handles[k] for k in order], [names[k] for k in order], fontsize=7, loc="upper center",
                  bbox_to_anchor=(0.5, -0.06), ncol=1, frameon=False)
        ax.grid(alpha=0.3)

        ax = axes[1, c]
        for node_set, style in (("equispaced", "-"), ("warp_blend", ":")):
            s = select(curves, node_set=node_set, free_node=free)
            ax.plot(s["position"], s["shape"], style, color="tab:blue", label=f"shape ({node_set})")
            ax.plot(s["position"], s["oddy"], style, color="tab:orange", label=f"Oddy ({node_set})")
        for loc in (1, 2, 3):
            q = select(configs, node_set="equispaced", free_node=free, location=loc)
            pos = q["x"][0] if free == "vertex" else q["y"][0]
            ax.axvline(pos, color=LOCATION_COLORS[loc], lw=0.8, ls="--")
        ax.set_xlabel("x" if free == "vertex" else "y")
        ax.set_ylabel("quality")
        ax.set_ylim(-0.02, 1.05)
        ax.set_title(f"({'def'[c]}) quality vs position")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle("Figure 3.4: cubic triangle, equispaced nodes, one free node (thin lines: images of reference "
                 "grid lines; dotted curves: warp & blend nodes)")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "fig3_4.png"), dpi=110)
    plt.close(fig)


def level_set_figure(d, elements, name, title):
    path = os.path.join(d, f"{name}_levelsets.csv")
    if not os.path.exists(path):
        return
    data = read_csv(path)
    node_set = select(elements, figure=name)["node_set"][0]
    fig, axes = plt.subplots(2, 3, figsize=(17, 9.5), gridspec_kw={"width_ratios": [1.6, 1, 1]})
    cmap = plt.get_cmap("viridis").copy()
    for c, free in enumerate(FREE_NODES):
        s = select(data, free_node=free)
        for r, measure in enumerate(("shape", "oddy")):
            ax = axes[r, c]
            X, Y, Q = grid(s, measure)
            ax.set_facecolor("0.85")  # infeasible region (q = 0)
            Qm = np.ma.masked_where(Q <= 0.0, Q)
            cs = ax.contourf(X, Y, Qm, levels=QUALITY_LEVELS, cmap=cmap)
            ax.contour(X, Y, (Q > 0).astype(float), levels=[0.5], colors="k", linewidths=1.0)
            draw_element(ax, elements, name, node_set, free, 0, color="w", lw=2.0, nodes=False)
            draw_element(ax, elements, name, node_set, free, 0, color="k", lw=0.8)
            ax.set_aspect("equal")
            ax.set_xlim(X.min(), X.max())
            ax.set_ylim(Y.min(), Y.max())
            ax.set_title(f"({'abcdef'[3 * r + c]}) {measure} quality, free {free} node")
            fig.colorbar(cs, ax=ax, shrink=0.8)
    fig.suptitle(title + " (gray: q = 0; black line: boundary of the feasible region)")
    fig.tight_layout()
    fig.savefig(os.path.join(d, f"{name}.png"), dpi=110)
    plt.close(fig)


def figure_4_5(d):
    data = read_csv(os.path.join(d, "fig4_5.csv"))
    x = data["x"]
    h = math.sqrt(3.0) / 2.0
    fig, axes = plt.subplots(3, 2, figsize=(12, 12))
    panels = [
        ("(a) distortion $\\eta$ (eq 3.2 with $|\\sigma|$)", data["eta_abs"], False, (0, 10)),
        ("(b) regularized distortion $\\eta_\\delta$, $\\delta = 0.05$ (finite at x = 0)", data["eta_reg"], False,
         (0, 30)),
        ("(c) distortion, log scale", data["eta_abs"], True, None),
        ("(d) regularized distortion, log scale", data["eta_reg"], True, None),
        ("(e) quality $q = 1/\\eta$ ($\\sigma_0$: 0 for x <= 0; dashed: $|\\sigma|$)", data["q_clamped"], False,
         (-0.02, 1.05)),
        ("(f) regularized quality $1/\\eta_\\delta$", data["q_reg"], False, (-0.02, 1.05)),
    ]
    for k, (title, y, log, ylim) in enumerate(panels):
        ax = axes[k // 2, k % 2]
        yy = np.where(np.isfinite(y), y, np.nan)
        ax.plot(x, yy, color="tab:blue")
        if k == 4:
            ax.plot(x, data["q_abs"], "--", color="0.5", lw=0.8)
        if log:
            ax.set_yscale("log")
        if ylim:
            ax.set_ylim(*ylim)
        ideal = float(np.interp(h, x, yy)) if k in (1, 3, 5) else 1.0
        ax.plot([h], [ideal], "o", color="tab:red", zorder=5)
        if k in (1, 3):
            at0 = float(np.interp(0.0, x, yy))
            ax.plot([0.0], [at0], "s", color="k", ms=4, zorder=5)
            ax.annotate(f"$\\eta_\\delta(0) = {at0:.1f}$", (0.0, at0), textcoords="offset points", xytext=(8, 4),
                        fontsize=8)
        if k in (0, 2):
            ax.plot([-h], [ideal], "o", mfc="none", mec="tab:red", zorder=5)
            ax.axvline(0.0, color="0.6", lw=0.8, ls=":")
        ax.set_xlabel("x")
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    fig.suptitle("Figure 4.5: linear triangle x0=(0,0.5), x1=(0,-0.5), x2=(x,0), equilateral ideal "
                 "(red dot: ideal, x = sqrt(3)/2)")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "fig4_5.png"), dpi=110)
    plt.close(fig)


def figure_4_6(d):
    data = read_csv(os.path.join(d, "fig4_6.csv"))
    h = math.sqrt(3.0) / 2.0
    fig, axes = plt.subplots(2, 2, figsize=(12, 11))
    panels = [
        ("(a) distortion $\\eta$ ($|\\sigma|$), log$_{10}$", "eta_abs", True),
        ("(b) regularized distortion $\\eta_\\delta$, log$_{10}$", "eta_reg", True),
        ("(c) quality ($\\sigma_0$)", "q_clamped", False),
        ("(d) regularized quality", "q_reg", False),
    ]
    for k, (title, col, log) in enumerate(panels):
        ax = axes[k // 2, k % 2]
        X, Y, V = grid(data, col)
        if log:
            V = np.log10(np.where(np.isfinite(V), V, np.nan))
            levels = np.linspace(0.0, 2.0, 21)
            cs = ax.contourf(X, Y, np.clip(V, None, 2.0), levels=levels, cmap="viridis_r")
        else:
            ax.set_facecolor("0.85")  # q = 0
            cs = ax.contourf(X, Y, np.ma.masked_where(V <= 0.0, V), levels=QUALITY_LEVELS, cmap="viridis")
        fig.colorbar(cs, ax=ax, shrink=0.85)
        ax.plot([0, 0], [0.5, -0.5], "ko-", ms=4)
        ax.plot([h], [0], "o", color="tab:red")
        if k in (0, 2):
            ax.plot([-h], [0], "o", mfc="none", mec="tab:red")
        ax.set_aspect("equal")
        ax.set_title(title)
    fig.suptitle("Figure 4.6: x2 free in the plane (black: fixed edge x0 x1; red: ideal positions)")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "fig4_6.png"), dpi=110)
    plt.close(fig)


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else os.path.join("results", "measures")
    elements = read_csv(os.path.join(d, "elements.csv"))
    figure_3_4(d, elements)
    level_set_figure(d, elements, "fig3_5", "Figure 3.5: cubic triangle, equispaced nodes")
    level_set_figure(d, elements, "fig3_6", "Figure 3.6: cubic triangle, warp & blend nodes")
    level_set_figure(d, elements, "figD_3", "Figure D.3: quadrilateral of degree 2")
    figure_4_5(d)
    figure_4_6(d)
    print("plot_measures: wrote fig3_4.png fig3_5.png fig3_6.png fig4_5.png fig4_6.png figD_3.png in " + d)


if __name__ == "__main__":
    main()
