"""``map.png`` of a sweep: held / dropped / disagreeing over the two leading swept axes, BVP boundary on top.

Each cell of the map is one pair of values of the first two swept axes
(:attr:`SweepGrid.swept`; one axis gives a strip, none a single cell).  When
more axes are swept, a cell stands for every point with those two values:

* **held** / **dropped**: the simulation holds (drops) the workpiece at every
  one of them and the BVP agrees (the simulation's ``feasible`` against
  ``bvp_feasible``);
* **mixed**: both occur, always in agreement with the BVP;
* **disagree**: at least one point where simulation and BVP disagree;
* **no verdict**: at least one point without an answer (not settled, or the
  BVP failed) and no disagreement.

The BVP's feasibility boundary is the 0.5 contour of the fraction of
BVP-feasible points in each cell (a line between cells where it changes).
matplotlib is imported here only, when the map is drawn.
"""

from __future__ import annotations

import io

import numpy as np

from simgrip.harness.sweep_grid import AXES
from simgrip.io import atomic_write

__all__ = ["CATEGORIES", "cell_categories", "write_map"]

#: Cell categories, in the colour order of the map.
CATEGORIES = ("held", "dropped", "mixed", "disagree", "no verdict")
_COLOURS = ("#2b8a3e", "#c92a2a", "#f59f00", "#7048e8", "#adb5bd")
_LABELS = {"kappa": r"$\bar\kappa_0$", "D": "D", "M": "M", "mu": r"$\mu_s$", "b": "b / l", "gamma": r"$\gamma$ / l"}


def _plot_axes(grid) -> tuple[str, ...]:
    return grid.swept[:2]


def cell_categories(grid, rows) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Category index (into :data:`CATEGORIES`) and BVP-feasible fraction per cell, and the plotted axes.

    Arrays have shape ``(len(y values), len(x values))`` with ``x`` the first
    swept axis; with fewer swept axes the missing dimensions have length 1.
    """
    plotted = _plot_axes(grid)
    xs = grid.axes[plotted[0]] if plotted else (0.0,)
    ys = grid.axes[plotted[1]] if len(plotted) > 1 else (0.0,)
    shape = (len(ys), len(xs))
    n_pts = np.zeros(shape)
    n_held = np.zeros(shape)
    n_dis = np.zeros(shape)
    n_none = np.zeros(shape)
    bvp_sum = np.zeros(shape)
    bvp_n = np.zeros(shape)
    xi = {v: i for i, v in enumerate(xs)}
    yi = {v: i for i, v in enumerate(ys)}
    for r in rows:
        j = xi[r[plotted[0]]] if plotted else 0
        i = yi[r[plotted[1]]] if len(plotted) > 1 else 0
        n_pts[i, j] += 1
        if r["agree"] is False:
            n_dis[i, j] += 1
        elif r["agree"] is None:
            n_none[i, j] += 1
        elif r["feasible"]:
            n_held[i, j] += 1
        if r["bvp_feasible"] is not None:
            bvp_sum[i, j] += float(r["bvp_feasible"])
            bvp_n[i, j] += 1
    cat = np.full(shape, CATEGORIES.index("mixed"))
    ok = n_pts - n_dis - n_none
    cat[(n_held == ok) & (ok > 0)] = CATEGORIES.index("held")
    cat[(n_held == 0) & (ok > 0)] = CATEGORIES.index("dropped")
    cat[n_none > 0] = CATEGORIES.index("no verdict")
    cat[n_dis > 0] = CATEGORIES.index("disagree")
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(bvp_n > 0, bvp_sum / np.maximum(bvp_n, 1), np.nan)
    return cat, frac, plotted


def _edges(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if len(v) == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def write_map(path, grid, rows) -> None:
    """Draw the map of ``rows`` (the sweep's table, grid order) and write it to ``path`` as PNG, atomically."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    cat, frac, plotted = cell_categories(grid, rows)
    xs = grid.axes[plotted[0]] if plotted else (0.0,)
    ys = grid.axes[plotted[1]] if len(plotted) > 1 else (0.0,)
    fig = Figure(figsize=(6.4, 4.8), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(_edges(xs), _edges(ys), cat, cmap=ListedColormap(_COLOURS), vmin=-0.5,
                  vmax=len(CATEGORIES) - 0.5, shading="flat")
    handles = [Patch(color=c, label=k) for c, k in zip(_COLOURS, CATEGORIES)]
    fin = np.nan_to_num(frac, nan=0.5)
    if len(xs) > 1 and len(ys) > 1 and np.nanmin(frac) < 0.5 < np.nanmax(frac):
        ax.contour(xs, ys, fin, levels=[0.5], colors="k", linewidths=1.5)
        handles.append(matplotlib.lines.Line2D([], [], color="k", label="BVP feasibility boundary"))
    elif len(xs) > 1 and len(ys) == 1:
        flips = [0.5 * (xs[j] + xs[j + 1]) for j in range(len(xs) - 1) if (fin[0, j] >= 0.5) != (fin[0, j + 1] >= 0.5)]
        for x in flips:
            ax.axvline(x, color="k", linewidth=1.5)
        if flips:
            handles.append(matplotlib.lines.Line2D([], [], color="k", label="BVP feasibility boundary"))
    ax.set_xlabel(_LABELS[plotted[0]] if plotted else "")
    ax.set_ylabel(_LABELS[plotted[1]] if len(plotted) > 1 else "")
    if len(plotted) < 2:
        ax.set_yticks([])
    if not plotted:
        ax.set_xticks([])
    fixed = ", ".join(f"{a}={grid.axes[a][0]:g}" for a in AXES if len(grid.axes[a]) == 1)
    more = [a for a in grid.swept[2:]]
    title = f"Grip {grid.grip}, n = {grid.links} links ({grid.method})"
    sub = fixed + (f"; each cell over {', '.join(more)}" if more else "")
    ax.set_title(f"{title}\n{sub}", fontsize=9)
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())
