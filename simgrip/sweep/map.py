"""``map.png`` of a sweep: held / dropped / disagreeing over the two leading swept axes, BVP boundary on top.

Each cell of the map is one pair of values of the first two swept axes
(:attr:`SweepGrid.swept`; one axis gives a strip, none a single cell).  When
more axes are swept, a cell stands for every point with those two values:

* **held** / **dropped**: the simulation holds the workpiece (drops it, or for
  Grip III violates condition (23)) at every one of them and the BVP agrees
  (the simulation's ``feasible`` against ``bvp_feasible``);
* **mixed**: both occur, always in agreement with the BVP;
* **disagree**: at least one point where simulation and BVP disagree;
* **no verdict**: at least one point without an answer (not settled, or the
  BVP failed) and no disagreement.

The BVP's feasibility boundary is drawn along the cell borders where the
BVP's verdict changes (in a cell standing for several points: whether most
of them are BVP-feasible).
matplotlib is imported here only, when the map is drawn.
"""

from __future__ import annotations

import io

import numpy as np

from simgrip.sweep.grid import AXES
from simgrip.io import atomic_write

__all__ = ["CATEGORIES", "MAX_MAP_CELLS", "cell_categories", "check_map", "write_map"]

#: Most cells of a map: the figure is 704 x 528 pixels (6.4 x 4.8 in at 110 dpi), its axes fewer, so more cells
#: than 500 x 500 cannot be told apart; the cell arrays cost ~50 bytes a cell.
MAX_MAP_CELLS = 250_000

#: Cell categories, in the colour order of the map.
CATEGORIES = ("held", "dropped", "mixed", "disagree", "no verdict")
_COLOURS = ("#2b8a3e", "#c92a2a", "#f59f00", "#7048e8", "#adb5bd")
_LEGEND = {"held": "held (BVP agrees)", "dropped": "dropped / infeasible (BVP agrees)",
           "mixed": "both, over the other axes", "disagree": "simulation and BVP disagree",
           "no verdict": "no verdict (failed point)"}
_LABELS = {"kappa": r"$\bar\kappa_0$", "D": "D", "M": "M", "mu": r"$\mu_s$", "b": "b / l", "gamma": r"$\gamma$ / l"}


def _plot_axes(grid) -> tuple[str, ...]:
    return grid.swept[:2]


def check_map(grid) -> None:
    """``ValueError`` naming ``--no-map`` when ``grid``'s map would have more than :data:`MAX_MAP_CELLS` cells."""
    plotted = _plot_axes(grid)
    sizes = [len(grid.axes[a]) for a in plotted]
    cells = 1
    for n in sizes:
        cells *= n
    if cells > MAX_MAP_CELLS:
        what = " x ".join(f"{n} ({a})" for n, a in zip(sizes, plotted))
        raise ValueError(f"map: {what} = {cells} cells is more than map.png can show (at most {MAX_MAP_CELLS}, "
                         "the figure has 704 x 528 pixels): add --no-map (write_map=False), or sweep fewer values")


def cell_categories(grid, rows) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Category index (into :data:`CATEGORIES`) and BVP-feasible fraction per cell, and the plotted axes.

    ``rows`` is any iterable of records (read once: e.g. :func:`simgrip.sweep.store.iter_csv`
    of ``sweep.csv``); memory grows with the cells, not the points.

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


def _boundary(frac, xe, ye) -> list:
    """Cell-border segments between cells where the BVP's verdict (majority of the cell) changes."""
    feas = frac >= 0.5
    known = ~np.isnan(frac)
    segs = []
    ny, nx = frac.shape
    for i in range(ny):
        for j in range(nx - 1):
            if known[i, j] and known[i, j + 1] and feas[i, j] != feas[i, j + 1]:
                segs.append([(xe[j + 1], ye[i]), (xe[j + 1], ye[i + 1])])
    for i in range(ny - 1):
        for j in range(nx):
            if known[i, j] and known[i + 1, j] and feas[i, j] != feas[i + 1, j]:
                segs.append([(xe[j], ye[i + 1]), (xe[j + 1], ye[i + 1])])
    return segs


def write_map(path, grid, rows) -> None:
    """Draw the map of ``rows`` (the sweep's records, any order, read once) and write it to ``path`` as PNG, atomically.

    Raises ``ValueError`` (:func:`check_map`) for a grid of more than :data:`MAX_MAP_CELLS` cells.
    """
    check_map(grid)
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
    handles = [Patch(color=c, label=_LEGEND[k]) for c, k in zip(_COLOURS, CATEGORIES)]
    segments = _boundary(frac, _edges(xs), _edges(ys))
    if segments:
        from matplotlib.collections import LineCollection
        from matplotlib.lines import Line2D

        ax.add_collection(LineCollection(segments, colors="k", linewidths=2.0))
        handles.append(Line2D([], [], color="k", linewidth=2.0, label="BVP feasibility boundary"))
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
