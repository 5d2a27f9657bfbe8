"""map.png drawn without matplotlib (issue 19): every cell in its category's colour, the BVP boundary where the
BVP's verdict changes, the picture's size; the tick choice.  Synthetic records, no simulation: fast."""

import numpy as np
import pytest
from PIL import Image

from simgrip.sweep.grid import make_grid
from simgrip.sweep.map import _COLOURS, CATEGORIES, SIZE, map_layout, write_map
from simgrip.sweep.picture import nice_ticks, tick_text


def _rgb(c):
    return tuple(int(c[k:k + 2], 16) for k in (1, 3, 5))


def _rows(grid, verdict):
    """A record per point: ``verdict(point) -> (feasible, bvp_feasible)``; ``agree`` from them (None if either is)."""
    out = []
    for i in range(grid.size):
        p = grid.point(i)
        f, bf = verdict(p)
        out.append({**p.values(), "feasible": f, "bvp_feasible": bf,
                    "agree": None if f is None or bf is None else f == bf})
    return out


def _pixel(img, lay, x, y):
    px, py = lay["to_px"](x, y)
    return tuple(int(v) for v in img[int(py), int(px)])


def test_cells_take_their_categories_colours_and_the_boundary_is_drawn(tmp_path):
    grid = make_grid("II", kappa=["1", "4", "4"], mu=["0.5", "1.5", "3"], links=4)

    def verdict(p):
        if p.kappa == 1.0 and p.mu == 1.5:
            return None, True  # no verdict
        if p.kappa == 2.0 and p.mu == 1.0:
            return False, True  # disagree
        held = p.kappa >= 3.0
        return held, held

    path = tmp_path / "map.png"
    write_map(path, grid, _rows(grid, verdict))
    img = np.asarray(Image.open(path).convert("RGB"))
    assert img.shape == (SIZE[1], SIZE[0], 3)
    lay = map_layout(grid)
    want = {(1.0, 1.5): "no verdict", (2.0, 1.0): "disagree", (3.0, 0.5): "held", (4.0, 1.5): "held",
            (1.0, 0.5): "dropped", (2.0, 0.5): "dropped"}
    for (k, mu), cat in want.items():
        assert _pixel(img, lay, k, mu) == _rgb(_COLOURS[CATEGORIES.index(cat)]), (k, mu, cat)
    # the BVP turns feasible between kappa 2 and 3 (rows mu = 0.5 and 1.5; on the mu = 1.0 row kappa 2's BVP
    # is feasible already, the disagreeing point): the border at 2.5 is black there, not on the middle row
    for mu in (0.5, 1.5):
        assert _pixel(img, lay, 2.5, mu) == (0, 0, 0)
    assert _pixel(img, lay, 2.5, 1.0) != (0, 0, 0)
    # no boundary between kappa 1 and 2 (both BVP-infeasible on the mu = 0.5 row)
    assert _pixel(img, lay, 1.5, 0.5) == _rgb(_COLOURS[CATEGORIES.index("dropped")])


@pytest.mark.parametrize("kw", [dict(kappa=["-7", "-3", "5"]), dict(kappa=["-5"])])
def test_a_strip_and_a_single_cell(tmp_path, kw):
    grid = make_grid("I", links=4, **kw)
    path = tmp_path / "map.png"
    write_map(path, grid, _rows(grid, lambda p: (True, True)))
    img = np.asarray(Image.open(path).convert("RGB"))
    assert img.shape == (SIZE[1], SIZE[0], 3)
    lay = map_layout(grid)
    left, top, right, bottom = lay["axes"]
    held = _rgb(_COLOURS[CATEGORIES.index("held")])
    assert tuple(img[(top + bottom) // 2, (left + right) // 2]) == held
    assert tuple(img[top + 1, left + 1]) == held and tuple(img[bottom - 1, right - 2]) == held  # the whole area
    assert tuple(img[top + 1, right + 3]) == (255, 255, 255)  # nothing drawn right of the frame but the legend


def test_ticks():
    assert nice_ticks(-7.0069, -2.9931) == [-7.0, -6.0, -5.0, -4.0, -3.0]
    assert nice_ticks(0.375, 1.625) == pytest.approx([0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6])
    t = nice_ticks(0.0, 1.0, most=5)
    assert t == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0])
    assert tick_text(t) == ["0.00", "0.25", "0.50", "0.75", "1.00"]
    assert tick_text([-1.0, -0.5, 0.0]) == ["\u22121.0", "\u22120.5", "0.0"]
    assert nice_ticks(1.0, 1.0) == [1.0]
