"""The settled state: what a settle returns, and the one reader that builds it.

:class:`SettledState` and :class:`FingerContact` are dimensionless (lengths over
``l``, forces over ``rho g l``).  :func:`read_state` reads both methods' results
from MuJoCo's data: the finger shape from the hinge angles, each finger's
contact force from MuJoCo's contacts (plus, for the static solve, the sticking
friction forces it carries as multipliers), expressed in the theory's frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import link_positions
from simgrip.sim.checks import PhysicsError
from simgrip.sim.scene import Scene
from simgrip.sim.workpiece_motion import workpiece_pose

__all__ = ["SettleError", "FingerContact", "SettledState", "finger_tip", "read_state", "workpiece_pose"]


class SettleError(PhysicsError):
    """The settle diverged (NaN, MuJoCo warning) or did not converge."""


@dataclass
class FingerContact:
    """The workpiece's contact on one finger (dimensionless: over ``l`` and ``rho g l``).

    ``N1, N2`` are the force on the rod in the finger's frame (``E1`` away from
    the palm centre, ``E2`` up); ``normal``/``friction`` are those the theory
    uses (I/II: ``N1`` and ``N2``; III: ``n`` along ``e2`` and ``f`` along
    ``e1``); ``gamma`` is the contact's arc length (1 for the tip);
    ``point`` the contact on the centreline (``X(gamma), Y(gamma)``);
    ``required_mu`` is ``|friction| / normal`` in the theory's frame and
    ``required_mu_contact`` the same ratio in MuJoCo's contact frame, the one
    its friction cone (and so hold/drop) uses: identical for Grips I/II; for
    Grip III the contact normal is the carrying link's normal, which differs
    from the centreline's at ``gamma`` by ``O(ds)``.
    ``moment`` the couple (E3, over ``rho g l^2``) the contact force exerts
    about that centreline point because it acts at the geoms' surface
    (measured from MuJoCo's contact position; ``~ -r_tip F_f`` for I/II,
    ``~ r_link f`` for III): pass it as ``contact_moment`` to the references.
    """

    N1: float
    N2: float
    normal: float
    friction: float
    gamma: float
    point: np.ndarray
    theta: float
    moment: float
    penetration: float
    required_mu: float
    required_mu_contact: float = math.nan


@dataclass
class SettledState:
    """A settled scene, dimensionless (lengths over ``l``, forces over ``rho g l``).

    Per-finger arrays have a leading axis of length ``fingers``; each finger is
    read in its own frame (``x`` away from the palm centre), so a mirrored
    finger reads like finger 0.
    """

    grip: str
    links: int
    fingers: int
    joint_angles: np.ndarray
    link_angles: np.ndarray
    nodes: np.ndarray
    tip: np.ndarray
    contacts: list
    workpiece_pose: np.ndarray | None
    held: bool
    steps: int
    newton_iterations: int
    forward_calls: int
    wall_time_s: float
    residual: float
    penetration: float
    converged: bool
    qpos: np.ndarray = field(repr=False)
    #: Seconds to build and compile the model (:func:`simgrip.compare.simulate`);
    #: ``wall_time_s`` is the settle alone.  None when the state was settled from a scene built elsewhere.
    build_time_s: float | None = None
    #: ``"newton"`` or ``"dynamics"``.
    method: str = "newton"
    #: Largest velocity at the end (dynamics; rad or l per sqrt(l/g)); 0 for Newton.
    velocity: float = 0.0
    #: Time step of the dynamic settle [s]; 0 for Newton.
    timestep: float = 0.0
    #: Grip III condition (23): no link beyond the contact reaches the workpiece's bottom face.
    tip_clear: bool = True
    #: ``settle(..., target_error=E)``: tip and contact forces are Richardson-extrapolated (:mod:`.target`).
    extrapolated: bool = False
    #: Estimated error of the extrapolated values: ``{"tip": over l, "force": relative}``; None otherwise.
    error_estimate: dict | None = None
    #: No contact pressed deeper than half the finger's radius, no Grip I/II tip past the face
    #: (:func:`simgrip.validity.check_contact_depth`); False: the verdict is not trusted (see ``warnings``).
    contact_ok: bool = True
    #: Grips I/II: the state has the shape of the grip asked for (:func:`simgrip.validity.check_grip_shape`).
    grip_matched: bool = True
    #: A physical state: no self-crossing, no link through another, a finger or the workpiece
    #: (:func:`simgrip.validity.check_valid`); False: ``held`` is False and ``warnings`` names the violation.
    valid: bool = True
    #: Conditions the state violates that the solve itself does not enforce (e.g. condition (23)).
    warnings: list = field(default_factory=list)
    #: Hinge rest angles (``springs.rest``) the state was settled with (a dynamic warm start ramps from them).
    rest: np.ndarray | None = field(default=None, repr=False)
    #: Effective residual tolerance: ``converged`` means ``residual <= tolerance``.  ``max(tol, floor)``
    #: with the contact-law round-off floor (Newton, :meth:`Newton.noise_floor`, capped at
    #: :data:`RESIDUAL_FLOOR_MAX`); the requested ``tol`` for dynamics and contact-free states.
    tolerance: float = math.nan
    #: Every contact of a finger, one record each (:func:`simgrip.settle.full_contact.contact_set`): filled by the
    #: full-contact settle (``contact="full"``); None otherwise (the point and surface settles' contacts are
    #: ``contacts``, one per finger).
    contact_set: list | None = None

    # convenience accessors for finger 0 --------------------------------------
    @property
    def contact(self) -> FingerContact | None:
        return self.contacts[0] if self.contacts else None

    @property
    def N1(self) -> float:
        return self.contact.N1 if self.contact else 0.0

    @property
    def N2(self) -> float:
        return self.contact.N2 if self.contact else 0.0

    @property
    def normal_force(self) -> float:
        return self.contact.normal if self.contact else 0.0

    @property
    def friction_force(self) -> float:
        return self.contact.friction if self.contact else 0.0

    @property
    def n(self) -> float:  # noqa: D401 - mirrors the theory's name
        return self.normal_force

    @property
    def f(self) -> float:
        return self.friction_force

    @property
    def gamma_sim(self) -> float | None:
        return self.contact.gamma if self.contact else None

    @property
    def contact_moment(self) -> float:
        return self.contact.moment if self.contact else 0.0

    @property
    def required_mu(self) -> float:
        return self.contact.required_mu if self.contact else 0.0


def finger_contact(scene: Scene, f: int, Fw, point, pen: float, nodes, phi, mu_contact: float,
                   m0: float | None = None) -> FingerContact:
    """Theory-frame reading of the workpiece's world force ``Fw`` on finger ``f`` acting at ``point``.

    ``m0``: the forces' moment about the finger's base in its frame (over ``rho g l^2``) when they
    act at several points; the couple about the contact's centreline point is ``m0 - c x F``.
    """
    L, W, n = scene.length, scene.force_scale, scene.n
    F = np.array([scene.mirror[f] * Fw[0], Fw[2]]) / W
    p2 = np.array([scene.mirror[f] * point[0], point[2]]) / L
    if scene.grip in ("I", "II"):
        gamma, theta = 1.0, float(phi[f, -1])
        cpoint = nodes[f, -1]
        normal, friction = F[0], F[1]
    else:
        li = link_of(scene, f, p2, nodes[f], phi[f])
        t = np.array([math.cos(phi[f, li]), math.sin(phi[f, li])])
        u = float(np.clip(np.dot(p2 - nodes[f, li], t), 0.0, 1.0 / n))
        gamma = li / n + u
        cpoint = nodes[f, li] + u * t
        # tangent at gamma: link angles are midpoint samples of theta
        # (second order); interpolate them as the hinge chain does
        smid = np.concatenate([[0.0], (np.arange(n) + 0.5) / n, [1.0]])
        theta = float(np.interp(gamma, smid, np.concatenate([[0.0], phi[f], [phi[f, -1]]])))
        e1 = np.array([math.cos(theta), math.sin(theta)])
        e2 = np.array([-e1[1], e1[0]])
        normal, friction = float(F @ e2), float(F @ e1)
    arm = p2 - cpoint
    moment = float(arm[0] * F[1] - arm[1] * F[0]) if m0 is None else float(m0 - (cpoint[0] * F[1] - cpoint[1] * F[0]))
    return FingerContact(
        N1=float(F[0]),
        N2=float(F[1]),
        normal=float(normal),
        friction=float(friction),
        gamma=float(gamma),
        point=np.array(cpoint),
        theta=theta,
        moment=moment,
        penetration=pen,
        required_mu=abs(friction) / normal if normal > 0 else math.inf,
        required_mu_contact=mu_contact,
    )


def link_of(scene, f, point, nodes, phi) -> int:
    n = scene.n
    best, bi = math.inf, 0
    for i in range(n):
        t = np.array([math.cos(phi[i]), math.sin(phi[i])])
        u = float(np.clip(np.dot(point - nodes[i], t), 0.0, 1.0 / n))
        dist = float(np.linalg.norm(point - nodes[i] - u * t))
        if dist < best:
            best, bi = dist, i
    return bi


def finger_tip(scene, finger: int = 0, qpos=None) -> np.ndarray:
    """Tip ``(X, Y)`` over ``l`` of one finger in its own frame, from its hinge angles."""
    q = np.asarray(scene.data.qpos if qpos is None else qpos)[scene.joint_qpos[finger]]
    return link_positions(np.cumsum(q), 1.0 / scene.n)[-1]


def read_state(scene: Scene, d, *, held: bool, method: str, residual: float, converged: bool, steps: int,
               newton_iterations: int, forward_calls: int, wall_time_s: float, friction=None, **extra) -> SettledState:
    """Read the settled state from ``d`` (contacts computed at ``d.qpos``).

    Each finger's contact force is the sum of MuJoCo's contact forces between
    its contact geoms and the workpiece's, applied at their force-weighted
    mean point.  ``friction(f)`` (the static solve) returns the world friction
    force its sticking constraint carries on finger ``f`` and ``|friction| /
    normal`` in MuJoCo's contact frame; without it (the dynamics) MuJoCo's own
    friction is in the contact forces and the ratio is read from them.
    ``extra`` goes to :class:`SettledState` unchanged.
    """
    m, L, n = scene.model, scene.length, scene.n
    q = np.array(d.qpos[scene.joint_qpos])
    phi = q.cumsum(axis=1)
    nodes = np.zeros((phi.shape[0], n + 1, 2))  # link_positions of each finger (the same sums, no temporaries)
    for f, p in enumerate(phi):
        ((1.0 / n) * np.cos(p)).cumsum(out=nodes[f, 1:, 0])
        ((1.0 / n) * np.sin(p)).cumsum(out=nodes[f, 1:, 1])
    contacts, pen_max = [], 0.0
    if held:  # (a state that holds nothing reads no contacts: MuJoCo's arrays are not looked at)
        wg = set(int(g) for g in scene.workpiece_geoms)
        con = d.contact  # (one view of MuJoCo's contact arrays: each ``d.contact`` builds a new one)
        geom1, geom2 = con.geom1[:d.ncon].tolist(), con.geom2[:d.ncon].tolist()
    for f in range(scene.fingers if held else 0):
        mine = set(int(g) for g in scene.contact_geoms[f])
        cons = [i for i in range(d.ncon) if geom1[i] in mine and geom2[i] in wg]
        if not cons:
            continue
        Fw, point, wsum, pen, fn, ft = np.zeros(3), np.zeros(3), 0.0, 0.0, 0.0, np.zeros(2)
        applied = []  # (world force on the finger, world point) of every force of this contact
        for i in cons:
            fc = np.zeros(6)
            mujoco.mj_contactForce(m, d, i, fc)
            fw = -(np.asarray(con.frame[i]).reshape(3, 3).T @ fc[:3])  # on the finger (geom1)
            Fw += fw
            applied.append((fw, np.asarray(con.pos[i])))
            w = max(math.sqrt(float(fw.dot(fw))), 1e-300)  # (np.linalg.norm's sqrt(x . x) of a 1-D float vector)
            point += w * np.asarray(con.pos[i])
            wsum += w
            pen = max(pen, -float(con.dist[i]) / L)
            fn += fc[0]
            ft += fc[1:3]
        point /= wsum
        if friction is not None:
            stuck, mu = friction(f)
            for fw, at in stuck:
                Fw += fw
                applied.append((fw, at))
        else:
            mu = float(np.linalg.norm(ft)) / fn if fn > 0 else math.inf
        # moment about the origin in the finger's frame (x mirrored, z up), over rho g l^2
        mir = scene.mirror[f]
        m0 = sum((mir * at[0] * fw[2] - at[2] * mir * fw[0]) for fw, at in applied) / (L * scene.force_scale)
        contacts.append(finger_contact(scene, f, Fw, point, pen, nodes, phi, mu, m0))
        pen_max = max(pen_max, pen)
    return SettledState(
        grip=scene.grip, links=n, fingers=scene.fingers, joint_angles=q, link_angles=phi, nodes=nodes,
        tip=nodes[:, -1].copy(), contacts=contacts, workpiece_pose=workpiece_pose(scene), held=held, steps=steps,
        newton_iterations=newton_iterations, forward_calls=forward_calls, wall_time_s=wall_time_s,
        residual=residual, penetration=pen_max, converged=converged, qpos=d.qpos.copy(), method=method, **extra,
    )
