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
Drawn with Pillow (:mod:`simgrip.sweep.picture`), not matplotlib: the
picture is cells, a frame, ticks and text, and matplotlib's import and first
draw cost ~0.7 s, a sixth of a 300-point sweep at 32 links (issue 19).
"""

from __future__ import annotations

import io

import numpy as np

from simgrip.sweep.grid import AXES
from simgrip.io import atomic_write
from simgrip.sweep.picture import Label

__all__ = ["CATEGORIES", "MAX_MAP_CELLS", "SIZE", "cell_categories", "check_map", "map_layout", "write_map"]

#: Most cells of a map: the figure is 704 x 528 pixels (6.4 x 4.8 in at 110 dpi), its axes fewer, so more cells
#: than 500 x 500 cannot be told apart; the cell arrays cost ~50 bytes a cell.
MAX_MAP_CELLS = 250_000

#: Cell categories, in the colour order of the map.
CATEGORIES = ("held", "dropped", "mixed", "disagree", "no verdict")
_COLOURS = ("#2b8a3e", "#c92a2a", "#f59f00", "#7048e8", "#adb5bd")
_LEGEND = {"held": "held (BVP agrees)", "dropped": "dropped / infeasible (BVP agrees)",
           "mixed": "both, over the other axes", "disagree": "simulation and BVP disagree",
           "no verdict": "no verdict (failed point)"}
_LABELS = {"kappa": Label("\u03ba", bar=True, sub="0"), "D": "D", "M": "M", "mu": Label("\u03bc", sub="s"), "b": "b / l",
           "gamma": "\u03b3 / l"}
_PAD = 6


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


def map_layout(grid) -> dict:
    """Where :func:`write_map` draws ``grid``'s map, in pixels of the :data:`SIZE` image (x right, y down).

    ``axes``: ``(left, top, right, bottom)`` of the plotting area; ``x_edges`` / ``y_edges``: the cell borders
    of the plotted axes (:func:`cell_categories`' columns and rows; ``y_edges`` from the bottom up);
    ``to_px(x, y)``: a point in the axes' values to pixels.
    """
    from simgrip.sweep.picture import nice_ticks, text_size, tick_text

    plotted = _plot_axes(grid)
    xe = _edges(grid.axes[plotted[0]] if plotted else (0.0,))
    ye = _edges(grid.axes[plotted[1]] if len(plotted) > 1 else (0.0,))
    xt = nice_ticks(xe[0], xe[-1]) if plotted else []
    yt = nice_ticks(ye[0], ye[-1]) if len(plotted) > 1 else []
    legend_w = _PAD + _PATCH[0] + _PAD + max(text_size(t, _LEGEND_PX)[0] for t in _legend_texts()) + _PAD
    ytick_w = max((text_size(t, _TICK_PX)[0] for t in tick_text(yt)), default=0)
    tick_h = text_size("0", _TICK_PX)[1]
    title_h = 2 * text_size("Gg", _TITLE_PX)[1]
    left = _MARGIN + (text_size(_label(plotted, 1), _LABEL_PX)[1] + _GAP if len(plotted) > 1 else 0) \
        + (ytick_w + _TICK + _GAP if yt else _GAP)
    right = SIZE[0] - _MARGIN - legend_w - 2 * _GAP
    top = _MARGIN + title_h + _GAP
    bottom = SIZE[1] - _MARGIN - (text_size(_label(plotted, 0), _LABEL_PX)[1] + _GAP if plotted else 0) \
        - (tick_h + _TICK + _GAP if xt else _GAP)
    sx = (right - left) / (xe[-1] - xe[0])
    sy = (bottom - top) / (ye[-1] - ye[0])

    def to_px(x, y):
        return left + (np.asarray(x, dtype=float) - xe[0]) * sx, bottom - (np.asarray(y, dtype=float) - ye[0]) * sy

    return {"axes": (left, top, right, bottom), "x_edges": xe, "y_edges": ye, "x_ticks": xt, "y_ticks": yt,
            "legend_width": legend_w, "to_px": to_px, "plotted": plotted}


#: The map's size [px] (matplotlib's default 6.4 x 4.8 in at 110 dpi, the size it had when matplotlib drew it).
SIZE = (704, 528)
_MARGIN, _GAP, _TICK = 8, 4, 4
_PATCH = (22, 11)
_TITLE_PX, _LABEL_PX, _TICK_PX, _LEGEND_PX = 14, 15, 13, 11
_BOUNDARY = "BVP feasibility boundary"


def _legend_texts() -> list:
    return [_LEGEND[k] for k in CATEGORIES] + [_BOUNDARY]


def _label(plotted, i):
    return _LABELS[plotted[i]] if len(plotted) > i else ""


def _rgb(hex_colour: str) -> tuple:
    return tuple(int(hex_colour[k:k + 2], 16) for k in (1, 3, 5))


def write_map(path, grid, rows) -> None:
    """Draw the map of ``rows`` (the sweep's records, any order, read once) and write it to ``path`` as PNG, atomically.

    Raises ``ValueError`` (:func:`check_map`) for a grid of more than :data:`MAX_MAP_CELLS` cells.
    """
    check_map(grid)
    from PIL import Image, ImageDraw

    from simgrip.sweep.picture import draw_text, text_size, tick_text

    cat, frac, plotted = cell_categories(grid, rows)
    lay = map_layout(grid)
    left, top, right, bottom = lay["axes"]
    xe, ye, to_px = lay["x_edges"], lay["y_edges"], lay["to_px"]
    img = np.full((SIZE[1], SIZE[0], 3), 255, dtype=np.uint8)
    # the cells: each pixel of the plotting area takes the colour of the cell its centre is in
    px_x, _ = to_px(xe, ye[0])
    _, px_y = to_px(xe[0], ye)
    cols = np.clip(np.searchsorted(px_x, np.arange(left, right) + 0.5) - 1, 0, len(xe) - 2)
    rows_ = np.clip(np.searchsorted(-px_y, -(np.arange(top, bottom) + 0.5)) - 1, 0, len(ye) - 2)
    palette = np.array([_rgb(c) for c in _COLOURS], dtype=np.uint8)
    img[top:bottom, left:right] = palette[cat[rows_[:, None], cols[None, :]]]
    # the BVP boundary, 2 px wide on the cell borders where its verdict changes
    segments = _boundary(frac, xe, ye)
    for (x0, y0), (x1, y1) in segments:
        xs, ys = to_px((x0, x1), (y0, y1))
        j0, j1 = int(round(float(min(xs)))) - 1, int(round(float(max(xs)))) + 1
        i0, i1 = int(round(float(min(ys)))) - 1, int(round(float(max(ys)))) + 1
        img[max(i0, top):min(i1, bottom), max(j0, left):min(j1, right)] = 0
    im = Image.fromarray(img)
    draw = ImageDraw.Draw(im)
    draw.rectangle([left - 1, top - 1, right, bottom], outline=(0, 0, 0), width=1)
    tick_h = text_size("0", _TICK_PX)[1]
    for v, s in zip(lay["x_ticks"], tick_text(lay["x_ticks"])):
        x = int(round(float(to_px(v, ye[0])[0])))
        draw.line([(x, bottom), (x, bottom + _TICK)], fill=(0, 0, 0))
        draw_text(draw, (x - text_size(s, _TICK_PX)[0] / 2, bottom + _TICK + _GAP // 2), s, _TICK_PX)
    for v, s in zip(lay["y_ticks"], tick_text(lay["y_ticks"])):
        y = int(round(float(to_px(xe[0], v)[1])))
        draw.line([(left - 1 - _TICK, y), (left - 1, y)], fill=(0, 0, 0))
        w, h = text_size(s, _TICK_PX)
        draw_text(draw, (left - 1 - _TICK - _GAP - w, y - h / 2), s, _TICK_PX)
    if plotted:
        lab = _label(plotted, 0)
        w, _ = text_size(lab, _LABEL_PX)
        y = bottom + (_TICK + _GAP + tick_h if lay["x_ticks"] else 0) + _GAP
        draw_text(draw, ((left + right - w) / 2, y), lab, _LABEL_PX)
    if len(plotted) > 1:  # the y label, turned a quarter anticlockwise
        lab = _label(plotted, 1)
        w, h = text_size(lab, _LABEL_PX)
        tile = Image.new("RGB", (w + 2, h + 2), (255, 255, 255))
        draw_text(ImageDraw.Draw(tile), (1, 1), lab, _LABEL_PX)
        tile = tile.rotate(90, expand=True)
        im.paste(tile, (_MARGIN, int(round((top + bottom - tile.size[1]) / 2))))
    fixed = ", ".join(f"{a}={grid.axes[a][0]:g}" for a in AXES if len(grid.axes[a]) == 1)
    more = [a for a in grid.swept[2:]]
    title = f"Grip {grid.grip}, n = {grid.links} links ({grid.method})"
    sub = fixed + (f"; each cell over {', '.join(more)}" if more else "")
    y = _MARGIN
    for line in (title, sub):
        w, h = text_size(line, _TITLE_PX)
        draw_text(draw, ((left + right - w) / 2, y), line, _TITLE_PX)
        y += h
    # the legend, right of the plotting area, its top at the area's top
    x0 = right + 2 * _GAP
    entries = [(c, _LEGEND[k]) for c, k in zip(_COLOURS, CATEGORIES)] + ([(None, _BOUNDARY)] if segments else [])
    row_h = max(_PATCH[1], text_size("Gg", _LEGEND_PX)[1]) + _GAP
    draw.rectangle([x0, top, x0 + lay["legend_width"], top + _PAD + len(entries) * row_h + _PAD - _GAP],
                   fill=(255, 255, 255), outline=(204, 204, 204))
    y = top + _PAD
    for colour, text in entries:
        cy = y + row_h // 2 - _GAP // 2
        if colour is None:
            draw.line([(x0 + _PAD, cy), (x0 + _PAD + _PATCH[0], cy)], fill=(0, 0, 0), width=2)
        else:
            draw.rectangle([x0 + _PAD, cy - _PATCH[1] // 2, x0 + _PAD + _PATCH[0], cy + _PATCH[1] // 2],
                           fill=_rgb(colour))
        th = text_size(text, _LEGEND_PX)[1]
        draw_text(draw, (x0 + 2 * _PAD + _PATCH[0], cy - th / 2), text, _LEGEND_PX)
        y += row_h
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())
