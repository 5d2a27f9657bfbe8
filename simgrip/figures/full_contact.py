"""Fig. 7 extended past the onset of full contact (issue 17 s.5): Grip I's ``N`` and tip height vs ``kappa_bar0``.

Three sources, standard case unless ``params`` says otherwise, the box hanging on the tip with its top edge
``depth`` above it (:mod:`simgrip.reference.free_boundary`'s problem):

* the paper's point-contact BVP (:func:`simgrip.reference.elastica.sweep`), each point judged by
  :func:`simgrip.reference.onset.point_contact_violations` at the same ``depth`` -- drawn solid while valid,
  dashed (and labelled invalid) past the onset (:func:`simgrip.reference.onset.onset`, -8.269 for the standard
  case), where the rod enters the box and then loops through itself;
* the full-contact reference: the point-contact BVP where it is valid; past the onset the tip + corner
  free-boundary BVP (:func:`simgrip.reference.free_boundary.solve_corner`), started from the constrained chain
  (:func:`simgrip.reference.constrained.solve_constrained`, ``ref_links`` links) at the first point past the
  onset and continued along ``kappa``; a point whose constrained chain has another contact set, or whose BVP
  fails, is NaN (``full_source`` says which);
* the MuJoCo chain, ``contact="full"`` at ``box_depth = depth`` (:func:`simgrip.settle.settle`), ``links``
  links, at a few ``sim_kappa`` (each settle takes ~0.5-8 s): the tip's ``N`` (:func:`simgrip.compare_full.tip_forces`)
  when held, NaN when dropped or when the settle fails (``sim_status`` says which).

Agreement (the test's bound, :func:`first_order_bound`): past the onset the chain touches the corner with a
straight link, so it is first order in ``ds``; the budget at ``kappa = -10`` is derived in
:mod:`simgrip.reference.free_boundary` and ``tests/test_full_grasp.py``.

:func:`full_contact_data` computes (no matplotlib); :func:`plot_full_contact` draws; :func:`make_full_contact_figure`
writes ``out_dir/fig07_full.png`` (``simgrip figures --which fig07_full``); the round workpiece's
``fig07_wrap`` is :mod:`simgrip.figures.wrap_contact`'s.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from simgrip.figures.catalog import FULL_CONTACT_FIGURES
from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["FULL_CONTACT_FIGURES", "KAPPA", "SIM_KAPPA", "first_order_bound", "first_order_tip_bound", "full_contact_data",
           "plot_full_contact", "make_full_contact_figure"]

#: Default curvature grid (steps of 1/4 to -12) and the simulated points (at most 8; past -10 the n = 32
#: full-contact settle does not converge: measured at -11 and -12, "did not converge" after 20000 steps).
KAPPA = tuple(np.linspace(0.0, -12.0, 49))
SIM_KAPPA = (-5.0, -6.0, -7.0, -8.0, -8.5, -9.0, -9.5, -10.0)
#: Shapes drawn in panel (c): this curvature (past the onset).
SHAPE_KAPPA = -10.0
_TOL = 1e-8            # solve_bvp tolerance of the point-contact sweep (as simgrip.figures.data)
_N_SHAPE = 201
#: ``|dN/d depth|`` of Grip I's kappa = -10 corner grasp (the constrained chain at n = 16, tests/test_full_grasp.py)
#: and the constrained chain's first-order coefficient ``|dN/dtilt| |theta'(gamma)|`` (free_boundary.py).
DN_DDEPTH = 56.0
DN_DS = 1.73
#: ``|dh/d depth|`` of the tip's height there: the constrained chain at n = 16, depths 0.400/0.399/0.398
#: (tips -0.477339, -0.476224, -0.475110: 1.115 per unit depth; the corner stays on the rod, the tip follows).
DH_DDEPTH = 1.115


def first_order_bound(links: int, r_link: float, depth_tol: float) -> float:
    """``|N_sim - N_BVP|`` allowed at Grip I, ``kappa = -10`` (standard case), over ``rho g l``.

    ``DN_DS / n`` (discretisation: a straight link on the corner) ``+ DN_DDEPTH depth_tol`` (the depth the
    grasp settles at) ``+ DN_DDEPTH r_link (sqrt 2 - 1) / 0.8`` (the capsule's rounding at the box's edge); each
    term derived in ``tests/test_full_grasp.py``.  Valid for the corner contact set at ``kappa = -10`` only.
    """
    return DN_DS / links + DN_DDEPTH * depth_tol + DN_DDEPTH * r_link * (math.sqrt(2.0) - 1.0) / 0.8


def first_order_tip_bound(links: int, r_link: float, depth_tol: float) -> float:
    """``|h_sim - h_BVP|`` allowed for the tip's height at Grip I, ``kappa = -10`` (standard case), over ``l``.

    The constrained chain's own offset at ``links`` links (the same discrete problem, sharp corner:
    :data:`simgrip.reference.free_boundary.GRIP_I_KAPPA_M10`, tabulated at n = 16, 32, 64, 128) plus
    ``DH_DDEPTH`` times the depth the settle may slip (``depth_tol``) and the capsule's rounding at the edge
    (``r_link (sqrt 2 - 1) / 0.8``, as in :func:`first_order_bound`).
    """
    from simgrip.reference.free_boundary import GRIP_I_KAPPA_M10 as ref

    if links not in ref["chain"]:
        raise ValueError(f"links: the chain's offset is tabulated at n = {sorted(ref['chain'])}, got {links}")
    chain = abs(ref["chain"][links]["tip_y"] - ref["bvp"]["tip_y"])
    return chain + DH_DDEPTH * (depth_tol + r_link * (math.sqrt(2.0) - 1.0) / 0.8)


def _kappas(name, values, limit=None):
    try:
        k = np.array([float(v) for v in values], dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a list of numbers, got {values!r}") from None
    if k.ndim != 1 or not np.all(np.isfinite(k)) or np.any(k > 0):
        raise ValueError(f"{name} must be finite values <= 0 (Grip I curls with kappa_bar0 < 0), got {values!r}")
    if limit is not None and len(k) > limit:
        raise ValueError(f"{name}: at most {limit} points (each is a MuJoCo settle), got {len(k)}")
    return k


def _point_contact(params, kappas, depth):
    from simgrip.reference import elastica
    from simgrip.reference.onset import point_contact_violations

    # continue from 0 whatever the grid (the sweep warm-starts each point from the last)
    order = np.argsort(-kappas, kind="stable")
    sols = [None] * len(kappas)
    for i, s in zip(order, elastica.sweep("I", params, [Uniform(float(kappas[i])) for i in order],
                                          tol=_TOL, failures="skip")):
        sols[i] = s
    ok = np.array([s is not None and bool(getattr(s, "success", True)) for s in sols])
    N = np.array([s.normal_force if o else np.nan for s, o in zip(sols, ok)])
    h = np.array([float(s.tip[1]) if o else np.nan for s, o in zip(sols, ok)])
    why = [("; ".join(point_contact_violations(s, depth)) if o else "solve failed") for s, o in zip(sols, ok)]
    valid = np.array([o and not w for o, w in zip(ok, why)])
    return sols, N, h, valid, why


def _full_reference(params, kappas, pc_sols, pc_valid, depth, ref_links):
    """The full-contact reference along ``kappas``: point contact while valid, then the corner BVP (continued)."""
    from simgrip.reference.bvp import ElasticaError
    from simgrip.reference.constrained import Box, ConstrainedError, solve_constrained
    from simgrip.reference.free_boundary import FreeBoundaryError, solve_corner

    n = len(kappas)
    N, h = np.full(n, np.nan), np.full(n, np.nan)
    valid = np.zeros(n, bool)
    source = np.array(["failed"] * n, dtype=object)
    corner = {}
    guess = None
    for i in np.argsort(-kappas, kind="stable"):
        if pc_valid[i]:
            N[i], h[i], valid[i], source[i] = pc_sols[i].normal_force, float(pc_sols[i].tip[1]), True, "point"
            continue
        prof = Uniform(float(kappas[i]))
        try:
            if guess is None:
                ch = solve_constrained("I", params, prof, ref_links, box=Box(depth=depth))
                if ch.kinds() != {"corner": 1}:
                    source[i] = f"contact set {ch.kinds()}"
                    continue
                guess = ch
            b = solve_corner("I", params, prof, guess, depth=depth)
        except (ConstrainedError, FreeBoundaryError, ElasticaError, ValueError) as exc:
            source[i] = f"failed: {exc}"
            guess = None
            continue
        guess = corner[i] = b
        N[i], h[i], valid[i], source[i] = b.N, float(b.tip[1]), b.valid, "corner"
    return N, h, valid, source, corner


def _simulate(params, kappas, links, depth):
    from simgrip.compare_full import tip_forces
    from simgrip.settle import settle
    from simgrip.settle.state import SettleError
    from simgrip.sim.scene import DEFAULT_R_TIP, build_scene

    m = len(kappas)
    N, h, F = np.full(m, np.nan), np.full(m, np.nan), np.full(m, np.nan)
    status, nodes = [], []
    for j, k in enumerate(kappas):
        try:
            st = settle(build_scene("I", params, float(k), links, contact="full", box_depth=depth))
        except SettleError as exc:
            status.append(f"settle failed: {exc}")
            nodes.append(np.full((links + 1, 2), np.nan))
            continue
        nodes.append(np.asarray(st.nodes[0], float)[:, :2])
        h[j] = float(nodes[-1][-1, 1])
        if st.held and st.valid:
            N[j], F[j] = tip_forces(st, DEFAULT_R_TIP)
            status.append("held")
        else:
            status.append("dropped" if st.valid else "invalid")
    return N, h, F, status, np.array(nodes)


def full_contact_data(params: DimensionlessParams | None = None, *, kappas=KAPPA, sim_kappas=SIM_KAPPA,
                      links: int = 32, ref_links: int = 32, depth: float = 0.4, shape_kappa=SHAPE_KAPPA) -> dict:
    """The numbers of ``fig07_full`` (see the module docstring); no matplotlib.

    Parameters
    ----------
    params : DimensionlessParams, optional
        Default the paper's standard case (D = 1, M = 5, mu_s = 1, b = 0.6).
    kappas : sequence of float
        ``kappa_bar0`` (<= 0) of the reference curves; swept from 0 outwards whatever the order.
    sim_kappas : sequence of float
        Where the MuJoCo chain is settled (at most 8; empty: no simulation).
    links, ref_links : int
        Links of the simulated chain, and of the constrained chain that finds the contact set past the onset.
    depth : float
        The box's top edge above the tip, over ``l`` (in (0, 2)).
    shape_kappa : float or None
        The curvature whose three shapes panel (c) draws (added to ``kappas`` and ``sim_kappas`` if missing).

    Returns
    -------
    dict
        ``kappa``; ``pc_N``, ``pc_h`` (tip height, z up), ``pc_valid``, ``pc_violation`` (point contact);
        ``onset`` (the last valid ``kappa``, :func:`~simgrip.reference.onset.onset`); ``full_N``, ``full_h``,
        ``full_valid``, ``full_source`` (``"point"``, ``"corner"`` or why NaN); ``sim_kappa``, ``sim_N``,
        ``sim_friction``, ``sim_h``, ``sim_status``, ``sim_nodes``; ``links``, ``depth``, params' ``D, M, mu_s, b``;
        the shapes at ``shape_kappa`` (``shape_pc``, ``shape_full``, ``shape_sim``: ``(k, 2)`` arrays or None).
        Forces on the rod over ``rho g l``, lengths over ``l``.
    """
    from simgrip.chain import check_links
    from simgrip.reference.arguments import check_params
    from simgrip.reference.onset import onset

    params = STANDARD if params is None else check_params(params)
    links, ref_links = check_links(links), check_links(ref_links)
    depth = float(depth)
    if not (math.isfinite(depth) and 0.0 < depth < 2.0):
        raise ValueError(f"depth must lie in (0, 2), got {depth!r}")
    k = _kappas("kappas", kappas)
    ks = _kappas("sim_kappas", sim_kappas, limit=8)
    if shape_kappa is not None:
        shape_kappa = float(_kappas("shape_kappa", [shape_kappa])[0])
        if not np.any(np.isclose(k, shape_kappa)):
            k = np.append(k, shape_kappa)
        if len(ks) and not np.any(np.isclose(ks, shape_kappa)):
            ks = _kappas("sim_kappas", list(ks) + [shape_kappa], limit=8)
    pc_sols, pc_N, pc_h, pc_valid, why = _point_contact(params, k, depth)
    full_N, full_h, full_valid, source, corner = _full_reference(params, k, pc_sols, pc_valid, depth, ref_links)
    sim_N, sim_h, sim_F, status, nodes = _simulate(params, ks, links, depth)
    on = onset("I", params, depth=depth)
    data = {"name": "fig07_full", "grip": "I", "kappa": k, "pc_N": pc_N, "pc_h": pc_h, "pc_valid": pc_valid,
            "pc_violation": np.array(why, dtype=object), "onset": float(on.kappa),
            "onset_violation": "; ".join(on.violations),
            "full_N": full_N, "full_h": full_h, "full_valid": full_valid, "full_source": source,
            "sim_kappa": ks, "sim_N": sim_N, "sim_friction": sim_F, "sim_h": sim_h,
            "sim_status": np.array(status, dtype=object), "sim_nodes": nodes,
            "links": links, "ref_links": ref_links, "depth": depth,
            "D": params.D, "M": params.M, "mu_s": params.mu_s, "b": params.b, "shape_kappa": shape_kappa,
            "shape_pc": None, "shape_full": None, "shape_sim": None}
    if shape_kappa is not None:
        i = int(np.argmin(np.abs(k - shape_kappa)))
        s = np.linspace(0.0, 1.0, _N_SHAPE)
        if pc_sols[i] is not None:
            data["shape_pc"] = np.asarray(pc_sols[i].position_at(s), float)
        if i in corner:
            data["shape_full"] = np.stack([corner[i].x, corner[i].y], axis=1)
        elif source[i] == "point":
            data["shape_full"] = data["shape_pc"]
        if len(ks):
            j = int(np.argmin(np.abs(ks - shape_kappa)))
            data["shape_sim"] = nodes[j] if np.all(np.isfinite(nodes[j])) else None
    return data


def plot_full_contact(data: dict):
    """Draw ``fig07_full`` from :func:`full_contact_data`'s ``data``: (a) ``N``, (b) tip height vs
    ``-kappa_bar0``, (c) the shapes at ``shape_kappa``.  Returns a :class:`matplotlib.figure.Figure`
    (Agg canvas, not registered with pyplot)."""
    from simgrip.figures.plot import _KBAR, _new_figure, _param_text, _runs

    fig, (a, b, c) = _new_figure(3)
    xk = -np.asarray(data["kappa"], float)
    xs = -np.asarray(data["sim_kappa"], float)
    held = np.array([s == "held" for s in data["sim_status"]], bool)
    for ax, key, title in ((a, "N", "(a) tip normal force N"), (b, "h", "(b) tip height")):
        first = {True: True, False: True}
        for ok, x, y in _runs(xk, data[f"pc_{key}"], data["pc_valid"]):
            lab = None
            if first[ok]:
                lab = "point contact (paper)" if ok else "point contact, invalid"
                first[ok] = False
            ax.plot(x, y, color="tab:blue", ls="-" if ok else "--", lw=4.0 if ok else 1.2, alpha=0.45 if ok else 1.0,
                    label=lab)
        ax.plot(xk, data[f"full_{key}"], color="k", lw=1.1, label=f"full contact (free boundary, depth {data['depth']:g})")
        sim = data[f"sim_{key}"]
        ax.plot(xs[held], sim[held], "o", mfc="none", color="tab:red", ms=6,
                label=f"MuJoCo contact='full', n = {data['links']}")
        if np.any(~held):  # N: drawn at 0; height: where the dropped finger's tip ended
            ax.plot(xs[~held], np.zeros(int(np.sum(~held))) if key == "N" else sim[~held], "x", color="tab:red",
                    ms=6, label="MuJoCo: not held (dropped) / failed")
        ax.axvline(-data["onset"], color="0.4", lw=0.8, ls=":")
        ax.text(-data["onset"], 0.98, f" onset {data['onset']:.3f}", transform=ax.get_xaxis_transform(),
                fontsize=7, va="top", ha="right", rotation=90)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel(rf"$-{_KBAR}$")
        ax.legend(fontsize=6.5, loc="upper left")
    a.axhline(data["M"] / data["mu_s"], color="0.6", lw=0.6, ls="-.", label=r"$M/\mu_s$: least $N$ that holds")
    a.legend(fontsize=6.5, loc="upper left")
    a.set_ylabel(r"$N\,/\rho g\ell$")
    b.set_ylabel(r"height $/\ell$ ($z$ up)")
    c.set_aspect("equal")
    c.set_title(rf"(c) shapes at ${_KBAR} = {data['shape_kappa']:g}$", fontsize=10)
    for key, style, lab in (("shape_pc", dict(color="tab:blue", ls="--", lw=1.0), "point contact (invalid)"),
                            ("shape_full", dict(color="k", lw=1.2), "free boundary"),
                            ("shape_sim", dict(color="tab:red", ls="none", marker="o", ms=2.5), "MuJoCo")):
        P = data.get(key)
        if P is not None:
            c.plot(P[:, 0], P[:, 1], label=lab, **style)
    tip_y = data["full_h"][int(np.argmin(np.abs(np.asarray(data["kappa"]) - data["shape_kappa"])))]
    if np.isfinite(tip_y):
        xb, top = 0.5 * data["b"], tip_y + data["depth"]
        c.fill([-xb, xb, xb, -xb], [top, top, top - 0.9, top - 0.9], color="0.85", zorder=0,
               label="box (hangs on the tip)")
    c.axvline(0.0, color="0.6", lw=0.6)
    c.legend(fontsize=6.5, loc="lower left")
    fig.suptitle(f"Fig. 7 past the onset - Grip I, point vs full contact; "
                 f"{_param_text(data, ('D', 'M', 'mu_s', 'b'))}")
    return fig


def make_full_contact_figure(name, out_dir, *, simulate: bool = True, links: int = 32) -> Path:
    """Compute, draw and write ``out_dir/<name>.png`` (``name`` in :data:`FULL_CONTACT_FIGURES`); without
    ``simulate`` no MuJoCo points.  Used by :func:`simgrip.figures.make_figures`."""
    from simgrip.figures.plot import save_figure

    if name == "fig07_wrap":  # the round workpiece: reference and constrained chain only (no planar MuJoCo scene)
        from simgrip.figures.wrap_contact import make_wrap_contact_figure

        return make_wrap_contact_figure(name, out_dir)
    if name not in FULL_CONTACT_FIGURES:
        raise ValueError(f"name: unknown full-contact figure {name!r}; known: {', '.join(FULL_CONTACT_FIGURES)}")
    data = full_contact_data(sim_kappas=SIM_KAPPA if simulate else (), links=links)
    return save_figure(plot_full_contact(data), Path(out_dir) / f"{name}.png")
