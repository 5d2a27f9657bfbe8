"""The start of the K-finger settle (:mod:`simgrip.gripper.settle`): every finger at its chain's equilibrium.

Each finger of a K-finger gripper is a planar hinge chain, rigid out of its
plane; it touches the workpiece with its tip at ``X = scene.reach[k]``
(:mod:`simgrip.gripper.placement`; ``b/2`` when centred).  The settle
starts every finger at the hinge chain's grip equilibrium
(:func:`simgrip.reference.solve_chain`) with its tip there, carrying a
vertical *share* ``s_k`` of the weight (``N2 = -s_k``), so that the
dynamics has only MuJoCo's contact softness left to settle.

* **Symmetric scenes** (centred, unturned, every finger alike): every
  share is ``M`` and every finger the planar problem, exactly.
* **Otherwise** the shares and the out-of-plane forces ``N3_k`` (which the
  hinges carry, the fingers being rigid out of plane) are chosen so that the
  workpiece starts balanced: its six equations (force and moment, with each
  finger's ``N1`` and tip height from its chain) are linear in
  ``(s, N3)``; the least-norm change from ``(M, 0)`` that solves them is
  taken (:func:`balance_shares`); Newton on the shares makes the chains
  solved at those shares give them back (each chain carrying the tip couple
  of its friction on the tip sphere's surface, ``r_tip n1 s``).  A share may
  have either sign (``|s| <= M_MAX``): a negative one is a finger whose
  friction pulls the workpiece *down* (the others then carry more than the
  weight), and its chain is solved with that upward load on its tip
  (:func:`simgrip.reference.solve_chain`'s signed ``load``).  Where Newton
  does not converge in :data:`BALANCE_ITERATIONS`, the best iterate is
  started from and the dynamics settles the rest (reported, never hidden).
  Whether the friction can carry a start's forces is not the start's
  business: :func:`start_forces` reports each finger's required ``mu``,
  and a start that needs more than ``mu_s`` drops; whether the balanced
  start is a stable equilibrium is :mod:`simgrip.gripper.stability`'s.
* **Statically indeterminate internal forces** (``K >= 4``): the six
  equations do not fix the ``2K`` unknowns ``(s, N3)``; ``2K - 6`` internal
  modes (a squeeze of the vertical shares, a twist of the ``N3``) are free.
  Per-finger ``N2`` and ``N3`` are then *not* determined by statics; the
  start takes the least-norm choice and the dynamics keeps that split (the
  sticking contacts hold what they start with; MuJoCo's contact solver,
  through its path, moves it only by creep).  Only ``N1``, the tips and the
  workpiece's pose are determinate: compare those, not the per-finger
  ``N2``/``N3``, across resolutions or against another solver.  Without the
  balanced start, a start whose shares do not balance the workpiece's
  moments loads those internal modes while the workpiece settles, and
  MuJoCo's sticking friction (a stiff viscous coupling, not a spring) lets
  them relax only by creep: the settle crawls for tens of thousands of steps
  with a moment residual well above its tolerance.
* ``K = 2``: both fingers lie in one plane, so nothing but their normal
  forces holds the workpiece along it: it starts shifted along that plane
  until the two ``N1`` agree (one more Newton unknown), where the tips' friction
  would otherwise have to carry the difference (it cannot: the tips can
  follow the workpiece in the plane).
* **Depth**: in the first step MuJoCo's soft contact sinks from the start's
  :data:`START_INSIDE` to the depth it rests at under the normal force
  (~2e-5 to 5e-5 l at the dynamics' step); where the contact normal is not in
  the finger's plane (a turned or off-centre workpiece) that sinking moves the
  tip along the surface too, the stiff sticking friction saturates for a step
  and can throw the workpiece off.  An unsymmetric start is therefore solved
  with every tip at that rest depth (:func:`rest_depth`), given the step.
* A sphere is held centred with equal profiles only (the builder refuses
  the rest): its start is the symmetric one at the contact angle.

None (nothing to hold) when a free finger does not reach its ``X`` or a
finger's loaded chain would pull on the workpiece (``N1 <= 0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.params import M_MAX, Grip
from simgrip.reference import DiscreteError, solve_chain
from simgrip.settle.state import SettleError
from simgrip.gripper.rest_depth import contact_rest_depth
from simgrip.gripper.scene import GripperScene

__all__ = ["StartForces", "balance_shares", "contact_reach", "finger_chain", "is_symmetric", "rest_depth",
           "start_forces", "start_qpos", "unreached_fingers", "warn_unreached"]

#: Newton iterations balancing the start's shares (each ``K + 1`` solves of every chain).
BALANCE_ITERATIONS = 8
#: The start's shares are taken as balanced when they move less than this (over rho g l).
BALANCE_TOL = 1e-10
#: The tip starts this far (over l) inside the surface, so that MuJoCo sees the contact.
START_INSIDE = 1e-6


def finger_chain(scene: GripperScene, grip: str, X: float | None = None, guess=None, finger: int = 0,
                 M: float | None = None, contact_moment: float = 0.0):
    """Finger ``finger``'s hinge chain (its own profile) in ``grip``, tip at ``X``, load ``M``; None if unsolved.

    ``M``: the workpiece's vertical load on the tip (``N2 = -M``, either sign; default ``params.M``).
    ``contact_moment``: the tip couple (about ``E3``, over ``rho g l^2``) of a force on the tip sphere's surface.
    """
    p = scene.params
    if X is not None:
        p = p.replace(b=2.0 * X)
    gravity = -float(scene.model.opt.gravity[2]) / scene.physical.g
    profile = scene.profiles[finger] if scene.profiles else scene.profile
    try:
        return solve_chain(grip, p, profile, scene.n, guess=guess, gravity=gravity, contact_moment=contact_moment,
                           load=None if M is None or grip == "free" else float(M))
    except (DiscreteError, ValueError):
        return None


def contact_reach(scene: GripperScene) -> np.ndarray:
    """Every finger's tip ``X`` (over ``l``, its own frame) on the workpiece: ``b/2`` or the placement's reach,
    times ``cos(beta)`` on a sphere (``beta`` the contact angle)."""
    K = scene.fingers
    X = np.full(K, 0.5 * scene.params.b) if scene.reach is None else np.array(scene.reach, dtype=float)
    return X * math.cos(float(np.atleast_1d(scene.contact_angle)[0]))


def unreached_fingers(scene: GripperScene, X=None, fingers: int | None = None) -> list[tuple[int, float, float]]:
    """``[(k, X_free, X_k)]``: the fingers whose free shape (the hinge chain's, no workpiece) has its tip
    outside their contact ``X_k`` (:func:`contact_reach` by default): closing from it they never press on
    the workpiece.  ``fingers``: check only the first ones (equal fingers: one)."""
    X = contact_reach(scene) if X is None else np.asarray(X, dtype=float)
    out = []
    for k in range(scene.fingers if fingers is None else fingers):
        free = finger_chain(scene, Grip.FREE, finger=k)
        if free is not None:
            tip_x = float(np.sum(np.cos(free.link_angles))) / scene.n
            if tip_x > X[k]:
                out.append((k, tip_x, float(X[k])))
    return out


def warn_unreached(scene: GripperScene, state) -> None:
    """A dropped state whose fingers do not reach the workpiece says so (``state.warnings``).

    The gripper closes from the fingers' free shape: a finger whose free tip lies outside the face never presses
    on it, so nothing holds.  The elastica BVP prescribes the tip on the face (``X(l) = b/2``) and can still
    find a held equilibrium there (the finger pulled onto the face, e.g. hanging from a heavy workpiece or
    sagging, for a soft one), which this gripper cannot close into: the verdicts may differ, and why is stated.
    """
    if scene.grip not in ("I", "II") or state.held or not state.grip_matched:
        return
    far = unreached_fingers(scene, fingers=1 if is_symmetric(scene) else None)
    if far:
        k, tip_x, X = far[0]
        state.warnings.append(
            f"not held: finger {k}'s free shape has its tip at X = {tip_x:.4g} l, outside the workpiece's face at "
            f"X = {X:.4g} l, so closing from it the finger never presses on the workpiece; the BVP, which puts "
            f"the tip on the face, may find a held equilibrium there that this gripper cannot close into")


def is_symmetric(scene: GripperScene) -> bool:
    """Centred, unturned workpiece and every finger alike: every finger is the planar problem."""
    same = all(np.array_equal(s.rest, scene.springs.rest) for s in scene.finger_springs)
    return bool(not np.any(scene.offset) and scene.workpiece_yaw == 0.0 and same)


def balance_shares(azimuths, X, Y, N1, centre, M: float, arms=None) -> tuple[np.ndarray, np.ndarray, float]:
    """``(s, N3, residual)``: the least-norm change from ``(M, 0)`` that balances the workpiece.

    Finger ``k`` (azimuth ``azimuths[k]`` [rad], world frame) acts on the
    workpiece at ``X_k E1_k + Y_k z`` with ``-(N1_k E1_k + N3_k E3_k - s_k z)``;
    plus ``arms[k]`` (world, over ``l``: the contact point on the tip sphere's
    surface off its centre, default none); the workpiece (centre ``centre = (x, y)``, weight ``K M``) is balanced
    when those forces carry its weight and their moment about its centre
    vanishes.  ``residual``: the largest equation left unbalanced (zero
    unless the equations have no solution, e.g. ``K = 2`` with unequal ``N1``).
    """
    az = np.asarray(azimuths, dtype=float)
    K = len(az)
    c = np.array([centre[0], centre[1], float(np.mean(Y))])
    A = np.zeros((6, 2 * K))
    rhs = np.zeros(6)
    rhs[2] = K * M
    for k, a in enumerate(az):
        e1 = np.array([math.cos(a), math.sin(a), 0.0])
        e3 = np.array([-math.sin(a), math.cos(a), 0.0])
        r = X[k] * e1 + np.array([0.0, 0.0, Y[k]]) - c
        if arms is not None:
            r = r + np.asarray(arms[k], dtype=float)
        f0 = -N1[k] * e1
        cols = {k: np.array([0.0, 0.0, 1.0]), K + k: -e3}
        for j, col in cols.items():
            A[:3, j] = col
            A[3:, j] = np.cross(r, col)
        rhs[:3] -= f0
        rhs[3:] -= np.cross(r, f0)
    u0 = np.concatenate([np.full(K, float(M)), np.zeros(K)])
    du = np.linalg.lstsq(A, rhs - A @ u0, rcond=None)[0]
    u = u0 + du
    return u[:K], u[K:], float(np.max(np.abs(A @ u - rhs)))


def _normals(scene: GripperScene) -> np.ndarray:
    """The workpiece's horizontal normal at each finger, ``(along E1, along E3)`` (K, 2)."""
    if scene.normals is None:
        return np.tile([1.0, 0.0], (scene.fingers, 1))
    return np.asarray(scene.normals, dtype=float)


def _arms(scene: GripperScene) -> np.ndarray:
    """World offsets (over l) of the contact points from the tip centres: ``-r_tip n`` (K, 3)."""
    n = _normals(scene)
    a = np.asarray(scene.azimuths, dtype=float)
    e1 = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    e3 = np.stack([-np.sin(a), np.cos(a), np.zeros_like(a)], axis=1)
    return -scene.r_tip * (n[:, :1] * e1 + n[:, 1:] * e3)


def _chains(scene: GripperScene, X, shares, guesses, couple: bool = True, inside=None, fingers: int | None = None):
    """Every finger's loaded chain at its ``X`` and share; raises SettleError if one has no stable equilibrium.

    ``couple``: the share's vertical force acts on the tip sphere's surface, ``r_tip n1`` inside the
    tip centre: a tip couple ``r_tip n1 s`` (the friction's; the normal force passes through the
    centre).  The symmetric start leaves it to the dynamics (as it always has).  ``fingers``: solve
    only the first so many (default all).
    """
    out = []
    n1 = _normals(scene)[:, 0] if couple else np.zeros(scene.fingers)
    for k in range(scene.fingers if fingers is None else fingers):
        depth = START_INSIDE if inside is None else float(inside[k])
        ch = finger_chain(scene, scene.grip, X=float(X[k]) - depth, finger=k, M=float(shares[k]),
                          guess=guesses[k], contact_moment=scene.r_tip * float(n1[k]) * float(shares[k]))
        if ch is None or not (ch.success and ch.min_eigenvalue > 0.0):
            raise SettleError(f"no start for grip {scene.grip}: finger {k}'s hinge chain has no stable equilibrium "
                              f"with its tip on the workpiece (X = {float(X[k]):g}, load {float(shares[k]):g}, "
                              f"b = {scene.params.b:g})")
        out.append(ch)
    return out


def _balanced(scene: GripperScene, X0, centre0, inside=None):
    """``(chains, X, centre)`` of the balanced start (see the module docstring): Newton on the shares.

    Unknowns: the shares (and, for ``K = 2``, the shift along finger 0's ``E1``); equations: the
    shares that :func:`balance_shares` returns from the chains at those shares are the shares (and
    the two ``N1`` agree).  Finite-difference Jacobian, steps halved while a chain fails or a share
    leaves ``[-M_MAX, M_MAX]``; the best iterate is kept (an unbalanced start is settled by the dynamics).
    """
    K, M = scene.fingers, float(scene.params.M)
    e1 = np.array([math.cos(scene.azimuths[0]), math.sin(scene.azimuths[0])])
    sign = np.array([1.0, -1.0]) if K == 2 else None
    arms = _arms(scene)

    def evaluate(z, guesses):
        shift = float(z[K]) if K == 2 else 0.0
        X = X0 + shift * sign if K == 2 else X0
        centre = centre0 + shift * e1
        chains = _chains(scene, X, z[:K], guesses, inside=inside)
        s, _n3, _r = balance_shares(scene.azimuths, X, [c.tip[1] for c in chains], [c.N1 for c in chains],
                                    centre, M, arms=arms)
        R = s - z[:K]
        if K == 2:
            R = np.append(R, chains[0].N1 - chains[1].N1)
        return R, chains, X, centre

    z = np.append(np.full(K, M), [0.0] if K == 2 else [])
    R, chains, X, centre = evaluate(z, [None] * K)
    best = (float(np.max(np.abs(R))), chains, X, centre)
    for _ in range(BALANCE_ITERATIONS):
        if best[0] < BALANCE_TOL * max(1.0, M):
            break
        guesses = [c.link_angles for c in chains]
        J = np.zeros((len(z), len(z)))
        for j in range(len(z)):
            eps = 1e-6 * max(1.0, abs(z[j])) if j < K else 1e-7
            dz = z.copy()
            dz[j] += eps
            try:
                J[:, j] = (evaluate(dz, guesses)[0] - R) / eps
            except SettleError:
                return best[1:]
        step = -np.linalg.lstsq(J, R, rcond=None)[0]
        for _half in range(6):
            zn = z + step
            if np.all(np.abs(zn[:K]) <= M_MAX) and (K != 2 or abs(zn[K]) < 0.5 * float(np.min(X0))):
                try:
                    Rn, cn, Xn, centre_n = evaluate(zn, guesses)
                except SettleError:
                    Rn = None
                if Rn is not None and float(np.max(np.abs(Rn))) < float(np.max(np.abs(R))):
                    break
            step *= 0.5
        else:
            break
        z, R, chains = zn, Rn, cn
        if float(np.max(np.abs(R))) < best[0]:
            best = (float(np.max(np.abs(R))), cn, Xn, centre_n)
    return best[1:]


def rest_depth(N1, timestep: float, scene: GripperScene) -> np.ndarray:
    """How deep (over l) MuJoCo's soft contact rests under normal forces ``N1`` (over rho g l), per finger.

    :func:`simgrip.gripper.rest_depth.contact_rest_depth` (``N tc^2 A_nn``: the contact's mobility through
    the dynamics' step metric) at the scene's current state, at least :data:`START_INSIDE`.
    """
    return np.maximum(START_INSIDE, contact_rest_depth(scene, N1, timestep))


@dataclass(frozen=True)
class StartForces:
    """The forces of the start (:func:`start_qpos`), per finger, in the finger's frame (over ``rho g l``).

    ``N1`` (along ``E1``), ``N2 = -share`` (up) and ``N3`` (out of plane) are the force on the rod,
    as :class:`~simgrip.gripper.settle.FingerRecord` reads the settled one; ``normal`` its component
    along the workpiece's normal into the tip, ``tangential`` the magnitude of the rest, and
    ``required_mu = tangential / normal`` (``inf`` where ``normal <= 0``): the friction coefficient the
    start needs at each finger.  ``residual``: the largest of the workpiece's six equations the start
    leaves unbalanced (0 to round-off when it is balanced); ``balanced``: ``residual`` below
    :data:`BALANCE_TOL` times ``max(1, M)``.
    """

    N1: np.ndarray
    N2: np.ndarray
    N3: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    required_mu: np.ndarray
    residual: float
    balanced: bool

    @property
    def max_required_mu(self) -> float:
        """The largest friction coefficient any finger's contact needs (``max(required_mu)``)."""
        return float(np.max(self.required_mu))


def _start(scene: GripperScene, timestep: float | None):
    """``(chains, X, centre, beta)`` of the start, or None when the workpiece cannot be held."""
    p = scene.params
    K = scene.fingers
    beta = scene.contact_angle  # sphere: the tip at X = (b/2) cos(beta) on the sphere; 0 for vertical faces
    X = (np.full(K, 0.5 * p.b) if scene.reach is None else np.array(scene.reach)) * math.cos(beta)
    wq = scene.workpiece_qpos
    centre = np.array(scene.model.qpos0[wq[:2]]) / scene.length  # the builder's (offset, turned by yaw)
    equal_shares = is_symmetric(scene) or scene.workpiece == "sphere"  # (a sphere's fingers are equal)
    alike = equal_shares and bool(np.all(X == X[0]))  # every finger the same problem: solve one, share it
    if unreached_fingers(scene, X, fingers=1 if alike else K):
        return None
    if equal_shares:  # (alike: one finger's chain serves all, the same arrays, read only)
        chains = _chains(scene, X, np.full(K, float(p.M)), [None] * K, couple=False, fingers=1 if alike else None)
        chains = chains * K if alike else chains
    else:
        X0, centre0 = X, centre
        chains, X, centre = _balanced(scene, X0, centre0)
        if timestep is not None:
            chains, X, centre = _balanced(scene, X0, centre0, inside=rest_depth([c.N1 for c in chains], timestep, scene))
    if not all(ch.N1 > 0.0 for ch in chains):
        return None  # a loaded finger would have to pull on the workpiece: it cannot hold it
    return chains, X, centre, beta


def start_forces(scene: GripperScene, timestep: float | None = None) -> StartForces | None:
    """The forces of the start :func:`start_qpos` makes (same arguments), or None when it holds nothing.

    ``N1`` and ``N2`` are each chain's; ``N3`` the out-of-plane forces :func:`balance_shares` pairs with
    the chains' shares (zero for a symmetric start).  The normal is the workpiece's at each finger
    (horizontal, ``scene.normals``; a sphere's raised by ``scene.contact_angle``).
    """
    got = _start(scene, timestep)
    if got is None:
        return None
    chains, X, centre, beta = got
    K, M = scene.fingers, float(scene.params.M)
    N1 = np.array([c.N1 for c in chains])
    share = -np.array([c.N2 for c in chains])
    arms = None if (is_symmetric(scene) or scene.workpiece == "sphere") else _arms(scene)
    s, N3, _r = balance_shares(scene.azimuths, X, [c.tip[1] for c in chains], N1, centre, M, arms=arms)
    if arms is None:
        N3 = np.zeros(K)
    # the workpiece's equations at the start's own shares (s from balance_shares is the least-norm answer)
    az = np.asarray(scene.azimuths, dtype=float)
    Y = np.array([c.tip[1] for c in chains])
    c3 = np.array([centre[0], centre[1], float(np.mean(Y))])
    force, moment = np.array([0.0, 0.0, -K * M]), np.zeros(3)
    arm3 = np.zeros((K, 3)) if arms is None else np.asarray(arms, dtype=float)
    for k, a in enumerate(az):
        e1 = np.array([math.cos(a), math.sin(a), 0.0])
        e3 = np.array([-math.sin(a), math.cos(a), 0.0])
        on_rod = N1[k] * e1 + N3[k] * e3 - share[k] * np.array([0.0, 0.0, 1.0])
        force -= on_rod
        moment += np.cross(X[k] * e1 + np.array([0.0, 0.0, Y[k]]) - c3 + arm3[k], -on_rod)
    residual = float(max(np.max(np.abs(force)), np.max(np.abs(moment))))
    nh = _normals(scene)
    normal_3 = np.stack([math.cos(beta) * nh[:, 0], math.cos(beta) * nh[:, 1], np.full(K, math.sin(beta))], axis=1)
    F = np.stack([N1, N3, -share], axis=1)  # (E1, E3, up) on the rod
    normal = np.einsum("ij,ij->i", F, normal_3)
    tangential = np.sqrt(np.maximum(np.einsum("ij,ij->i", F, F) - normal**2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(normal > 0.0, tangential / np.where(normal > 0.0, normal, 1.0), math.inf)
    return StartForces(N1=N1, N2=-share, N3=N3, normal=normal, tangential=tangential, required_mu=mu,
                       residual=residual, balanced=bool(residual < BALANCE_TOL * max(1.0, M)))


def start_qpos(scene: GripperScene, timestep: float | None = None) -> np.ndarray | None:
    """qpos of the start (see the module docstring), or None when the workpiece cannot be held.

    ``timestep`` [s]: the dynamics' step; given, an unsymmetric start puts every tip at the depth
    MuJoCo's contact rests at (:func:`rest_depth`) instead of :data:`START_INSIDE`.
    """
    got = _start(scene, timestep)
    if got is None:
        return None
    chains, X, centre, beta = got
    p, L, wq = scene.params, scene.length, scene.workpiece_qpos
    q = np.array(scene.data.qpos)
    for k, ch in enumerate(chains):
        q[scene.joint_qpos[k]] = ch.joint_angles
    heights = [float(ch.tip[1]) for ch in chains]
    q[wq[:2]] = centre * L
    q[wq[2]] = (float(np.mean(heights)) - 0.5 * p.b * math.sin(beta)) * L
    turn = scene.yaw + scene.workpiece_yaw
    q[wq[3:]] = [math.cos(0.5 * turn), 0.0, 0.0, math.sin(0.5 * turn)]
    return q

