"""Draw the figures from :func:`simgrip.figures.figure_data`'s numbers (matplotlib).

Only matplotlib's object-oriented API is used: each figure gets its own Agg
canvas and is never registered with pyplot, so there is no global state.  This
module imports matplotlib on import; :mod:`simgrip.figures` imports it only
when a figure is drawn.

Shape panels draw the pair of fingers (the computed finger and its mirror image
``x -> -x``); heights are positive up (the paper's Fig. 9 measures them
downwards).  Figures 6-9 optionally carry simulated points: see
:mod:`simgrip.figures.overlay` for the ``overlay`` format.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import matplotlib.transforms as mtransforms
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from simgrip.figures.catalog import GRIP_SIGN, GRIP_TITLE, OVERLAY_FIGURES, figure_key
from simgrip.io import atomic_write

__all__ = ["plot_figure", "save_figure"]

_N_SHAPES = {"I": 7, "II": 7, "III": 6}  # shapes drawn (at integer / even kappa_bar0)
_KBAR = r"\bar{\kappa}_0"


def _runs(x, y, mask):
    """Contiguous runs of ``mask`` (sorted by x) as ``(x, y)`` pieces, each extended to its neighbours so
    that the valid and invalid pieces meet (the full-contact and wrap figures' valid/invalid curves)."""
    o = np.argsort(x)
    x, y, mask = np.asarray(x)[o], np.asarray(y)[o], np.asarray(mask, bool)[o]
    out, i = [], 0
    while i < len(x):
        j = i
        while j + 1 < len(x) and mask[j + 1] == mask[i]:
            j += 1
        lo, hi = i, j if mask[i] else min(j + 1, len(x) - 1)
        if not mask[i]:
            lo = max(i - 1, 0)
        out.append((bool(mask[i]), x[lo:hi + 1], y[lo:hi + 1]))
        i = j + 1
    return out


def _new_figure(ncols, width=4.3, height=3.9):
    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(1, ncols, i + 1) for i in range(ncols)]
    return fig, axes


def _cmap(n, name="viridis", lo=0.0, hi=0.9):
    cm = matplotlib.colormaps[name]
    return [cm(v) for v in np.linspace(lo, hi, max(n, 1))]


def _shade(ax, x, mask, label="feasible"):
    """Shade the x-intervals where ``mask`` holds (full height of the axes)."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return
    ax.fill_between(x, 0, 1, where=mask, transform=ax.get_xaxis_transform(), color="tab:green",
                    alpha=0.18, linewidth=0, label=label, step=None, interpolate=False)


def _hatch(ax, x, mask, label="friction suffices, tip above contact"):
    """Hatch the x-intervals where ``mask`` holds (Grip III: |f| <= mu_s n, but (23) fails)."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return
    ax.fill_between(x, 0, 1, where=mask, transform=ax.get_xaxis_transform(), facecolor="none",
                    edgecolor="tab:red", alpha=0.35, hatch="///", linewidth=0, label=label)


def _shape_axes(ax, title):
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(r"$x/\ell$ (along $\mathbf{E}_1$)")
    ax.set_ylabel(r"$z/\ell$ (up)")
    ax.set_title(title, fontsize=10)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.plot([0.0], [0.0], "ks", ms=4, zorder=7)  # the palm (the fingers' base)


def _draw_pair(ax, x, z, color, label=None, lw=1.4):
    ax.plot(x, z, color=color, lw=lw, label=label)
    ax.plot(-np.asarray(x), z, color=color, lw=lw, alpha=0.55)


def _shape_indices(n, count=7):
    return np.unique(np.linspace(0, n - 1, count).round().astype(int))


def _param_text(data, keys=("D", "M", "mu_s", "b")):
    names = {"D": "D", "M": "M", "mu_s": r"\mu_s", "b": r"b/\ell", "gamma": r"\gamma/\ell"}
    return ", ".join(f"${names[k]} = {data[k]:g}$" for k in keys if k in data)


def _overlay_shapes(ax, overlay, label):
    for i, pair in enumerate(overlay.get("shapes") or []):
        x, z = (np.asarray(v, dtype=float) for v in pair)
        ax.plot(x, z, "o", ms=2.5, mfc="none", mew=0.8, color="tab:red", linestyle="none",
                label=label if i == 0 else None)


def _overlay_points(ax, overlay, key, xfun, label, marker="o", color="tab:red"):
    """Simulated values ``overlay[key]`` against ``kappa``; filled markers (NaN: not drawn).

    With ``overlay["held"]`` only the held states are drawn (a dropped state is
    the free finger, not a point of the grip's curves)."""
    if overlay is None or key not in overlay:
        return
    x = xfun(np.asarray(overlay["kappa"], dtype=float))
    y = np.asarray(overlay[key], dtype=float)
    if "held" in overlay:
        y = np.where(np.asarray(overlay["held"], dtype=bool), y, np.nan)
    ax.plot(x, y, marker, color=color, ms=5.5, mec="k", mew=0.7, linestyle="none", label=label, zorder=5)


def _overlay_verdict(ax, overlay, xfun, grip):
    """The simulation's hold/drop verdict as a row of markers along the bottom of ``ax``.

    Filled triangle: the workpiece is held (Grip III: and the tip stays below the
    contact); hollow circle: dropped; cross (Grip III): held, but the tip is above
    the contact (condition (23) fails on the simulated shape); red diamond (a row
    above): an invalid state (it crosses itself or enters the workpiece, reported
    not held by the settle; ``overlay["valid"]``); red X: the settle failed (also listed in the legend).
    Compare with the shaded feasible region.
    """
    if overlay is None or "held" not in overlay:
        return
    tr = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
    k = np.asarray(overlay["kappa"], dtype=float)
    x = xfun(k)
    held = np.asarray(overlay["held"], dtype=bool)
    failed = np.asarray(overlay.get("failed", np.zeros(len(k), dtype=bool)), dtype=bool)
    feas = np.asarray(overlay.get("feasible", held), dtype=bool) & held
    invalid = ~np.asarray(overlay.get("valid", np.ones(len(k), dtype=bool)), dtype=bool) & ~failed
    y = 0.045
    rows = (
        (feas, dict(marker="^", color="k", mfc="k", ms=6), "MuJoCo holds the box"),
        (held & ~feas, dict(marker="x", color="k", ms=6, mew=1.2), "MuJoCo holds, tip above contact"),
        (~held & ~failed & ~invalid, dict(marker="o", color="k", mfc="white", ms=6, mew=1.0), "MuJoCo drops the box"),
        (failed, dict(marker="X", color="tab:red", ms=7), None),
    )
    for mask, style, lab in rows:
        if mask.any():
            ax.plot(x[mask], np.full(mask.sum(), y), linestyle="none", transform=tr, clip_on=False,
                    zorder=6, label=lab, **style)
    if invalid.any():  # a row above: the state itself is impossible, whatever the friction says
        ax.plot(x[invalid], np.full(invalid.sum(), 2.2 * y), linestyle="none", transform=tr, clip_on=False, zorder=6,
                marker="D", color="tab:red", mfc="white", ms=6, mew=1.2,
                label="invalid state (crosses itself / enters the box)")
    if failed.any():
        ks = ", ".join(f"{v:g}" for v in k[failed])
        ax.plot([], [], "X", color="tab:red", ms=7, label=rf"settle failed at ${_KBAR} = {ks}$")


def _overlay_failed_note(ax, overlay, label):
    failed = np.asarray(overlay.get("failed", []), dtype=bool)
    if failed.any():
        ks = ", ".join(f"{v:g}" for v in np.asarray(overlay["kappa"], dtype=float)[failed])
        ax.plot([], [], "X", color="tab:red", ms=7, label=rf"{label}: failed at ${_KBAR} = {ks}$")


def _plot_fig06(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8, height=4.4)
    colors = _cmap(len(data["kappa"]), "coolwarm", 0.0, 1.0)
    for ax, panel, title in ((a, "a", "(a) without gravity"), (b, "b", "(b) with gravity")):
        _shape_axes(ax, title)
        for i, k in enumerate(data["kappa"]):
            ax.plot(data[f"x_{panel}"][i], data[f"z_{panel}"][i], color=colors[i], lw=1.6,
                    label=rf"${_KBAR} = {k:g}$")
        ax.legend(fontsize=7, loc="best")
    if overlay is not None:
        label = overlay.get("label", "simulation")
        if "a" in overlay or "b" in overlay:  # both panels (simulation_overlay("fig06"))
            panels = [(ax, overlay[p]) for ax, p in ((a, "a"), (b, "b")) if p in overlay]
        else:  # one panel, chosen by overlay["gravity"]
            panels = [(a if overlay.get("gravity", True) is False else b, overlay)]
        for ax, sub in panels:
            _overlay_shapes(ax, sub, f"{label} (nodes)")
            if "tip_x" in sub and "tip_z" in sub:
                ax.plot(sub["tip_x"], sub["tip_z"], "o", color="tab:red", mec="k", mew=0.7, ms=6,
                        linestyle="none", label=f"{label} (tips)", zorder=5)
            _overlay_failed_note(ax, overlay, label)
            ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"Fig. 6 - free clamped rod, uniform ${_KBAR}$, $D = {data['D']:g}$")
    return fig


#: Panels (b) and (c) of Figs. 7-9 per grip kind: title, the reference curves ``(key, colour, label)`` and the
#: overlay's points ``(key, marker, colour, label)``.
_FRICTION_PANEL = {
    "III": (r"(b) friction $|f|$ needed vs $\mu_s n$ available",
            (("required", "tab:blue", r"$|f|/\rho g\ell$ needed"),
             ("available", "tab:orange", r"$\mu_s n/\rho g\ell$ available")),
            (("f", "o", "tab:blue", "$|f|$"), ("mu_n", "s", "tab:orange", r"$\mu_s n$"))),
    "I/II": (r"(b) friction $|F_f|$ needed vs $\mu_s N$ available",
             (("required", "tab:blue", r"$|F_f|/\rho g\ell = M$ needed"),
              ("available", "tab:orange", r"$\mu_s N/\rho g\ell$ available")),
             (("muN", "s", "tab:orange", r"$\mu_s N$"),)),
}
_HEIGHT_PANEL = {
    "III": (r"(c) heights $h$ and $h_\gamma$",
            (("h", "tab:purple", r"$h$ (tip)"), ("h_gamma", "tab:brown", r"$h_\gamma$ (contact $s=\gamma$)")),
            (("h", "o", "tab:purple", "$h$"), ("h_gamma", "s", "tab:brown", r"$h_\gamma$"))),
    "I/II": (r"(c) tip height $h$", (("h", "tab:purple", r"$h$ (tip)"),), (("h", "o", "tab:purple", "$h$"),)),
}


def _feasible_background(ax, xk, data, grip):
    """Shade the feasible region; Grip III: hatch where friction suffices but the tip is above the contact (23)."""
    _shade(ax, xk, data["feasible"])
    if grip == "III":
        _hatch(ax, xk, np.asarray(data["friction_ok"]) & ~np.asarray(data["tip_below_contact"]))


def _curves_panel(ax, spec, xk, data, overlay, xfun, label):
    """Reference curves and the overlay's points of one panel (``spec``: see :data:`_FRICTION_PANEL`)."""
    title, curves, points = spec
    for key, color, lab in curves:
        ax.plot(xk, data[key], color=color, label=lab)
    ax.set_title(title, fontsize=10)
    if overlay is not None:
        for key, marker, color, lab in points:
            _overlay_points(ax, overlay, key, xfun, f"{label}: {lab}", marker, color)


def _shapes_panel(a, data, overlay, label, grip, sign):
    """Panel (a) of Figs. 7-9: the pair of fingers at a few curvatures (thick where feasible)."""
    k = np.asarray(data["kappa"])
    _shape_axes(a, "(a) deformed shapes (thick, f: feasible)")
    idx = _shape_indices(len(k), _N_SHAPES[grip])
    colors = _cmap(len(idx))
    for j, i in enumerate(idx):
        if not data["success"][i]:
            continue
        feas = bool(data["feasible"][i])
        _draw_pair(a, data["shape_x"][i], data["shape_z"][i], colors[j],
                   label=rf"${_KBAR} = {k[i]:.3g}$" + (" (f)" if feas else ""), lw=2.4 if feas else 1.2)
        if grip == "III":
            a.plot([data["x_gamma"][i], -data["x_gamma"][i]], [data["h_gamma"][i]] * 2, "v",
                   color=colors[j], ms=4)
    for xv in (data["b"] / 2.0, -data["b"] / 2.0):
        a.axvline(xv, color="0.5", lw=0.8, ls="--")
    if overlay is not None:
        _overlay_shapes(a, overlay, label)
    # room for the legend on the side away from the palm (below for I/III, above for II)
    zs = np.asarray(data["shape_z"])[np.asarray(data["success"], dtype=bool)]
    lo, hi = (float(np.nanmin(zs)), float(np.nanmax(zs))) if zs.size else (-1.0, 0.0)
    lo, hi = min(lo, 0.0) - 0.05, max(hi, 0.0) + 0.05
    rows = 0.075 * math.ceil((len(idx) + (overlay is not None)) / 2) + 0.06
    # (extend the data limits, not the view limits: the equal aspect adjusts the data limits)
    a.update_datalim([(0.0, lo - rows if sign < 0 else hi + rows)])
    a.autoscale_view()
    a.legend(fontsize=6.5, loc="lower center" if sign < 0 else "upper center", ncol=2, columnspacing=0.8,
             handlelength=1.6)


def _plot_grip_sweep(data, overlay=None):
    grip = data["grip"]
    kind = "III" if grip == "III" else "I/II"
    num = {"I": 7, "II": 8, "III": 9}[grip]
    sign = GRIP_SIGN[grip]
    xk = sign * np.asarray(data["kappa"])  # plot against |kappa| with the paper's orientation (-kappa for I/III)
    xlabel = rf"$-{_KBAR}$" if sign < 0 else rf"${_KBAR}$"
    xfun = lambda kk: sign * kk  # noqa: E731
    label = (overlay or {}).get("label", "simulation")
    fig, (a, b, c) = _new_figure(3)
    _shapes_panel(a, data, overlay, label, grip, sign)

    # (b) friction needed vs available
    _feasible_background(b, xk, data, grip)
    _curves_panel(b, _FRICTION_PANEL[kind], xk, data, overlay, xfun, label)
    if overlay is not None:
        _overlay_verdict(b, overlay, xfun, grip)
    b.axhline(0.0, color="0.6", lw=0.6)
    b.set_xlabel(xlabel)
    b.set_ylabel(r"force on the rod $/\rho g\ell$")
    # legend in the upper left, above the curves (room made for Grips I/II, whose M line crosses it)
    if grip != "III":
        y0, y1 = b.get_ylim()
        b.set_ylim(y0, y1 + 0.6 * (y1 - y0))
    b.legend(fontsize=7, loc="upper left")

    # (c) heights
    _feasible_background(c, xk, data, grip)
    _curves_panel(c, _HEIGHT_PANEL[kind], xk, data, overlay, xfun, label)
    c.set_xlabel(xlabel)
    c.set_ylabel(r"height $/\ell$ ($z$ up)")
    c.legend(fontsize=7, loc="lower right" if grip == "III" else "best")

    keys = ("D", "M", "mu_s", "b", "gamma") if grip == "III" else ("D", "M", "mu_s", "b")
    fig.suptitle(f"Fig. {num} - {GRIP_TITLE[grip]} vs ${_KBAR}$; {_param_text(data, keys)}")
    return fig


def _plot_fig11(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8)
    for grip, color, sign in (("I", "tab:blue", -1), ("II", "tab:orange", 1)):
        kk = np.abs(data[f"kappa_{grip}"])
        a.plot(kk, data[f"lambda_min_{grip}"], "o-", ms=3, color=color,
               label=f"Grip I (${_KBAR} \\leq 0$)" if grip == "I" else f"Grip II (${_KBAR} \\geq 0$)")
    a.set_xlabel(rf"$|{_KBAR}|$")
    a.set_title("(a) Grips I and II (Figs. 7, 8)", fontsize=10)
    _shade(b, -data["kappa_III"], data["feasible_III"])
    b.plot(-data["kappa_III"], data["lambda_min_III"], "o-", ms=3, color="tab:green", label="Grip III")
    b.set_xlabel(rf"$-{_KBAR}$")
    b.set_title(r"(b) Grip III (Fig. 9), $\gamma/\ell = %g$" % data["gamma"], fontsize=10)
    for ax in (a, b):
        ax.axhline(0.0, color="k", lw=0.7, ls=":")
        ax.set_ylabel(r"$\lambda_{\min}(E^T L E)$")
        ax.legend(fontsize=8, loc="best")
    fig.suptitle(f"Fig. 11 - stability along the sweeps of Figs. 7-9 ($K = {data['K']}$); "
                 f"{_param_text(data)}")
    return fig


def _plot_fig12(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8, height=4.2)
    colors = _cmap(len(data["alpha"]))
    for i, al in enumerate(data["alpha"]):
        a.plot(data["s"], data["profile"][i], color=colors[i], label=rf"$\alpha = {al:g}$")
        b.plot(data["x"][i], data["z"][i], color=colors[i], label=rf"$\alpha = {al:g}$")
    a.set_xlabel(r"$\bar{s} = s/\ell$")
    a.set_ylabel(rf"${_KBAR}(\bar{{s}})$")
    a.set_title("(a) intrinsic curvature, eq. (34)", fontsize=10)
    a.legend(fontsize=8)
    _shape_axes(b, "(b) free heavy rod")
    b.legend(fontsize=8)
    fig.suptitle(rf"Fig. 12 - concentrated profile (34): $\bar{{\kappa}}_{{\max}} = {data['kappa_max']:g}$, "
                 rf"$p = {data['p']:d}$, $D = {data['D']:g}$")
    return fig


def _plot_alpha(data, overlay=None):
    grip = data["grip"]
    num = {"I": 13, "II": 14, "III": 15}[grip]
    fig, (a, b, c) = _new_figure(3)
    _shape_axes(a, r"(a) deformed shapes vs $\alpha$")
    colors = _cmap(len(data["shape_index"]))
    for j, i in enumerate(data["shape_index"]):
        if data["success"][i]:
            _draw_pair(a, data["shape_x"][i], data["shape_z"][i], colors[j],
                       label=rf"$\alpha = {data['alpha'][i]:g}$")
            if grip == "III":
                a.plot([data["x_gamma"][i], -data["x_gamma"][i]], [data["h_gamma"][i]] * 2, "v",
                       color=colors[j], ms=4)
    for xv in (data["b"] / 2, -data["b"] / 2):
        a.axvline(xv, color="0.5", lw=0.8, ls="--")
    a.legend(fontsize=7)
    if grip == "III":
        b.plot(data["alpha_capacity"], data["capacity"], "o-", ms=3, color="tab:orange",
               label=r"largest $|N_2|/\rho g\ell = M$ held")
        b.set_title(r"(b) load capacity $|N_2|$ at $\mu_s = %g$" % data["mu_s"], fontsize=10)
        b.set_ylabel(r"$|N_2|/\rho g\ell$")
    else:
        b.plot(data["alpha_capacity"], data["capacity"], "o-", ms=3, color="tab:orange",
               label=r"$\mu_s N/\rho g\ell$ at $M = %g$" % data["M"])
        b.set_title(r"(b) load capacity $\mu_s N$", fontsize=10)
        b.set_ylabel(r"$\mu_s N/\rho g\ell$")
    b.axhline(data["M"], color="tab:blue", ls="--", lw=1, label=f"$M = {data['M']:g}$ (weight per finger)")
    if np.isfinite(data.get("uniform_capacity", np.nan)):
        b.axhline(data["uniform_capacity"], color="0.35", ls=":", lw=1.2,
                  label=rf"uniform ${_KBAR} = {data['p'] * data['kappa_max']:+g}$")
    b.set_xlabel(r"$\alpha$")
    b.legend(fontsize=7)
    c.plot(data["alpha_stab"], data["lambda_min"], "o-", ms=3, color="tab:green")
    c.axhline(0.0, color="k", lw=0.7, ls=":")
    c.set_xlabel(r"$\alpha$")
    c.set_ylabel(r"$\lambda_{\min}(E^T L E)$")
    c.set_title("(c) stability: smallest eigenvalue", fontsize=10)
    keys = ("D", "M", "mu_s", "b", "gamma") if grip == "III" else ("D", "M", "mu_s", "b")
    fig.suptitle(rf"Fig. {num} - {GRIP_TITLE[grip]}, profile (34) with $\bar{{\kappa}}_{{\max}} = "
                 rf"{data['kappa_max']:g}$, $p = {data['p']:+d}$; {_param_text(data, keys)}")
    return fig


def _plot_fig16(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=5.0, height=4.2)
    colors = {"I": "tab:blue", "II": "tab:orange", "III": "tab:green"}
    inset = b.inset_axes([0.09, 0.47, 0.42, 0.4])
    for grip in ("I", "II", "III"):
        a.plot(np.abs(data[f"kappa_{grip}"]), data[f"least_mu_{grip}"], color=colors[grip], label=f"Grip {grip}")
        load = np.asarray(data[f"max_load_{grip}"], dtype=float)
        shown = np.where(np.isinf(load), data["M_max"], load)
        kl = np.abs(data[f"kappa_load_{grip}"])
        fold = np.asarray(data.get(f"max_load_reason_{grip}", np.array([""] * len(kl)))) == "fold"
        for ax in (b, inset):
            ax.plot(kl, shown, "-", color=colors[grip], label=f"Grip {grip}" if ax is b else None)
            ax.plot(kl[~fold], shown[~fold], "o", ms=3, color=colors[grip])
            ax.plot(kl[fold], shown[fold], "o", ms=5, mfc="white", color=colors[grip])
        if np.isinf(load).any():
            b.plot(kl[np.isinf(load)], np.full(np.isinf(load).sum(), data["M_max"]), "^", ms=7,
                   color=colors[grip], label=rf"Grip {grip}: $M \geq {data['M_max']:g}$ (search limit)")
    if any((np.asarray(data.get(f"max_load_reason_{g}", [])) == "fold").any() for g in ("I", "II", "III")):
        b.plot([], [], "o", ms=5, mfc="white", color="0.3", label="limited by snap-through (fold)")
    a.axhline(1.0, color="0.5", ls="--", lw=0.8, label=r"$\mu_s = 1$")
    finite = np.concatenate([data[f"least_mu_{g}"][np.isfinite(data[f"least_mu_{g}"])] for g in ("I", "II", "III")])
    top = min(3.0, float(finite.max())) if finite.size else 3.0
    a.set_ylim(0.0, max(top, 1.2) * 1.05)
    a.set_xlim(0.0, None)
    a.set_xlabel(rf"$|{_KBAR}|$")
    a.set_ylabel(r"least $\mu_s = |f|/n$")
    a.set_title(f"(a) least $\\mu_s$ to hold $M = {data['M']:g}$ (gaps: cannot hold)", fontsize=10)
    b.set_xlabel(rf"$|{_KBAR}|$")
    b.set_ylabel(r"largest $M = m/\rho\ell$")
    b.set_title(r"(b) largest $M$ held at $\mu_s = 1$", fontsize=10)
    for ax in (b, inset):
        ax.axhline(data["M"], color="0.5", ls="--", lw=0.8, label=f"$M = {data['M']:g}$" if ax is b else None)
    kmax = max(np.abs(data["kappa_load_I"]).max(), np.abs(data["kappa_load_II"]).max())
    small = np.concatenate([data["max_load_I"], data["max_load_II"]])
    small = small[np.isfinite(small)]
    inset.set_xlim(0.0, kmax * 1.02)
    inset.set_ylim(0.0, (small.max() if small.size else 10.0) * 1.15)
    inset.set_title("Grips I, II (zoom)", fontsize=7)
    inset.tick_params(labelsize=7)
    a.legend(fontsize=8)
    # below the panel: inside it, every corner holds points (Grips I/II near 6, the M line, Grip III's rise)
    b.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3)
    fig.suptitle(rf"Fig. 16 - load capability of the three grips; $D = {data['D']:g}$, "
                 rf"$b/\ell = {data['b']:g}$, $\gamma/\ell = {data['gamma']:g}$ (Grip III)")
    return fig


_PLOTTERS = {"fig06": _plot_fig06, "fig07": _plot_grip_sweep, "fig08": _plot_grip_sweep,
             "fig09": _plot_grip_sweep, "fig11": _plot_fig11, "fig12": _plot_fig12,
             "fig13": _plot_alpha, "fig14": _plot_alpha, "fig15": _plot_alpha, "fig16": _plot_fig16}


def plot_figure(name, data: dict, *, overlay: dict | None = None):
    """Draw figure ``name`` from :func:`figure_data`'s ``data``; returns a :class:`matplotlib.figure.Figure`.

    ``overlay`` (figures 6-9 only) adds simulated points; see
    :mod:`simgrip.figures.overlay` for its keys.  The figure has an Agg canvas attached and is not registered
    with pyplot.
    """
    key = figure_key(name)
    if key not in _PLOTTERS:
        raise ValueError(f"name: {key} is not drawn from figure_data (the K-finger figures: "
                         f"simgrip.figures.gripper.make_gripper_figure)")
    if overlay is not None:
        if key not in OVERLAY_FIGURES:
            raise ValueError(f"overlay is supported for fig06-fig09 only, not {key}")
        if "kappa" not in overlay and key != "fig06":
            raise ValueError("overlay needs a 'kappa' array (kappa_bar0 of each simulated point)")
    return _PLOTTERS[key](data, overlay)


def save_figure(fig, path, *, dpi: int = 110) -> Path:
    """Write ``fig`` as a PNG atomically (see :func:`simgrip.io.atomic_write`)."""
    path = Path(path)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    return path
