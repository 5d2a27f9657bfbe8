"""The symmetry skip of a K-finger gripper: one finger's planar settle, replicated to K fingers.

Where a K-finger scene (:mod:`simgrip.gripper.scene`) is exactly symmetric,
every finger is the same planar problem and the workpiece only slides along
the palm axis, so the K-finger settled state is one planar finger's, turned
to every azimuth.  :func:`settle_symmetric` settles that one finger with the
planar static settle (:func:`simgrip.settle.settle`: Newton in link angles,
tridiagonal, :mod:`simgrip.settle.chain_newton`) and returns a
:class:`~simgrip.gripper.settle.GripperState` with the same fields as the
K-finger dynamics (:func:`simgrip.gripper.settle.settle_gripper`).

Exactness (:func:`~simgrip.gripper.scene_symmetry.symmetry`) is read from the compiled
model: identical fingers evenly spaced about the palm axis, the workpiece on
it, every finger meeting the same surface head on.

**The planar problem.**  Box and cylinder: the planar symmetric reduction
(:func:`simgrip.scenes.build_scene` with one finger and a workpiece of mass
``M`` sliding in ``z``, the same ``n``, profile, radii and gravity).  Sphere
at contact elevation ``beta``: the same rod problem at width ``b cos beta``
(:mod:`simgrip.reference.inclined`: each finger carries ``M`` vertically and
its tip sits at ``X = (b/2) cos beta``), settled with a friction
coefficient of 100 (the model's largest: the planar cone binds only
where ``N1 < M/100``, and that finger is taken as dropped; ``N1 <= 0`` drops
it as the dynamics does); the sphere's own cone then decides
(``|F_f| <= mu_s N`` along the sphere's normal), and a dropped sphere leaves
the fingers to settle alone (the planar free finger).  The contact is the
planar settle's: ``contact="point"`` (default, the paper's point contact:
friction on the centreline) or ``"surface"`` (box and cylinder: at MuJoCo's
contact point, the finite-radius couple, as the dynamics).

**Replication and the judge.**  Finger ``k`` takes the planar hinge angles;
the workpiece sits on the axis, as high relative to the tips as the planar
one (sphere: its centre ``b/2`` minus the planar penetration from every
tip), oriented as built.  The contact force on finger ``k`` is ``N1 E1_k +
N2 z`` at its tip centre plus the planar couple about ``E1_k x z``, and
minus that on the workpiece.  The reported ``residual`` is MuJoCo's static
balance of the K-finger model at that state under those forces (springs and
gravity from ``mj_passive``/``mj_rne`` at rest, the forces by
``mj_applyFT``), scaled per dof as the dynamics' (hinges and rotation over
``rho g l^2``, translation over ``rho g l``); penetration and contact points
are MuJoCo's collision in the K-finger scene.  The hinge rows are the planar
finger's, the workpiece's horizontal and rotation rows cancel by symmetry,
and its vertical row adds K fingers' vertical rows, so ``tolerance`` is
``K`` times the planar state's.  The contact's force law is the planar
settle's (its stiff static contact, :mod:`simgrip.settle.statics`), not the
dynamics' softer one, so the penetration is smaller than the dynamics'.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import mujoco
import numpy as np

from simgrip.settle.state import SettleError
from simgrip.gripper.scene import GripperScene
from simgrip.gripper.scene_symmetry import EQUAL_RTOL, Symmetry, cradle_edges, symmetry
from simgrip.validity import check_grip_shape

__all__ = ["GRIPPER_METHODS", "Symmetry", "planar_scene", "settle_cradle_dynamics", "settle_symmetric",
           "symmetric_or_none", "symmetry"]

#: ``settle_gripper(method=...)``: the over-damped dynamics, the symmetry skip, or the skip where exact.
GRIPPER_METHODS = ("dynamics", "symmetric", "auto")
#: Friction coefficient of the sphere's planar problem (the model's largest): the planar cone binds only
#: where ``N1 < M / 100``, the sphere's own cone decides.
_NEVER_BINDS = 100.0


def _planar_params(scene: GripperScene, beta: float):
    """The planar problem's parameters in the scene's own units (the sphere's: width ``b cos beta``)."""
    p = scene.physical
    if scene.workpiece != "sphere":
        return p
    return replace(p, b=p.b * math.cos(beta), mu_s=_NEVER_BINDS)


def planar_scene(scene: GripperScene, grip: str | None = None):
    """The one-finger planar scene of ``scene``'s per-finger problem (built, not settled).

    ``grip``: default the scene's; ``"free"`` for the finger alone.  Same ``n``,
    profile, radii and gravity (the model's ``opt.gravity``) as ``scene``.
    """
    from simgrip.scenes import build_scene

    beta = float(np.atleast_1d(scene.contact_angle)[0]) if scene.workpiece == "sphere" else 0.0
    g = scene.grip if grip is None else grip
    if g == "III":
        pl = _planar_cradle(scene)
    else:
        pl = build_scene(g, _planar_params(scene, beta), scene.profile, scene.n, r_tip=scene.r_tip,
                         r_link=scene.r_link)
    pl.model.opt.gravity[:] = scene.model.opt.gravity
    gbit = int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
    pl.model.opt.disableflags = (int(pl.model.opt.disableflags) & ~gbit) | (int(scene.model.opt.disableflags) & gbit)
    return pl


def _planar_cradle(scene: GripperScene):
    """The planar Grip III scene of the K = 4 cradle: the start it was built with, so the same box and contact links.

    As the planar cradle's settle, every settle of the scene starts from the shape the box was placed on
    (:func:`simgrip.gripper.cradle.cradle_start_angles`), not from the state a previous settle left.
    """
    from simgrip.gripper.cradle import cradle_start_angles
    from simgrip.sim.scene import build_scene as build_model

    m, L = scene.model, scene.length
    edge = cradle_edges(scene)[0]
    q_start = cradle_start_angles(m)
    pl = build_model(scene.grip, scene.physical, scene.profile, scene.n, r_tip=scene.r_tip, r_link=scene.r_link,
                     r_corner=float(m.geom_size[edge][0]) / L, initial_angles=q_start)
    pm = pl.model
    links = sorted(int(np.nonzero(scene.index.link_geom[0] == m.pair_geom1[i])[0][0])
                   for i in range(m.npair) if int(m.pair_geom2[i]) == edge)
    plinks = sorted(int(np.nonzero(pl.index.link_geom[0] == pm.pair_geom1[i])[0][0]) for i in range(pm.npair))
    same = (abs(float(pl.box_half[0]) - float(scene.size[0])) <= EQUAL_RTOL * L
            and abs(float(pl.box_half[2]) - float(scene.size[2])) <= EQUAL_RTOL * L
            and abs(float(pm.body_pos[pl.workpiece_body][2]) - float(m.qpos0[scene.workpiece_qpos[2]])) <= EQUAL_RTOL * L
            and links == plinks)
    if not same:
        raise ValueError("scene: the planar cradle from its start shape is not its box and contact links (the "
                         "model was changed after building)")
    return pl


def symmetric_or_none(scene: GripperScene, method: str | None, *, contact: str | None = None, **kw):
    """``settle_gripper``'s hook: the skip's state for ``method`` ``"symmetric"`` or ``"auto"``, else None.

    ``None`` (settle_gripper's default) is ``"auto"``: the skip where the scene
    is exactly symmetric (:func:`symmetry`), else None (the caller settles it
    by dynamics); Grip III, which has no K-finger dynamics, raises ValueError
    naming ``method`` where it is not symmetric.  ``"symmetric"`` raises there
    too; ``"dynamics"`` returns None (and raises for Grip III).  ``contact``:
    the skip's (:func:`settle_symmetric`, default ``"point"``); the dynamics
    has MuJoCo's surface contact only, so ``"point"`` raises ValueError naming
    ``contact`` where the dynamics runs.  ``kw`` go to :func:`settle_symmetric`.
    """
    t0 = time.perf_counter()
    if method is None:
        method = "auto"
    if method not in GRIPPER_METHODS:
        raise ValueError(f"method must be one of {GRIPPER_METHODS}, got {method!r}")
    if contact is not None and contact not in ("point", "surface"):
        raise ValueError(f"contact must be 'point' or 'surface', got {contact!r}")
    if method == "dynamics":
        if isinstance(scene, GripperScene) and scene.grip == "III":
            raise ValueError("method: the K-finger cradle (Grip III) has no dynamic settle; it is settled by the "
                             "symmetry skip (method 'symmetric' or 'auto')")
        _dynamics_contact(contact)
        return None
    sym = symmetry(scene)
    if not sym.exact:
        if method == "auto" and scene.grip != "III":
            _dynamics_contact(contact)
            return None
        raise ValueError(f"method '{method}' needs an exactly symmetric scene: {sym.reason}")
    return _settle_exact(scene, t0, contact=contact or "point", **kw)


def _dynamics_contact(contact: str | None) -> None:
    """The dynamics' contact is MuJoCo's, on the tip sphere's surface: ValueError naming ``contact`` otherwise."""
    if contact not in (None, "surface"):
        raise ValueError(f"contact: the K-finger dynamics has MuJoCo's surface contact only (the point contact is "
                         f"the symmetry skip's, for exactly symmetric scenes), got {contact!r}")


def settle_symmetric(scene: GripperScene, *, tol: float | None = None, max_steps: int | None = None,
                     contact: str = "point", allow_unconverged: bool = False, planar=None):
    """Settle an exactly symmetric K-finger scene from one finger's planar settle (see the module docstring).

    Parameters
    ----------
    scene : GripperScene
        Exactly symmetric (:func:`symmetry`), else ValueError naming ``scene``.
    tol : float, optional
        The planar settle's static residual tolerance (default its own,
        :data:`simgrip.settle.DEFAULT_TOL`); the K-finger state's
        ``tolerance`` is ``K`` times the planar state's.
    max_steps : int, optional
        The planar settle's Newton iteration budget.
    contact : {"point", "surface"}
        Where the sticking friction acts (:func:`simgrip.settle.settle`);
        ``"surface"`` for box and cylinder only.
    allow_unconverged : bool
        Return ``converged=False`` instead of raising :class:`SettleError`.
    planar : Scene, optional
        A scene from :func:`planar_scene` of this ``scene`` to reuse (built
        here when None).  Grips I/II settle from the hinge chain's start
        whatever state the planar scene was left in, so reusing it gives the
        same state bit for bit and saves its build.

    Returns
    -------
    GripperState
        ``steps`` counts the planar Newton iterations; ``velocity`` and ``timestep`` are 0.
    """
    t0 = time.perf_counter()
    sym = symmetry(scene)
    if not sym.exact:
        raise ValueError(f"scene is not exactly symmetric ({sym.reason}): settle it with method='dynamics'")
    return _settle_exact(scene, t0, tol=tol, max_steps=max_steps, contact=contact, allow_unconverged=allow_unconverged,
                         planar=planar)


def _settle_exact(scene: GripperScene, t0: float, *, tol=None, max_steps=None, contact: str = "point",
                  allow_unconverged: bool = False, planar=None, planar_method: str = "newton"):
    """:func:`settle_symmetric` of a scene already found exactly symmetric (``t0``: when the settle began).

    ``planar_method``: the planar settle's method; ``"dynamics"`` (MuJoCo's surface contact) is the K = 4
    cradle's fallback where its Newton settle fails (:func:`settle_cradle_dynamics`).
    """
    from simgrip.settle import settle

    if contact not in ("point", "surface"):
        raise ValueError(f"contact must be 'point' or 'surface', got {contact!r}")
    if contact == "surface" and scene.workpiece == "sphere":
        raise ValueError("contact: 'surface' puts the vertical face's couple on the tip; the sphere's skip is "
                         "the point contact only")
    kw = {k: v for k, v in (("tol", tol), ("max_steps", max_steps)) if v is not None}
    pst = settle(_check_planar(scene, planar), contact=contact, allow_unconverged=allow_unconverged,
                 method=planar_method, **kw)
    tolerance = scene.fingers * float(pst.tolerance)
    # The planar settle reports a contact equilibrium in the other grip's shape (a finger curled away from the
    # workpiece that still presses on it from the other side of the palm) as not held, with a "wrong grip"
    # warning (check_grip_shape); its finger still carries the workpiece.  Replicated unloaded, that shape would
    # not balance (the residual is the workpiece's weight: "did not converge").  So the mechanical state is
    # replicated held, and the K-finger grip-shape check reports it not held with its own warning, as the
    # K-finger dynamics does.
    wrong_grip = not pst.grip_matched and pst.contact is not None
    # likewise an impossible planar state (issue 17: simgrip.validity.check_valid, not held): replicated as the
    # mechanical state it is, then the K-finger check (check_gripper_valid) reports it not held, not valid
    impossible = not getattr(pst, "valid", True) and pst.contact is not None
    held = bool(pst.held) or wrong_grip or impossible
    if wrong_grip:
        pst = replace(pst, warnings=[w for w in pst.warnings if not w.startswith("wrong grip:")])
    converged = bool(pst.converged)
    steps = int(pst.steps)
    if held and scene.workpiece == "sphere":
        held = _sphere_holds(scene, pst)
    if not held and scene.workpiece == "sphere" and (pst.held or wrong_grip or impossible):
        # the sphere's cone fails: it drops, and the fingers settle alone
        alone = settle(planar_scene(scene, "free"), allow_unconverged=allow_unconverged, **kw)
        converged, steps = converged and bool(alone.converged), steps + int(alone.steps)
        tolerance = max(tolerance, float(alone.tolerance))
        pst = alone
    state = _replicate(scene, pst, held, converged, steps, tolerance, allow_unconverged, t0)
    state.contact = contact
    if planar_method == "dynamics":
        state.method = "dynamics"
    return state


def settle_cradle_dynamics(scene: GripperScene, *, tol=None, max_steps=None, allow_unconverged: bool = False):
    """The K = 4 cradle (Grip III, exactly symmetric) settled by one finger's planar dynamics, replicated.

    The cradle has no K-finger dynamics; each of its fingers is exactly the planar Grip III problem, so the
    planar over-damped dynamics (``settle(method="dynamics")``, MuJoCo's surface contact) of that problem,
    replicated as the skip replicates its Newton state, is the cradle's dynamic settle.  ``method`` of the
    state is ``"dynamics"``, ``contact`` ``"surface"``; ``tol``/``max_steps`` are the planar dynamics'.
    """
    t0 = time.perf_counter()
    if scene.grip != "III":
        raise ValueError(f"scene: settle_cradle_dynamics settles the Grip III cradle, got Grip {scene.grip}")
    sym = symmetry(scene)
    if not sym.exact:
        raise ValueError(f"scene is not exactly symmetric ({sym.reason})")
    return _settle_exact(scene, t0, tol=tol, max_steps=max_steps, contact="surface",
                         allow_unconverged=allow_unconverged, planar_method="dynamics")


def _check_planar(scene: GripperScene, planar):
    """``planar`` if it is ``scene``'s planar problem (ValueError naming ``planar`` otherwise), or a new one."""
    from simgrip.sim.scene import Scene

    if planar is None:
        return planar_scene(scene)
    if scene.grip == "III":
        raise ValueError("planar: Grip III settles from the scene's start shape; its planar scene is built anew")
    if not isinstance(planar, Scene):
        raise ValueError(f"planar must be a simgrip.sim.scene.Scene from planar_scene(scene), got "
                         f"{type(planar).__name__}")
    m, pm = scene.model, planar.model
    same = (planar.grip == scene.grip and planar.n == scene.n and planar.fingers == 1 and planar.has_workpiece
            and (planar.r_tip, planar.r_link) == (scene.r_tip, scene.r_link)
            and np.array_equal(pm.qpos_spring[planar.joint_qpos[0]], m.qpos_spring[scene.joint_qpos[0]])
            and np.allclose(pm.jnt_stiffness[pm.dof_jntid[planar.joint_dof[0]]],
                            m.jnt_stiffness[m.dof_jntid[scene.joint_dof[0]]], rtol=EQUAL_RTOL, atol=0.0)
            and np.array_equal(pm.opt.gravity, m.opt.gravity)
            and planar.physical == _planar_params(scene, float(np.atleast_1d(scene.contact_angle)[0])))
    if not same:
        raise ValueError("planar is not this scene's planar problem (grip, links, radii, springs, gravity "
                         "or parameters differ): build it with planar_scene(scene)")
    return planar


def _check_cradle(scene: GripperScene, state, phi, gamma: float) -> None:
    """The K = 4 cradle is well-posed only where the fingers beyond the contact stay off the palm axis.

    The four fingers' planes meet on the palm axis; finger points at ``X_k, X_j`` in two perpendicular
    planes lie at least ``sqrt(X_k^2 + X_j^2) >= sqrt(2) min X`` apart, so ``X > sqrt(2) r_link``
    beyond ``gamma`` keeps the link capsules apart (there is no contact pair between fingers).
    Otherwise the state is reported not held, with a warning.
    """
    from simgrip.chain import link_positions

    nodes = link_positions(phi, 1.0 / scene.n)
    beyond = nodes[np.arange(scene.n + 1) / scene.n > gamma + 1e-12]
    if beyond.size and float(np.min(beyond[:, 0])) <= math.sqrt(2.0) * scene.r_link:
        state.held = False
        state.grip_matched = False
        state.warnings.append(f"the fingers beyond the contact reach the palm axis (X = {np.min(beyond[:, 0]):.3g} l "
                              f"<= sqrt(2) r_link): the four fingers would pass through each other; the state is "
                              f"reported as not held")


def _sphere_holds(scene: GripperScene, pst) -> bool:
    """The sphere's cone at the planar contact: ``N > 0`` and ``|F_f| <= mu_s N`` along the sphere's normal."""
    beta = float(np.atleast_1d(scene.contact_angle)[0])
    c, s = math.cos(beta), math.sin(beta)
    normal = pst.N1 * c + pst.N2 * s
    friction = -pst.N1 * s + pst.N2 * c
    return bool(normal > 0.0 and abs(friction) <= float(scene.physical.mu_s) * normal)


def _replicate(scene: GripperScene, pst, held: bool, converged: bool, steps: int, tolerance: float,
               allow_unconverged: bool, t0: float):
    """The K-finger state from the planar state ``pst`` (see the module docstring)."""
    from simgrip.gripper.start import warn_unreached
    from simgrip.gripper.state import FingerRecord, GripperState, warn_friction_boundary

    m, d, K = scene.model, scene.data, scene.fingers
    L, W = scene.length, scene.force_scale
    q_finger = np.asarray(pst.joint_angles[0], dtype=float)
    phi = np.cumsum(q_finger)
    tip = np.asarray(pst.tip[0], dtype=float)
    qpos = np.array(m.qpos0)
    qpos[scene.joint_qpos] = q_finger[None, :]
    wq = scene.workpiece_qpos
    if held:
        if scene.workpiece == "sphere":
            # on the axis, the planar penetration deep into every tip
            r = 0.5 * scene.params.b - float(pst.penetration)
            qpos[wq[2]] = (tip[1] - math.sqrt(max(r * r - tip[0] ** 2, 0.0))
                           * (1.0 if float(np.atleast_1d(scene.contact_angle)[0]) >= 0 else -1.0)) * L
        else:
            qpos[wq[2]] = float(pst.workpiece_pose[1]) * L  # the planar workpiece's height (same root)
    d.qpos[:] = qpos
    d.qvel[:] = 0.0
    d.qfrc_applied[:] = 0.0
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_comVel(m, d)
    wb = scene.workpiece_body
    centre = np.array(d.xpos[wb])
    frames = [scene.frame(k) for k in range(K)]
    forces, torques, points = [], [], []
    if held:
        c = pst.contact
        for k in range(K):
            e1, e3 = frames[k][0], np.cross(frames[k][0], [0.0, 0.0, 1.0])  # E1 x z: the planar moment's axis
            F = W * (c.N1 * e1 + c.N2 * np.array([0.0, 0.0, 1.0]))
            tau = W * L * c.moment * e3
            if scene.grip == "III":  # at the centreline point at gamma, on the link that carries it
                p = L * (float(c.point[0]) * e1 + np.array([0.0, 0.0, float(c.point[1])]))
                body = int(scene.index.link_body[k, min(int(c.gamma * scene.n), scene.n - 1)])
            else:  # at the tip's centre
                p = np.array(d.geom_xpos[scene.tip_geom[k]])
                body = int(m.geom_bodyid[scene.tip_geom[k]])
            mujoco.mj_applyFT(m, d, F, tau, p, body, d.qfrc_applied)
            mujoco.mj_applyFT(m, d, -F, -tau, p, wb, d.qfrc_applied)
            forces.append(F)
            torques.append(tau)
            points.append(p)
    d.qfrc_applied[scene.workpiece_dof[2]] += scene.weight_relief  # the model's gravity less the true weight
    mujoco.mj_passive(m, d)
    mujoco.mj_rne(m, d, 0, d.qfrc_bias)
    fscale = np.full(m.nv, scene.moment_scale)
    fscale[scene.workpiece_dof[:3]] = W
    r = (d.qfrc_applied + d.qfrc_passive - d.qfrc_bias) / fscale
    if not held:
        r[scene.workpiece_dof] = 0.0  # parked
    residual = float(np.max(np.abs(r)))
    # MuJoCo's collision at the state (the scene's own options), the data left there at rest
    d.qfrc_applied[:] = 0.0
    mujoco.mj_forward(m, d)
    records, pen_max = [], 0.0
    total_f, total_m = np.zeros(3), np.zeros(3)
    edges = cradle_edges(scene) if scene.grip == "III" else None
    for k in range(K if held else 0):
        if edges is None:
            mine, other = {int(scene.tip_geom[k])}, int(scene.workpiece_geom)
        else:
            mine, other = set(int(g) for g in scene.index.link_geom[k]), edges[k]
        cons = [i for i in range(d.ncon) if int(d.contact.geom1[i]) in mine and int(d.contact.geom2[i]) == other]
        if not cons:
            raise SettleError(f"symmetric settle: finger {k} does not touch the workpiece at the replicated "
                              f"state (the planar state is not the K-finger scene's)")
        i = min(cons, key=lambda j: float(d.contact.dist[j]))  # the deepest
        pen = -float(d.contact.dist[i]) / L
        nvec = -np.asarray(d.contact.frame[i])[:3]  # from the workpiece into the finger
        R = frames[k]
        nk = R @ nvec
        n2d = np.array([nk[0], nk[2]]) / math.hypot(nk[0], nk[2])
        t2d = np.array([-n2d[1], n2d[0]])
        Fk = R @ forces[k] / W
        F2d = np.array([Fk[0], Fk[2]])
        normal, friction = float(F2d @ n2d), float(F2d @ t2d)
        pk = R @ np.asarray(d.contact.pos[i]) / L
        tangential = math.sqrt(max(float(Fk @ Fk) - normal ** 2, 0.0))
        need = tangential / normal if normal > 0 else math.inf
        angle = float(math.atan2(n2d[1], n2d[0]))
        if edges is not None:  # the theory's frame at gamma: n along e2 = E3 x e1, f along e1 (the planar reading)
            c = pst.contact
            normal, friction, need = float(c.normal), float(c.friction), float(c.required_mu)
            angle = math.remainder(float(c.theta) + 0.5 * math.pi, 2.0 * math.pi)
        records.append(FingerRecord(
            finger=k, N1=float(Fk[0]), N2=float(Fk[2]), N3=float(Fk[1]), normal=normal, friction=friction,
            contact_angle=angle, tip=tip.copy(), point=np.array([pk[0], pk[2], pk[1]]),
            moment=float(pst.contact.moment), penetration=pen, required_mu=need))
        pen_max = max(pen_max, pen)
        total_f -= forces[k]
        total_m += np.cross(points[k] - centre, -forces[k]) - torques[k]
    if held:
        total_f += scene.workpiece_mass * np.asarray(m.opt.gravity)  # the true weight (not the inertia floor)
    state = GripperState(
        grip=scene.grip, workpiece=scene.workpiece, fingers=K, links=scene.n,
        joint_angles=np.tile(q_finger, (K, 1)), link_angles=np.tile(phi, (K, 1)), tip=np.tile(tip, (K, 1)),
        records=records, held=held, converged=bool(converged and residual <= tolerance), residual=residual,
        tolerance=tolerance, velocity=0.0, penetration=pen_max,
        force_balance=total_f / W if held else np.zeros(3),
        moment_balance=total_m / (W * L) if held else np.zeros(3),
        workpiece_position=centre / L, workpiece_quat=np.array(d.xquat[wb]), steps=steps, timestep=0.0,
        wall_time_s=time.perf_counter() - t0, qpos=np.array(d.qpos))
    state.method = "symmetric"
    state.tip_clear = bool(getattr(pst, "tip_clear", True)) if held else True
    state.warnings.extend(pst.warnings)
    if scene.grip == "III" and held:
        _check_cradle(scene, state, phi, float(pst.contact.gamma))
    warn_friction_boundary(scene, state)
    warn_unreached(scene, state)
    if not state.converged and not allow_unconverged:
        raise SettleError(f"symmetric settle did not converge (K-finger residual {residual:.3g} above the tolerance "
                          f"{tolerance:.3g}, {steps} planar Newton iterations)")
    check_grip_shape(scene, state)
    state.warnings[:] = list(dict.fromkeys(state.warnings))  # the replicated planar state's and the K-finger's own
    return state
