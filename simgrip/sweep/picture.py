"""The drawing primitives of a sweep's ``map.png``: fonts, labels with a bar and a subscript, axis ticks.

``map.png`` (:mod:`simgrip.sweep.map`) is a raster of cells, a frame, ticks,
labels and a legend: nothing that needs a plotting library's layout engine.
It is drawn with Pillow (a dependency of matplotlib, which simgrip requires)
in DejaVu Sans, the font matplotlib ships, found without importing matplotlib
(whose import and first draw took ~0.7 s of a 300-point sweep's ~4 s, issue 19);
Pillow's basic text layout (no shaping library) keeps the picture the same
on every machine with the same Pillow.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from pathlib import Path

__all__ = ["Label", "font", "nice_ticks", "tick_text", "text_size", "draw_text"]

#: matplotlib's bundled font, relative to its package folder.
_DEJAVU = Path("mpl-data", "fonts", "ttf", "DejaVuSans.ttf")


@functools.lru_cache(maxsize=8)
def font(px: int):
    """DejaVu Sans at ``px`` pixels (matplotlib's copy), else Pillow's default TrueType font at that size.

    A documented bounded cache: the map uses three sizes."""
    from PIL import ImageFont

    spec = importlib.util.find_spec("matplotlib")
    for folder in (spec.submodule_search_locations or ()) if spec is not None else ():
        path = Path(folder) / _DEJAVU
        if path.is_file():
            return ImageFont.truetype(str(path), px, layout_engine=ImageFont.Layout.BASIC)
    return ImageFont.load_default(px)  # pragma: no cover - matplotlib without its fonts


class Label:
    """A label ``main`` with an optional bar over it and a subscript (``κ̄₀``: ``Label("κ", bar=True, sub="0")``)."""

    __slots__ = ("main", "bar", "sub")

    def __init__(self, main: str, *, bar: bool = False, sub: str = ""):
        self.main, self.bar, self.sub = main, bar, sub

    def __repr__(self) -> str:
        return f"Label({self.main!r}, bar={self.bar}, sub={self.sub!r})"


def _parts(label):
    return label if isinstance(label, Label) else Label(str(label))


def text_size(label, px: int) -> tuple[int, int]:
    """Width and height [px] of ``label`` (a string or a :class:`Label`) at ``px`` pixels."""
    lab = _parts(label)
    f = font(px)
    w = _width(f, lab.main)
    if lab.sub:
        w += _width(font(_sub_px(px)), lab.sub)
    return int(math.ceil(w)), _line_height(px) + (_sub_drop(px) if lab.sub else 0)


def _width(f, s: str) -> float:
    return float(f.getlength(s)) if s else 0.0


def _sub_px(px: int) -> int:
    return max(6, int(round(0.7 * px)))


def _sub_drop(px: int) -> int:
    return max(1, int(round(0.12 * px)))


def _line_height(px: int) -> int:
    a, d = font(px).getmetrics()
    return int(a + d)


def draw_text(draw, xy, label, px: int, fill=(0, 0, 0)) -> None:
    """Draw ``label`` with its top-left corner at ``xy`` [px]: the main text, the bar over it, the subscript."""
    lab = _parts(label)
    x, y = int(round(xy[0])), int(round(xy[1]))
    f = font(px)
    draw.text((x, y), lab.main, font=f, fill=fill)
    w = _width(f, lab.main)
    if lab.bar and lab.main:
        top = f.getbbox(lab.main)[1]  # the glyphs' top below the line's top
        yb = y + top - max(2, px // 6)
        draw.line([(x + 1, yb), (x + int(round(w)) - 1, yb)], fill=fill, width=max(1, px // 14))
    if lab.sub:
        a = f.getmetrics()[0]
        fs = font(_sub_px(px))
        draw.text((x + int(round(w)), y + a - fs.getmetrics()[0] + _sub_drop(px)), lab.sub, font=fs, fill=fill)


def nice_ticks(lo: float, hi: float, most: int = 8) -> list[float]:
    """Tick values in ``[lo, hi]`` at a step of 1, 2, 2.5 or 5 times a power of ten, at most ``most`` of them
    (at least 2 when the interval holds them)."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return [lo] if math.isfinite(lo) else []
    raw = (hi - lo) / max(1, most - 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 2.5, 5.0, 10.0):
        step = m * mag
        first = math.ceil(lo / step - 1e-9)
        last = math.floor(hi / step + 1e-9)
        if last - first + 1 <= most:
            break
    return [k * step for k in range(first, last + 1)]


def tick_text(values: list[float]) -> list[str]:
    """Labels of ``values`` (evenly spaced ticks) with the decimals their spacing needs (``-0.0`` written ``0.0``,
    the minus sign as matplotlib writes it, U+2212)."""
    if len(values) < 2:
        return [f"{v:g}" for v in values]
    step = abs(values[1] - values[0])
    dec = max(0, -int(math.floor(math.log10(step) + 1e-9))) if step > 0 else 0
    if step > 0 and abs(step * 10**dec - round(step * 10**dec)) > 1e-6:  # 2.5 x 10^k: one decimal more
        dec += 1
    out = []
    for v in values:
        s = f"{v:.{dec}f}"
        out.append(s.lstrip("-") if float(s) == 0.0 else s.replace("-", "\u2212"))
    return out
