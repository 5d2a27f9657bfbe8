"""K-finger grippers end to end: build the scene, settle it, and its record (``simgrip simulate --fingers K``).

:func:`simulate_gripper` builds :func:`simgrip.gripper.scene.build_gripper` and
settles it with :func:`simgrip.gripper.settle.settle_gripper`;
:func:`gripper_record` turns the settled state into the fields of the planar
``simulate`` record (:func:`simgrip.compare.settled_record`), those of the
first finger at the top level, plus ``fingers``: one record per finger.
"""

from __future__ import annotations

import math
import time

from simgrip.compare import settle_fields
from simgrip.chain import check_link_count
from simgrip.params import DimensionlessParams, Grip, as_dimensionless
from simgrip.profiles import as_profile

__all__ = ["gripper_record", "simulate_gripper"]


def simulate_gripper(grip: str, params: DimensionlessParams, profile, links: int, *, fingers: int, workpiece: str,
                     yaw: float = 0.0, contact_angle: float = 0.0, offset=(0.0, 0.0), workpiece_yaw: float = 0.0,
                     progress=None, **settle_kw):
    """Build the K-finger gripper and settle it; returns its :class:`~simgrip.gripper.settle.GripperState`.

    ``profile`` is one profile or one per finger; ``yaw``, ``contact_angle`` [rad], ``offset`` (over l)
    and ``workpiece_yaw`` [rad] go to :func:`~simgrip.gripper.scene.build_gripper`, extra keywords
    (``method``: default ``"auto"``, the symmetry skip where the scene is exactly symmetric, else the
    dynamics; ``contact``, ``tol``, ...) to :func:`~simgrip.gripper.settle.settle_gripper`.  The state's
    ``build_time_s`` is the build and compile of the model [s] (``wall_time_s`` the settle alone);
    ``progress`` (:mod:`simgrip.progress`; None: silent) is told the phases.
    """
    from simgrip.progress import phase
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper.scene import _build_gripper, check_gripper

    from simgrip.sim.fingers import check_finger_links

    grip, K, shape = check_gripper(grip, fingers, workpiece)  # checked here, once; handed down as checked values
    links = check_finger_links(check_link_count(links))  # a Count, in [2, MAX_LINKS]: not checked again below
    if not isinstance(profile, (list, tuple)):
        profile = as_profile(profile)
    start = {}
    if grip == "III" and not isinstance(profile, (list, tuple)):
        from simgrip.scenes import start_angles  # the cradle starts where the theory does (the planar simulate's)

        start["initial_angles"] = start_angles(grip, params, profile, links)
    t0 = time.perf_counter()
    with phase(progress, f"building the model ({fingers} fingers x {links} links)"):
        if settle_kw.get("contact") == "full":  # every link touches (issue 17)
            start["contact"] = "full"
        scene = _build_gripper(grip, params, profile, links, K=K, shape=shape, yaw=yaw, contact_angle=contact_angle,
                               offset=offset, workpiece_yaw=workpiece_yaw, **start)
    build_time_s = time.perf_counter() - t0
    with phase(progress, "settling"):
        state = settle_gripper(scene, **settle_kw)
    state.build_time_s = build_time_s
    state.nodes = gripper_nodes(scene, state.link_angles)
    return state


def gripper_nodes(scene, link_angles) -> np.ndarray:
    """Each finger's centreline ``(K, n + 1, 3)`` over ``l`` in the scene's frame: finger ``k``'s plane is
    vertical at its azimuth (:attr:`~simgrip.gripper.scene.GripperScene.azimuths`, the whole scene's ``yaw`` in it)."""
    import numpy as np

    from simgrip.chain import link_positions

    out = []
    for k, phi in enumerate(np.asarray(link_angles, dtype=float)):
        xz = link_positions(phi, 1.0 / scene.n)
        a = float(scene.azimuths[k])
        out.append(np.stack([xz[:, 0] * math.cos(a), xz[:, 0] * math.sin(a), xz[:, 1]], axis=1))
    return np.array(out)


def _contacts(state) -> list:
    """Every contact on a finger: the full-contact settle's list, else one per finger that touches (its tip, in the
    scene's frame; ``normal_force`` and ``friction_force`` in the finger's plane, as ``fingers``)."""
    full = getattr(state, "contact_set", None)
    if full is not None:
        return list(full)
    nodes = getattr(state, "nodes", None)
    return [{"finger": int(r.finger), "link": int(state.links) - 1, "arc_length": 1.0, "with": "workpiece",
             "point": None if nodes is None else [float(v) for v in nodes[r.finger][-1]],
             "normal_force": float(r.normal), "friction_force": float(r.friction)}
            for r in (state.records if state.held else [])]


def _finger(state, k: int) -> dict:
    """Finger ``k``'s record; zero forces and no contact when it does not touch the workpiece."""
    rec = next((r for r in state.records if r.finger == k), None)
    if rec is None:
        return {"normal_force": 0.0, "friction_force": 0.0, "N1": 0.0, "N2": 0.0, "N3": 0.0,
                "tip": [float(state.tip[k][0]), float(state.tip[k][1])], "contact": None, "contact_angle": None,
                "contact_moment": 0.0, "required_mu": 0.0, "penetration": 0.0}
    return {
        "normal_force": float(rec.normal),
        "friction_force": float(rec.friction),
        "N1": float(rec.N1),
        "N2": float(rec.N2),
        "N3": float(rec.N3),
        "tip": [float(rec.tip[0]), float(rec.tip[1])],
        "contact": [float(v) for v in rec.point],
        "contact_angle": float(rec.contact_angle),
        "contact_moment": float(rec.moment),
        "required_mu": float(rec.required_mu),
        "penetration": float(rec.penetration),
    }


def _stability(state, params: DimensionlessParams, profile) -> float:
    """Smallest eigenvalue of the hinge chain's projected Hessian at finger 0's settled shape (NaN if none)."""
    from simgrip import reference as discrete

    try:
        if state.held and state.records:
            r = state.records[0]
            p = params.replace(b=2.0 * float(r.tip[0]))  # finger 0's settled tip X (off-centre, inclined contact)
            ch = discrete.solve_chain(state.grip, p, profile, state.links, contact_moment=r.moment,
                                      guess=state.link_angles[0])
        else:
            ch = discrete.solve_chain(Grip.FREE, params, profile, state.links, guess=state.link_angles[0])
        return float(ch.min_eigenvalue)
    except (discrete.DiscreteError, ValueError):
        return math.nan


def gripper_record(state, params: DimensionlessParams, profile=None) -> dict:
    """JSON-ready record of a settled gripper (dimensionless).

    Top level: the planar ``simulate`` record's fields for finger 0
    (``tip``, ``normal_force``, ``friction_force``, ``required_mu``, ``N1``,
    ``N2``; zeros when dropped), ``held`` and ``feasible`` for the workpiece
    (``feasible``: held and, Grip III, condition (23) met: ``state.tip_clear``), ``valid`` (no finger
    through itself, another or the workpiece: :func:`simgrip.validity_shapes.check_gripper_valid`),
    the settle's ``steps``, ``residual``, ``penetration``, ``wall_time_s``, ``build_time_s`` (the model's),
    ``method`` (which settle ran: ``"symmetric"``, the symmetry skip, or
    ``"dynamics"``) and ``contact`` (where the friction acts: ``"point"`` or
    ``"surface"``); then ``fingers``: one record per finger (``normal_force``,
    ``friction_force``, ``N1``, ``N2``, ``N3``, ``tip``, ``contact`` (X, Y,
    out of plane), ``contact_angle``, ``contact_moment``, ``required_mu``,
    ``penetration``; zero forces and ``contact`` None for a finger off the
    workpiece), ``workpiece``, ``workpiece_position``, ``offset``,
    ``workpiece_yaw`` and the workpiece's ``force_balance`` / ``moment_balance``.
    Angles (``contact_angle``, ``workpiece_yaw``) are in radians, whatever the
    command line took (degrees).
    """
    params = as_dimensionless(params)
    first = state.records[0] if state.records else None
    return {
        "source": "simulation",
        "grip": state.grip,
        "links": int(state.links),
        "tip": [float(state.tip[0][0]), float(state.tip[0][1])],
        "normal_force": float(first.normal) if first else 0.0,
        "friction_force": float(first.friction) if first else 0.0,
        "required_mu": float(first.required_mu) if first else 0.0,
        "feasible": bool(state.held and getattr(state, "tip_clear", True) and getattr(state, "valid", True)),
        "valid": bool(getattr(state, "valid", True)),
        "min_eigenvalue": None if profile is None else _stability(state, params, as_profile(
            profile[0] if isinstance(profile, (list, tuple)) else profile)),
        "N1": float(first.N1) if first else 0.0,
        "N2": float(first.N2) if first else 0.0,
        **settle_fields(state),
        "method": state.method,
        "contact": state.contact,
        "warnings": list(state.warnings),
        "extrapolated": False,
        "error_estimate": None,
        "params": {"D": params.D, "M": params.M, "b": params.b, "mu_s": params.mu_s, "gamma": params.gamma},
        "workpiece": state.workpiece,
        "fingers": [_finger(state, k) for k in range(state.fingers)],
        "workpiece_position": [float(v) for v in state.workpiece_position],
        "offset": [float(v) for v in getattr(state, "offset", (0.0, 0.0))],
        "workpiece_yaw": float(getattr(state, "workpiece_yaw", 0.0)),
        "force_balance": [float(v) for v in state.force_balance],
        "moment_balance": [float(v) for v in state.moment_balance],
        "nodes": None if getattr(state, "nodes", None) is None else [[[float(v) for v in p] for p in f]
                                                                      for f in state.nodes],
        "contacts": _contacts(state),
    }
