"""The planar simulation and its record: :func:`simulate` builds and settles, :func:`settled_record` reads.

Both :func:`simgrip.compare.compare` (against the elastica) and
:func:`simgrip.compare_full.compare_full` (a full-contact grasp against the
free-boundary reference) start from here, and :mod:`simgrip.compare`
re-exports every name; this module imports neither.  All numbers are
dimensionless (lengths over ``l``, forces on the rod over ``rho g l``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from simgrip.contact_report import contact_records, node_records
from simgrip.chain import check_link_count
from simgrip.params import DimensionlessParams, as_dimensionless, check_grip
from simgrip.profiles import as_profile

__all__ = ["settle_fields", "settled_record", "simulate", "tip_forces", "verdict_fields"]


def simulate(grip: str, params: DimensionlessParams, profile, links: int, *, progress=None, method=None,
             **settle_kw):
    """Build the symmetric-reduction scene of ``grip`` with ``links`` links per finger and settle it.

    Returns the :class:`~simgrip.settle.SettledState`, its ``build_time_s`` the
    build and compile of the model [s] (``wall_time_s`` is the settle alone).
    ``progress`` (:mod:`simgrip.progress`; None: silent) is told the phases.
    Extra keywords go to :func:`~simgrip.settle.settle`.

    ``method``: ``"newton"`` or ``"dynamics"`` settle that way (an explicit
    choice: a failure raises :class:`~simgrip.settle.SettleError`).  ``None``
    (the default, also ``"auto"``) is Newton, and where Newton fails, the
    over-damped dynamics with a warning saying so (issue 16: the default must
    not fail where another method answers; the K-finger ``auto`` does the same).
    The fallback needs a contact the dynamics has (``contact`` None or
    ``"surface"``) and no ``target_error`` (which extrapolates Newton only);
    otherwise Newton's failure is raised.
    """
    from simgrip.progress import phase
    from simgrip.settle import SettleError, settle
    from simgrip.sim.fingers import check_finger_links
    from simgrip.sim.reuse import build_scene  # compiled once per structure, set in place (bit-identical)

    grip = check_grip(grip)  # checked here, once, and handed down as checked values (a Grip, a Count)
    if progress is not None and not callable(progress):  # (1 raised "'int' object is not callable" mid-build)
        raise ValueError(f"progress must be None or a callable told each phase, got {progress!r}")
    profile = as_profile(profile)
    links = check_finger_links(check_link_count(links))  # [2, MAX_LINKS], as the CLI's --links
    auto = method in (None, "auto")

    full = {"contact": "full"} if settle_kw.get("contact") == "full" else {}  # every link touches (issue 17)
    for k in ("box_depth", "extra_friction"):  # the full-contact grasp (simgrip.sim.full_contact.check_grasp)
        if k in settle_kw:
            full[k] = settle_kw.pop(k)

    def build():
        with phase(progress, f"building the model ({links} links per finger)"):
            # forward=False: the settle follows at once and computes what it reads (bit-identical states)
            return build_scene(grip, params, profile, links, forward=False, **full)

    t0 = time.perf_counter()
    scene = build()
    build_time_s = time.perf_counter() - t0
    try:
        with phase(progress, "settling"):
            # sync=False: the cached scene is reset before its next use and nobody else sees its data
            state = settle(scene, method="newton" if auto else method, **{"sync": False, **settle_kw})
    except SettleError as exc:
        if not (auto and settle_kw.get("contact") in (None, "surface") and settle_kw.get("target_error") is None):
            raise
        kw = {k: v for k, v in settle_kw.items() if k not in ("contact", "tol", "max_steps")}
        t1 = time.perf_counter()
        scene = build()  # from the built state, not where the failed solve left the chain
        build_time_s += time.perf_counter() - t1
        try:
            with phase(progress, "settling by the dynamics (Newton failed)"):
                state = settle(scene, method="dynamics", **kw)
        except SettleError as exc2:
            raise SettleError(f"{exc}; the fallback to the dynamics failed too: {exc2}") from exc2
        state.warnings.insert(0, f"the default settle (Newton) failed ({exc}); this state is the over-damped "
                                 f"dynamics' (method 'dynamics', MuJoCo's surface contact and friction) instead")
    state.build_time_s = build_time_s
    return state


def _stability(state, grip, params, profile) -> float:
    """Smallest eigenvalue of the hinge chain's projected Hessian at the settled shape."""
    from simgrip import reference as discrete

    try:
        if grip == "III" and state.contact is not None:
            p = params.replace(b=2.0 * float(state.contact.point[0]))
            ch = discrete.solve_chain(
                grip, p, profile, state.links, gamma=state.contact.gamma,
                contact_moment=state.contact.moment, guess=state.link_angles[0],
            )
        else:
            C = float(state.contact.moment) if state.contact is not None and state.held else 0.0
            ch = discrete.solve_chain(grip, params, profile, state.links, contact_moment=C,
                                      guess=state.link_angles[0])
        return float(ch.min_eigenvalue)
    except (discrete.DiscreteError, ValueError):
        return math.nan


def settled_record(state, params: DimensionlessParams, profile=None) -> dict:
    """Record of a settled state in the fields of :func:`simgrip.report.elastica_record`.

    Adds ``wall_time_s`` (the settle alone), ``build_time_s`` (the model's build and compile),
    ``steps``, ``held``, ``penetration`` (over ``l``),
    ``residual``, ``links`` (the finest used), ``method``, ``warnings``, ``extrapolated`` and
    ``error_estimate`` (``settle(..., target_error=E)``: tip over ``l``, forces relative; else None),
    ``nodes`` and ``contacts`` (every contact on the finger: :mod:`simgrip.contact_report`); a held full-contact
    Grip I/II state also ``tip_normal_force`` and ``tip_friction_force`` (the contacts at the tip,
    :func:`simgrip.compare_full.tip_forces`; ``normal_force`` is the resultant of all).  ``feasible`` is the
    simulation's verdict: the workpiece is held, its contacts are surface contacts
    (``contact_ok``: none deeper than half the finger's radius, no Grip I/II tip past
    the face; the record then carries ``contact_ok: False``) and, Grip III, condition
    (23) holds (``tip_clear``: the tip below the contact, no part of the rod beyond the
    contact in the workpiece).  ``min_eigenvalue`` is the hinge chain's stability
    eigenvalue at this shape when ``profile`` is given.
    """
    params = as_dimensionless(params)
    c = state.contact
    grip = state.grip
    v = verdict_fields(state)
    rec = {
        "source": "simulation",
        "grip": grip,
        "links": int(state.links),
        "tip": v["tip"],
        "normal_force": v["normal_force"],
        "friction_force": float(state.friction_force),
        "required_mu": v["required_mu"],
        "feasible": v["feasible"],
        "valid": v["valid"],
        "min_eigenvalue": None if profile is None else _stability(state, grip, params, as_profile(profile)),
        "N1": float(state.N1),
        "N2": float(state.N2),
        **settle_fields(state),
        "method": state.method,
        "warnings": v["warnings"],
        "extrapolated": bool(state.extrapolated),
        "error_estimate": state.error_estimate,
        "params": {"D": params.D, "M": params.M, "b": params.b, "mu_s": params.mu_s, "gamma": params.gamma},
        "nodes": node_records(state),
        "contacts": contact_records(state),
    }
    if grip == "III" and c is not None:
        rec.update(
            contact=[float(c.point[0]), float(c.point[1])],
            gamma=float(c.gamma),
            n=float(c.normal),
            f=float(c.friction),
            contact_moment=float(c.moment),
        )
    if grip == "III" and c is not None and state.held:
        rec["tip_clear"] = bool(state.tip_clear)  # condition (23) (simgrip.validity), beside the reference's
    if not getattr(state, "contact_ok", True):
        rec["contact_ok"] = False  # a contact too deep or a tip past the face (simgrip.validity.check_contact_depth)
    if grip != "III" and c is not None:
        rec["contact_moment"] = float(c.moment)
    if grip in ("I", "II") and state.held and getattr(state, "contact_set", None) is not None:
        from simgrip.sim.scene import DEFAULT_R_TIP

        rec["tip_normal_force"], rec["tip_friction_force"] = tip_forces(state, DEFAULT_R_TIP)
    return rec


def verdict_fields(state) -> dict:
    """The fields of :func:`settled_record` that say what the settle found, without the per-node and per-contact
    lists (a sweep's row, :mod:`simgrip.sweep.point`): ``tip`` (finger 0's, over ``l``), ``normal_force``,
    ``required_mu`` (0 without a contact), ``feasible``, ``valid``, ``warnings``, and :func:`settle_fields`'
    (``held``, ``wall_time_s``, ``penetration``, ``converged``, ...); the same values as the record's."""
    tip = state.tip
    return {
        "tip": [float(tip[0][0]), float(tip[0][1])] if tip.ndim == 2 else [float(v) for v in tip],
        "normal_force": float(state.normal_force),
        "required_mu": float(state.required_mu) if state.contact is not None else 0.0,
        "feasible": (bool(state.held and state.tip_clear and getattr(state, "contact_ok", True))
                     if state.grip != "free" else True) and bool(getattr(state, "valid", True)),
        "valid": bool(getattr(state, "valid", True)),
        "warnings": list(state.warnings),
        **settle_fields(state),
    }


def settle_fields(state) -> dict:
    """The fields every simulation record shares: held, wall time [s] (the settle), build time [s] (the model's
    build and compile; None when the state was settled from a scene built elsewhere), steps, penetration [m],
    residual, converged."""
    build = getattr(state, "build_time_s", None)
    return {
        "held": bool(state.held),
        "wall_time_s": float(state.wall_time_s),
        "build_time_s": None if build is None else float(build),
        "steps": int(state.steps),
        "penetration": float(state.penetration),
        "residual": float(state.residual),
        "converged": bool(state.converged),
    }


def tip_forces(state, r_tip: float) -> tuple[float, float]:
    """``(N, F_f)`` over ``rho g l``: the normal and friction forces of finger 0's contacts with the workpiece
    within ``3 r_tip`` (over ``l``) of its tip node, from ``state.contact_set`` (a full-contact settle's)."""
    if state.contact_set is None:
        raise ValueError("state: a full-contact settle's state (contact='full') lists its contacts; this one does not")
    tip = np.asarray(state.nodes[0][-1], dtype=float)
    near = [c for c in state.contact_set if c["finger"] == 0 and c["with"] == "workpiece"
            and math.dist(c["point"], tip) < 3.0 * r_tip]
    return sum(c["normal_force"] for c in near), sum(c["friction_force"] for c in near)
