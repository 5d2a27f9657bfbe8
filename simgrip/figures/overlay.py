"""The settled MuJoCo hinge chain on the reference curves of figures 6-9.

:func:`simulation_overlay` settles the chain (``links`` links, symmetric
reduction) at a few ``kappa_bar0`` of a figure's sweep, warm-started along it
(:func:`simgrip.settle.settle` with ``warm_start``), and returns the simulated
points in the ``overlay`` format :func:`simgrip.figures.plot_figure` draws:

=========================  ===================================================
key                        meaning
=========================  ===================================================
``"kappa"``                ``kappa_bar0`` of each simulated point, shape (n,)
``"label"``                legend label (default ``"simulation"``)
``"shapes"``               list of ``(x, z)`` array pairs (finger centrelines),
                           drawn as markers on the shape panel
``"tip_x"``, ``"tip_z"``   fig06: tip positions (panel (b), or (a) when
                           ``overlay["gravity"]`` is False)
``"a"``, ``"b"``           fig06: per-panel dicts with ``"tip_x"``, ``"tip_z"``,
                           ``"shapes"`` (instead of the keys above): (a) without,
                           (b) with gravity
``"muN"``, ``"h"``         fig07/fig08: available friction ``mu_s N`` and tip height
``"f"``, ``"mu_n"``,       fig09: ``|f|``, ``mu_s n``, tip height and contact
``"h"``, ``"h_gamma"``     height
``"held"``                 fig07-09: bool (n,), the simulation holds the
                           workpiece.  Values are drawn (filled markers) only
                           where held; panel (b) gets a row of verdict markers
                           along its bottom: filled triangle held, hollow
                           circle dropped, cross (with ``"feasible"`` False)
                           held but infeasible -- compare with the shading
``"feasible"``             fig07-09: bool (n,), the simulation's verdict in the
                           caption's terms (default ``"held"``)
``"valid"``                fig07-09: bool (n,), the settled state is physical
                           (:func:`simgrip.validity.check_valid`: no link
                           through itself or the workpiece); ``"held"`` is the
                           solve's hold (an invalid state is reported not held
                           by the settle), ``"feasible"`` False where invalid;
                           the verdict row marks invalid states apart
``"failed"``               bool (n,): points whose settle failed (NaN values);
                           listed in the legend, never dropped silently
=========================  ===================================================

Every key but ``"kappa"`` is optional: an overlay from another simulator can
carry only what it has.
"""

from __future__ import annotations

import numpy as np

from simgrip.figures.catalog import FIG_GRIP, OVERLAY_FIGURES, figure_key
from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["simulation_overlay"]

#: kappa_bar0 of the simulated points.  Integer values coincide with the
#: reference shapes the figures draw; Grips I/II add half steps where the grip
#: holds (the feasible interval is only ~1.25 wide), Grip III adds -3 and -5.
_SIM_KAPPA = {
    "free": (-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0),
    "I": (0.0, -1.0, -2.0, -3.0, -4.0, -5.0, -5.5, -6.0),
    "II": (0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.5, 6.0),
    "III": (0.0, -2.0, -3.0, -4.0, -5.0, -6.0, -8.0, -10.0),
}
_SIM_LABEL = "MuJoCo chain, n = {links}"


def _sim_scene(grip, params, kappa, links, gravity):
    from simgrip.sim.reuse import build_scene  # one compile per grip and links, set in place

    scene = build_scene(grip, params, Uniform(float(kappa)), links)
    if not gravity:  # the model's own gravity vector: what MuJoCo and the settle's statics both read
        scene.model.opt.gravity[:] = 0.0
    return scene


def _sim_sweep(grip, params, kappas, links, *, gravity=True):
    """Settled states along ``kappas`` (in that order), warm-started.

    Each point starts from the previous equilibrium (the continuation of
    :func:`simgrip.settle.settle_sweep`) while that one holds the workpiece (a
    free rod always continues); after a drop -- where ``settle_sweep`` would
    keep the workpiece dropped -- and whenever a warm start fails, the point is
    settled cold in a freshly built scene (Grips I/II: the closing procedure;
    Grip III: the corner placed at ``params.gamma``), so that hold/drop is
    decided at every point.  Returns ``(states, errors)``: ``states[i]`` is
    ``None`` where even the cold settle failed, ``errors[i]`` the message(s).
    """
    from simgrip.sim.scene import set_curvature
    from simgrip.settle import SettleError, settle

    states, errors = [], []
    scene = prev = None
    for k in kappas:
        st, msg = None, []
        if prev is not None and (grip == "free" or prev.held):
            try:
                set_curvature(scene, Uniform(float(k)))
                st = settle(scene, warm_start=prev)
            except (SettleError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                msg.append(f"warm start: {type(exc).__name__}: {exc}")
                st = None
        if st is None:
            try:
                scene = _sim_scene(grip, params, k, links, gravity)
                st = settle(scene)
            except (SettleError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                msg.append(f"cold start: {type(exc).__name__}: {exc}")
                st = None
        states.append(st)
        errors.append("; ".join(msg))
        prev = st
    return states, errors


def _nodes(st):
    nodes = np.asarray(st.nodes[0], dtype=float)
    return nodes[:, 0].copy(), nodes[:, 1].copy()


def _overlay_free(params, links, kappas):
    kappas = np.asarray(sorted(kappas), dtype=float)
    out = {"kappa": kappas, "links": int(links), "label": _SIM_LABEL.format(links=links)}
    failed = np.zeros(len(kappas), dtype=bool)
    errors = [""] * len(kappas)
    for panel, gravity in (("a", False), ("b", True)):
        # continue outwards from the straight rod in both directions (as the reference does)
        neg = [i for i, k in enumerate(kappas) if k <= 0][::-1]
        pos = [i for i, k in enumerate(kappas) if k >= 0]
        states = [None] * len(kappas)
        for order in (neg, pos):
            if not order:
                continue
            sts, errs = _sim_sweep("free", params, kappas[order], links, gravity=gravity)
            for i, s, e in zip(order, sts, errs):
                if order is pos and kappas[i] == 0 and neg:
                    continue  # already settled by the sweep towards negative kappa
                states[i] = s
                if e:
                    errors[i] = (errors[i] + f"; ({panel}) " if errors[i] else f"({panel}) ") + e
        tip = np.array([s.tip[0] if s is not None else (np.nan, np.nan) for s in states], dtype=float)
        failed |= np.array([s is None for s in states])
        out[panel] = {
            "tip_x": tip[:, 0], "tip_z": tip[:, 1],
            "shapes": [_nodes(s) for s in states if s is not None],
            "gravity": gravity,
        }
    out["failed"] = failed
    out["errors"] = errors
    return out


def _overlay_grip(grip, params, links, kappas):
    kappas = np.asarray(kappas, dtype=float)
    states, errors = _sim_sweep(grip, params, kappas, links)
    n = len(kappas)
    nan = np.full(n, np.nan)
    failed = np.array([s is None for s in states])
    valid = np.array([s is None or bool(getattr(s, "valid", True)) for s in states])
    # the solve's own hold (an invalid state is reported not held, but its contact and forces are the chain's):
    # the values and the friction verdict are drawn as settled, the invalid ones marked apart ("valid")
    held = np.array([s is not None and (bool(s.held) or not v) and s.contact is not None
                     for s, v in zip(states, valid)])
    tip = np.array([s.tip[0] if s is not None else (np.nan, np.nan) for s in states], dtype=float)
    out = {"kappa": kappas, "grip": grip, "links": int(links), "label": _SIM_LABEL.format(links=links),
           "held": held, "valid": valid, "failed": failed, "errors": errors, "tip_x": tip[:, 0], "tip_z": tip[:, 1],
           "residual": np.array([s.residual if s is not None else np.nan for s in states])}
    c = [s.contact if h else None for s, h in zip(states, held)]
    pick = lambda f: np.array([f(ci) if ci is not None else np.nan for ci in c], dtype=float)  # noqa: E731
    out["N1"], out["N2"] = pick(lambda ci: ci.N1), pick(lambda ci: ci.N2)
    out["n"], out["f_signed"] = pick(lambda ci: ci.normal), pick(lambda ci: ci.friction)
    out["gamma"] = pick(lambda ci: ci.gamma)
    out["contact_moment"] = pick(lambda ci: ci.moment)
    out["h"] = np.where(held, tip[:, 1], nan)
    mu = params.mu_s
    if grip in ("I", "II"):
        out["muN"] = mu * out["N1"]
        out["feasible"] = held & valid  # the simulation's verdict: the workpiece is held, by a physical state
    else:
        out["f"] = np.abs(out["f_signed"])
        out["mu_n"] = mu * out["n"]
        out["x_gamma"] = pick(lambda ci: float(ci.point[0]))
        out["h_gamma"] = pick(lambda ci: float(ci.point[1]))
        with np.errstate(invalid="ignore"):
            out["tip_below_contact"] = held & (out["h"] < out["h_gamma"])
        # the sim's box is not a collider for the tip: condition (23) is checked on its geometry
        out["feasible"] = out["tip_below_contact"] & valid
    # shapes: held states at the kappas the reference panel draws (integers; even for Grip III)
    step = 2.0 if grip == "III" else 1.0
    out["shape_kappa"] = np.array([k for k, h in zip(kappas, held) if h and float(k / step).is_integer()])
    out["shapes"] = [_nodes(s) for k, s, h in zip(kappas, states, held) if h and float(k / step).is_integer()]
    return out


def simulation_overlay(name, *, links: int = 16, params: DimensionlessParams | None = None,
                       kappas=None) -> dict:
    """Simulated points (MuJoCo hinge chain, symmetric reduction) for figure ``name`` (6-9).

    Settles the chain of ``links`` links per finger at a few ``kappa_bar0``
    (default :data:`_SIM_KAPPA`, 7-8 values across the figure's range),
    warm-started along the sweep (see :func:`_sim_sweep`), and returns the
    ``overlay`` :func:`plot_figure` draws (see the module docstring), plus:

    * ``"failed"`` (bool per point): the settle failed even from a cold start;
      its numbers are NaN and ``"errors"[i]`` says why (drawn as a note in
      the figure: never silent);
    * Figs. 7-9: ``"held"`` -- the simulation holds the workpiece.  Force and
      height values are NaN where it dropped it (the state is then the free
      finger, not a grip); ``"tip_x"``/``"tip_z"`` are the tips of every state.
      ``"feasible"`` is the simulation's verdict in the caption's terms (Grip
      III: held *and* the tip below the contact, condition (23), measured on
      the simulated shape: the box is not a collider for the finger's tip);
      ``"N1"``, ``"N2"``, ``"n"``, ``"f_signed"``, ``"gamma"``,
      ``"contact_moment"`` (and ``"x_gamma"`` for Grip III) the raw contact;
    * Fig. 6: ``"a"`` (gravity off: the model's gravity set to 0) and ``"b"`` (gravity
      on), each with ``"tip_x"``, ``"tip_z"``, ``"shapes"``.

    Shapes are the chain's ``links + 1`` nodes, finger 0's frame (``x`` along
    ``E1``, ``z`` up, base at the origin).
    """
    from simgrip.chain import check_links

    key = figure_key(name)
    if key not in OVERLAY_FIGURES:
        raise ValueError(f"simulation overlays exist for fig06-fig09 only, not {key}")
    links = check_links(links)
    params = STANDARD if params is None else params
    if key == "fig06":
        return _overlay_free(params, links, _SIM_KAPPA["free"] if kappas is None else kappas)
    grip = FIG_GRIP[key]
    return _overlay_grip(grip, params, links, _SIM_KAPPA[grip] if kappas is None else kappas)

