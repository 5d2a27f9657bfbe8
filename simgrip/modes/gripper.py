"""Modes of a K-finger gripper (:mod:`simgrip.gripper.scene`): K chains holding a workpiece free in 3-D.

The settled gripper (:func:`simgrip.gripper.settle.settle_gripper`) is linearised
as the planar scenes are (:mod:`.linear`): each finger's tip (its centreline end,
the point contact) sticks to the workpiece's material point in all three world
directions (the workpiece has six dofs; ``mj_integratePos`` steps its free
joint), and the workpiece's weight relief (``GripperScene.weight_relief``, an
applied force of the settles) enters the multipliers.  Its spectrum holds every
mode: the symmetric ones (all fingers alike, the workpiece moving vertically),
and those where the fingers differ and the workpiece sways, rocks or turns.

Beside it: the **symmetric** modes, the same eigenproblem restricted to the
subspace where every finger has the same joint motion and the workpiece moves
only vertically.  In an exactly symmetric scene (equal fingers evenly around a
centred cylinder, sphere or box) that subspace is invariant, so they are exact
modes of the gripper; they are those of the planar symmetric reduction with the
workpiece's inertial mass shared by the K fingers, and are compared with the
linearised rod (:mod:`.rod`) at that mass.
"""

from __future__ import annotations

import math
import time

import numpy as np

from simgrip.modes.linear import Stick, eigen, linearise

__all__ = ["gripper_modes", "gripper_sticks", "symmetric_basis"]


def gripper_sticks(scene, state, data) -> tuple:
    """Every touching finger's tip (centreline end of its last link) sticking to the workpiece, in x, y, z."""
    out = []
    wb = int(scene.workpiece_body)
    R = data.xmat[wb].reshape(3, 3)
    for rec in state.records:
        body = int(scene.index.link_body[rec.finger, -1])
        local = np.array([scene.length / scene.n, 0.0, 0.0])
        world = data.xpos[body] + data.xmat[body].reshape(3, 3) @ local
        out.append(Stick(body, local, wb, R.T @ (world - data.xpos[wb]), rows="xyz"))
    return tuple(out)


def symmetric_basis(scene) -> np.ndarray:
    """``(nv, n + 1)``: every finger's hinge ``j`` moving alike (one column per hinge), and the workpiece's
    vertical translation (the free joint's third dof)."""
    m = scene.model
    S = np.zeros((m.nv, scene.n + 1))
    for f in range(scene.fingers):
        S[scene.index.joint_dof[f], np.arange(scene.n)] = 1.0
    S[int(scene.workpiece_dof[2]), scene.n] = 1.0
    return S / np.linalg.norm(S, axis=0)


def gripper_modes(grip, params, profile, links, *, fingers: int, workpiece: str = "cylinder", count: int = 3,
                  reference: bool = True, progress=None, **settle_kw):
    """Natural frequencies of the settled K-finger gripper, its symmetric modes and the rod's.

    Parameters
    ----------
    grip : {"I", "II"}
    params : DimensionlessParams or PhysicalParams
    profile : CurvatureProfile, float or callable
        One profile for every finger.
    links, fingers, workpiece
        As :func:`simgrip.gripper.scene.build_gripper`.
    count : int
        Lowest modes of the whole gripper and of its symmetric subspace, ``1 <= count <= links - 1``.
    reference : bool
        Solve the linearised rod for the symmetric modes.
    settle_kw
        Passed to :func:`simgrip.gripper.settle.settle_gripper`.

    Returns
    -------
    dict
        ``frequencies`` (the gripper's lowest ``count``, ``omega sqrt(l/g)``), ``symmetric_frequencies``,
        ``reference_frequencies`` (None without ``reference``), ``relative_difference`` (symmetric against
        the rod), ``dofs``, ``settled`` (held, residual, the linearisation's misfit and asymmetry), ``wall_time_s``.
    """
    import mujoco

    from simgrip.modes import ModesError, reference_modes
    from simgrip.params import check_grip
    from simgrip.profiles import as_profile
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper.scene import build_gripper
    from simgrip.sim.scene import check_params

    grip = check_grip(grip)
    if grip not in ("I", "II"):
        raise ValueError(f"grip: the K-finger modes cover Grips I and II, got {grip!r}")
    dimless, phys = check_params(params)
    prof = as_profile(profile)
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 1 <= count <= int(links) - 1:
        raise ValueError(f"count must be an integer in [1, links - 1 = {int(links) - 1}], got {count!r}")
    from simgrip.progress import phase

    with phase(progress, f"building the model ({fingers} fingers x {links} links)"):
        scene = build_gripper(grip, params, prof, links, fingers=fingers, workpiece=workpiece)
    t0 = time.perf_counter()
    with phase(progress, "settling"):
        state = settle_gripper(scene, **settle_kw)
    t_settle = time.perf_counter() - t0
    if not state.held or len(state.records) != scene.fingers:
        raise ModesError(f"grip {grip}: the settled gripper does not hold the workpiece with every finger: there is "
                         f"no equilibrium of the grip to vibrate about")
    m = scene.model
    d = mujoco.MjData(m)
    d.qpos[:] = state.qpos
    mujoco.mj_kinematics(m, d)
    applied = np.zeros(m.nv)
    applied[int(scene.workpiece_dof[2])] = scene.weight_relief
    t1 = time.perf_counter()
    lin = linearise(scene, d, sticks=gripper_sticks(scene, state, d), applied=applied)
    t2 = time.perf_counter()
    count = int(count)
    if count > lin.dofs:
        raise ValueError(f"count must be at most {lin.dofs} (the gripper's degrees of freedom), got {count}")
    tscale = phys.length / phys.g
    w = eigen(lin.M, lin.K, lin.basis, count)[0] * tscale
    S = symmetric_basis(scene)
    import scipy.linalg as sla

    Ns = S @ sla.null_space(lin.jacobian @ S)
    ws = eigen(lin.M, lin.K, Ns, min(count, Ns.shape[1]))[0] * tscale
    t3 = time.perf_counter()

    def freq(x):
        return np.sqrt(np.where(x >= 0, x, np.nan))

    ref = rel = None
    times = {"settle": t_settle, "linearise": t2 - t1, "eigen": t3 - t2}
    if reference:
        t4 = time.perf_counter()
        mass = float(m.body_mass[scene.workpiece_body]) / scene.fingers / (phys.rho * phys.length)
        ref = reference_modes(grip, dimless, prof, ws.size, tip_mass=mass).omega
        rel = freq(ws) / ref - 1.0
        times["reference"] = time.perf_counter() - t4

    def lst(a):
        return None if a is None else [None if not math.isfinite(float(x)) else float(x) for x in a]

    return {"grip": grip, "links": scene.n, "fingers": scene.fingers, "workpiece": scene.workpiece, "count": count,
            "dofs": lin.dofs, "frequencies": lst(freq(w)), "symmetric_frequencies": lst(freq(ws)),
            "reference_frequencies": lst(ref), "relative_difference": lst(rel),
            "settled": {"held": bool(state.held), "residual": float(state.residual), "misfit": lin.misfit,
                        "asymmetry": lin.asymmetry},
            "wall_time_s": times}
