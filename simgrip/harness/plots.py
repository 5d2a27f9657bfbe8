"""The harness's two plots: the bench's Pareto plot (error vs run time) and the stress run's stability map.

matplotlib's object-oriented API only (Agg canvas, no pyplot state); written
atomically.  This module imports matplotlib: the harness imports it only when
a plot is drawn.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from simgrip.io import atomic_write

__all__ = ["pareto_figure", "pareto_plot", "stability_map"]

#: Errors below this are drawn at it (the BVP reference has error 0 against itself).
ERROR_FLOOR = 1e-13


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save_png(fig: Figure, path: Path) -> None:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())


def _curve(res, grip, method):
    """A method's rows of one grip, in plotting order (the BVP: its tolerance curve, ``n = 0``)."""
    if method == "bvp":
        rows = (r for r in res.rows if r["grip"] == grip and r["method"] == "bvp" and r["n"] == 0)
        return sorted(rows, key=lambda r: -r["tol"])
    if method == "settle_target":
        rows = (r for r in res.rows if r["grip"] == grip and r["method"] == method and r.get("time_s"))
        return sorted(rows, key=lambda r: -r["target_error"])
    rows = (r for r in res.rows if r["grip"] == grip and r["method"] == method and r.get("time_s"))
    return sorted(rows, key=lambda r: r["n"])


def pareto_plot(res, cases: dict, path: Path) -> None:
    """Write :func:`pareto_figure` of ``res`` and ``cases`` to ``path`` (PNG, whole or not at all)."""
    _save_png(pareto_figure(res, cases), path)


def pareto_figure(res, cases: dict) -> Figure:
    """Tip error against wall time per grip and method (``res``: a :class:`~simgrip.harness.bench.BenchResult`).

    Measured points are joined by lines; naive points extrapolated within the
    trusted range are hollow squares; naive runs whose time is only a lower
    bound are drawn at the measured time with a right-pointing marker (the
    time lies to the right), so one far extrapolation cannot stretch the axis;
    naive runs with no static state (the workpiece slid off) are listed in a note.
    """
    from matplotlib.ticker import NullFormatter

    grips = [g for g in ("free", "I", "II", "III") if any(r["grip"] == g for r in res.rows)]
    fig = _figure(4.0 * len(grips), 3.8)
    axes = fig.subplots(1, len(grips), squeeze=False)[0]
    style = {"settle": ("o-", "C0"), "settle_target": ("*-", "C4"), "naive": ("s--", "C3"), "minimiser": ("^-", "C2"),
             "bvp": ("d:", "C1")}
    for ax, g in zip(axes, grips):
        for meth, (ls, col) in style.items():
            rs = [r for r in _curve(res, g, meth) if r.get("tip_err") is not None]
            pts = [r for r in rs if math.isfinite(r["time_s"]) and not r.get("lower_bound")]
            lab = {"bvp": "BVP, tol 1e-3 … 1e-10 (reference at the floor)",
                   "settle_target": "settle(target_error = 1e-3 … 1e-6)"}.get(meth, meth)
            if pts:
                ax.loglog([r["time_s"] for r in pts], [max(r["tip_err"], ERROR_FLOOR) for r in pts], ls, color=col,
                          label=lab, ms=4)
            if meth == "naive":
                ex = [r for r in pts if r.get("extrapolated")]
                if ex:
                    ax.loglog([r["time_s"] for r in ex], [max(r["tip_err"], ERROR_FLOOR) for r in ex], "s", ms=9,
                              mfc="none", color=col, label="naive, extrapolated")
                never = [str(r["n"]) for r in rs if math.isinf(r["time_s"]) and not r.get("lower_bound")]
                if never:
                    ax.text(0.02, 0.02, f"naive: no static state at n = {', '.join(never)}", transform=ax.transAxes,
                            fontsize=7, color=col)
                lb = [r for r in rs if r.get("lower_bound")]
                if lb:
                    ax.loglog([r["time_min_s"] for r in lb], [max(r["tip_err"], ERROR_FLOOR) for r in lb], ">", ms=8,
                              color=col, label="naive, not reached in the time shown")
            if meth == "settle":
                for r in pts:
                    ax.annotate(str(r["n"]), (r["time_s"], max(r["tip_err"], ERROR_FLOOR)), fontsize=6,
                                textcoords="offset points", xytext=(3, 3))
        ax.set_title(f"{'free rod' if g == 'free' else 'Grip ' + g}, κ̄0 = {cases[g]:g}")
        ax.set_xlabel("wall time [s]")
        ax.xaxis.set_minor_formatter(NullFormatter())  # a panel spanning under a decade labels its minor ticks
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("tip error |r − r_BVP| / ℓ")
    legend = {}  # every method and marker seen on any panel, once
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            legend.setdefault(lab, h)
    # below the panels, not on one: inside, it covered Grip III's points
    fig.legend(list(legend.values()), list(legend), fontsize=7, loc="outside lower center", ncol=4)
    return fig


_COLORS = {"easy": "tab:green", "slow": "gold", "dropped": "tab:blue", "flagged": "tab:purple",
           "rejected": "0.6", "unsettled": "tab:orange", "failed": "tab:red"}


def stability_map(cases, grips, slow_steps: int, path: Path) -> None:
    """Per grip, ``kappa`` against ``log10 D`` of every stress case, coloured by its ``"category"``."""
    fig = _figure(14, 4.0)
    axes = fig.subplots(1, len(grips), sharey=True)
    for ax, g in zip(axes, grips):
        for cat, col in _COLORS.items():
            pts = [c for c in cases if c["grip"] == g and c["category"] == cat]
            if pts:
                ax.scatter([c["kappa"] for c in pts], [math.log10(c["D"]) for c in pts], s=12,
                           c=col, label=f"{cat} ({len(pts)})", edgecolors="none", alpha=0.8)
        for k in (2 * math.pi, -2 * math.pi):
            ax.axvline(k, color="k", lw=0.5, ls=":")
        ax.set_title("free rod" if g == "free" else f"Grip {g}")
        ax.set_xlabel("κ̄0 (peak)")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6, loc="upper left")
    axes[0].set_ylabel("log10 D")
    totals = ", ".join(f"{cat} {sum(c['category'] == cat for c in cases)}" for cat in _COLORS
                       if any(c["category"] == cat for c in cases))
    fig.suptitle(f"settle stability map: easy (≤ {slow_steps} steps), slow, dropped workpiece (valid state), flagged "
                 "invalid (any flag, dropped or not: stress.json's 'flagged'), rejected (ValueError), unsettled "
                 f"(SettleError), failed; dotted: a full turn\nall grips: {totals}", fontsize=9)
    _save_png(fig, path)
