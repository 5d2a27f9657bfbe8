"""``fig07_wrap``: the round workpiece of issue 17 s.5 -- a free rod closing on a fixed cylinder, vs ``kappa_bar0``.

The problem is :mod:`simgrip.reference.wrap`'s (the free clamped rod, its weight, uniform ``kappa0 < 0``, a fixed
frictionless cylinder in its plane, default centre ``(0.2, -0.2)``, radius ``0.15``, as in
``tests/test_free_boundary.py``).  Three sources:

* the paper's free-rod BVP (:func:`simgrip.reference.elastica.sweep`, ``"free"``), which ignores the cylinder: drawn
  solid while its centreline stays outside the cylinder (and does not cross itself), dashed past that;
* the wrap BVP (:func:`simgrip.reference.wrap.solve_wrap`: a contact arc ``[s1, s2]`` with the curvature of the
  surface and the tip on it), each point started from the constrained chain;
* the constrained chain itself (:func:`simgrip.reference.constrained.solve_constrained`, ``links`` links, continued
  along ``kappa``), the independent discrete reference: its tip and the force on its last link.

No MuJoCo points: the planar scenes have no fixed cylinder for the free rod (``build_scene`` builds Grips I-III's
box); the K-finger cylinder grasp (``grip_forces``) is point contact.  Between the first touch and the wrap's range
(``kappa`` above about -7 here) the contact is the tip alone, which the wrap BVP does not cover: those points are NaN.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["WRAP_KAPPA", "CYLINDER", "wrap_contact_data", "plot_wrap_contact", "make_wrap_contact_figure"]

#: Curvatures of the free-rod curve, and those where the wrap is solved (steps of 1/4 from -7 to -12).
KAPPA_FREE = tuple(np.linspace(0.0, -12.0, 49))
WRAP_KAPPA = tuple(np.linspace(-7.0, -12.0, 21))
#: The cylinder (centre x, y and radius, over ``l``).
CYLINDER = (0.2, -0.2, 0.15)
SHAPE_KAPPA = -10.0


def _outside(sol, cyl) -> bool:
    from simgrip.reference.contact_geometry import self_crossing

    x, y = np.asarray(sol.x, float), np.asarray(sol.y, float)
    d = np.hypot(x - cyl[0], y - cyl[1])
    return bool(np.all(d >= cyl[2] - 1e-9) and not self_crossing(np.stack([x, y], axis=1), 0.0))


def wrap_contact_data(params: DimensionlessParams | None = None, *, kappas=WRAP_KAPPA, free_kappas=KAPPA_FREE,
                      links: int = 32, cylinder=CYLINDER) -> dict:
    """The numbers of ``fig07_wrap`` (module docstring); no matplotlib.

    Returns ``kappa_free``, ``free_h`` (the free rod's tip height, z up), ``free_valid``; ``kappa``, ``Q`` (the
    cylinder's force on the tip, over ``rho g l``), ``arc`` (the wrapped length ``s2 - s1``), ``h`` (tip height),
    ``wrap_valid``; ``chain_Q`` (the force on the chain's last link), ``chain_h``, ``chain_kinds``; ``shape_*``
    at ``kappa = -10`` (``(k, 2)`` arrays or None).  ``ValueError`` for bad arguments (named).
    """
    from simgrip.chain import check_links
    from simgrip.reference import elastica
    from simgrip.reference.arguments import check_params
    from simgrip.reference.constrained import ConstrainedError, Cylinder, solve_constrained
    from simgrip.reference.wrap import WrapError, solve_wrap

    params = STANDARD if params is None else check_params(params)
    links = check_links(links)
    k = np.array(sorted((float(v) for v in kappas), reverse=True))
    kf = np.array(sorted((float(v) for v in free_kappas), reverse=True))
    if not (np.all(np.isfinite(k)) and np.all(k < 0) and np.all(np.isfinite(kf)) and np.all(kf <= 0)):
        raise ValueError(f"kappas and free_kappas must be finite and < 0 / <= 0, got {kappas!r}, {free_kappas!r}")
    try:
        cyl = Cylinder(*(float(v) for v in cylinder))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"cylinder must be (x, y, radius), got {cylinder!r}: {exc}") from None
    c3 = (cyl.x, cyl.y, cyl.radius)
    free = elastica.sweep("free", params, [Uniform(float(v)) for v in kf], failures="skip", tol=1e-8)
    free_h = np.array([float(s.tip[1]) if s is not None else np.nan for s in free])
    free_valid = np.array([s is not None and _outside(s, c3) for s in free])
    m = len(k)
    Q, arc, h, valid = (np.full(m, np.nan) for _ in range(4))
    valid = np.zeros(m, bool)
    chain_Q, chain_h = np.full(m, np.nan), np.full(m, np.nan)
    kinds, wraps, chains, guess = [], {}, {}, None
    for i, kv in enumerate(k):
        prof = Uniform(float(kv))
        try:
            ch = solve_constrained("free", params, prof, links, cylinder=cyl, guess=guess)
        except ConstrainedError as exc:
            kinds.append(f"failed: {exc}")
            guess = None
            continue
        guess = chains[i] = ch
        kinds.append(str(ch.kinds()))
        chain_h[i] = float(ch.tip[1])
        chain_Q[i] = float(sum(np.linalg.norm(c.force) for c in ch.contacts if c.index == links - 1))
        try:
            w = solve_wrap(params, prof, cyl, ch)
        except (WrapError, ValueError):
            continue
        wraps[i] = w
        Q[i], arc[i], h[i], valid[i] = w.Q, w.arc, float(w.tip[1]), w.valid
    data = {"name": "fig07_wrap", "kappa_free": kf, "free_h": free_h, "free_valid": free_valid, "kappa": k,
            "Q": Q, "arc": arc, "h": h, "wrap_valid": valid, "chain_Q": chain_Q, "chain_h": chain_h,
            "chain_kinds": np.array(kinds, dtype=object), "links": links, "cylinder": c3,
            "D": params.D, "M": params.M, "mu_s": params.mu_s, "b": params.b, "shape_kappa": SHAPE_KAPPA,
            "shape_free": None, "shape_wrap": None, "shape_chain": None}
    s = np.linspace(0.0, 1.0, 201)
    jf = int(np.argmin(np.abs(kf - SHAPE_KAPPA)))
    if free[jf] is not None and abs(kf[jf] - SHAPE_KAPPA) < 1e-9:
        data["shape_free"] = np.asarray(free[jf].position_at(s), float)
    j = int(np.argmin(np.abs(k - SHAPE_KAPPA)))
    if abs(k[j] - SHAPE_KAPPA) < 1e-9:
        if j in wraps:
            data["shape_wrap"] = np.stack([wraps[j].x, wraps[j].y], axis=1)
        if j in chains:
            data["shape_chain"] = np.asarray(chains[j].nodes, float)
    return data


def plot_wrap_contact(data: dict):
    """Draw ``fig07_wrap``: (a) the tip force ``Q`` and the wrapped length, (b) the tip height, (c) the shapes at
    ``kappa = -10``.  Returns a :class:`matplotlib.figure.Figure` (Agg canvas, not registered with pyplot)."""
    from simgrip.figures.plot import _KBAR, _new_figure, _runs

    fig, (a, b, c) = _new_figure(3)
    xk = -np.asarray(data["kappa"])
    lab_chain = f"constrained chain, n = {data['links']}"
    a.plot(xk, data["Q"], color="k", label="wrap BVP: tip force Q")
    a.plot(xk, data["chain_Q"], "o", mfc="none", color="tab:purple", ms=4, label=f"{lab_chain}: last link")
    a2 = a.twinx()
    a2.plot(xk, data["arc"], color="tab:green", ls="-.", label="wrapped length $s_2 - s_1$")
    a2.set_ylabel(r"wrapped length $/\ell$", color="tab:green")
    a.set_ylabel(r"$Q\,/\rho g\ell$")
    a.set_title("(a) tip force and wrapped length", fontsize=10)
    h1, l1 = a.get_legend_handles_labels()
    h2, l2 = a2.get_legend_handles_labels()
    a.legend(h1 + h2, l1 + l2, fontsize=6.5, loc="upper left")
    first = {True: True, False: True}
    for ok, x, y in _runs(-np.asarray(data["kappa_free"]), data["free_h"], data["free_valid"]):
        lab = None
        if first[ok]:
            lab = "free rod (paper), clear of the cylinder" if ok else "free rod, through the cylinder (invalid)"
            first[ok] = False
        b.plot(x, y, color="tab:blue", ls="-" if ok else "--", lw=4.0 if ok else 1.2, alpha=0.45 if ok else 1.0,
               label=lab)
    b.plot(xk, data["h"], color="k", label="wrap BVP")
    b.plot(xk, data["chain_h"], "o", mfc="none", color="tab:purple", ms=4, label=lab_chain)
    b.set_ylabel(r"tip height $/\ell$ ($z$ up)")
    b.set_title("(b) tip height", fontsize=10)
    b.legend(fontsize=6.5, loc="lower left")
    for ax in (a, b):
        ax.set_xlabel(rf"$-{_KBAR}$")
    cx, cy, R = data["cylinder"]
    t = np.linspace(0.0, 2.0 * math.pi, 200)
    c.fill(cx + R * np.cos(t), cy + R * np.sin(t), color="0.85", zorder=0, label="cylinder (fixed)")
    for key, style, lab in (("shape_free", dict(color="tab:blue", ls="--", lw=1.0), "free rod (invalid)"),
                            ("shape_wrap", dict(color="k", lw=1.2), "wrap BVP"),
                            ("shape_chain", dict(color="tab:purple", ls="none", marker="o", ms=2.5), lab_chain)):
        P = data.get(key)
        if P is not None:
            c.plot(P[:, 0], P[:, 1], label=lab, **style)
    c.set_aspect("equal")
    c.set_title(rf"(c) shapes at ${_KBAR} = {data['shape_kappa']:g}$", fontsize=10)
    c.legend(fontsize=6.5, loc="lower left")
    fig.suptitle(f"A free rod wrapping a cylinder (centre ({cx:g}, {cy:g}), radius {R:g}); D = {data['D']:g}")
    return fig


def make_wrap_contact_figure(name, out_dir) -> Path:
    """Compute, draw and write ``out_dir/fig07_wrap.png`` (used by :func:`simgrip.figures.make_figures`)."""
    from simgrip.figures.plot import save_figure

    if name != "fig07_wrap":
        raise ValueError(f"name: this module makes fig07_wrap, got {name!r}")
    return save_figure(plot_wrap_contact(wrap_contact_data()), Path(out_dir) / f"{name}.png")
