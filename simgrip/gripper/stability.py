"""Is the K-finger settle's balanced start a *stable* equilibrium?  Two independent answers.

The balanced start (:mod:`simgrip.gripper.start`) is an equilibrium of
the workpiece and the chains; it may still be unstable (a pinched workpiece
whose contact forces, turning with it, tip it further than the fingers'
stiffness pulls it back).  The dynamics then leaves it exponentially, and a
drop from such a start is not a friction failure.

:func:`start_stiffness` (the statics, no MuJoCo)
    The potential energy of the gripper, with the contacts sticking, as a
    function of the workpiece's rigid displacement ``(u, w)`` (translation,
    rotation about its centre of mass, which the start puts level with the
    mean tip height).  Contact ``k`` is the material point ``r_k`` of the
    workpiece the tip ``k`` touches; it moves by ``u + w x r_k + 1/2 w x (w x
    r_k)``.  Finger ``k`` is rigid out of its plane, so the first-order
    motion along its ``E3`` must vanish (``K`` constraints); in its plane its
    tip follows the point, and the chain's equilibrium energy ``W_k(X, Y)``
    (springs and weight, the tip held at ``(X, Y)``) has gradient ``(N1,
    N2)`` and Hessian ``S_k``, the tip stiffness, from central differences of
    :func:`simgrip.reference.solve_chain` (``(N1, Y)`` as functions of ``(X,
    load)``, inverted).  The workpiece's weight is linear in ``u`` and
    independent of ``w``.  The second variation is therefore ``J_k^T P^T S_k
    P J_k`` summed over fingers plus the geometric term of the pre-load,
    ``F_k . 1/2 w x (w x r_k)`` with ``F_k = N1 E1 + N3 E3 + N2 z`` the force
    on the rod (``w^T (sym(F r^T) - (F . r) I) w``), restricted to the
    constraints' null space.  A negative eigenvalue there is a direction in
    which the energy falls: unstable.  (The eigenvalues mix units, l and rad;
    their signs, the Hessian's inertia, do not depend on that.)  Neglected:
    the tip sphere's radius (contact at the tip centre, no rolling, no tip
    couple); ``K = 2`` has a zero mode (the turn about the line through the two
    contacts, which point contacts do not resist).
:func:`start_growth` (MuJoCo's own dynamics)
    The settle's one-step map ``x_{t+1} = A x_t`` (``x = (qpos, qvel)``, the
    dynamics' options, :func:`mujoco.mjd_transitionFD`) linearised about the
    start at rest: its largest eigenvalue modulus is 1 (the neutral drift of
    sticking friction, a viscous coupling) for a stable start and above
    ``1 + UNSTABLE_GROWTH`` when a mode grows; the dynamics leaves the start at
    that rate per step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.gripper.start import START_INSIDE, _start, balance_shares, finger_chain, is_symmetric, start_qpos
from simgrip.gripper.scene import GripperScene

__all__ = ["FD_EPS", "STIFFNESS_STEP", "UNSTABLE_GROWTH", "StartStiffness", "start_growth", "start_stiffness"]

#: A start whose linearised one-step map grows by more than this per step is unstable: e^10 within the
#: settle's 20 000-step budget.  MuJoCo's neutral modes sit at 1 within ~5e-5.
UNSTABLE_GROWTH = 5e-4
#: Finite-difference step of :func:`start_growth`'s linearisation (qpos in m and rad, qvel): well inside
#: the start's contact depth (>= 1e-6 l), so that no contact appears or vanishes between the samples.
FD_EPS = 1e-9
#: Central-difference step (over l, and over rho g l for the load) of the tip stiffness: its error is
#: O(step^2) ~ 1e-10 relative.
STIFFNESS_STEP = 1e-5


@dataclass(frozen=True)
class StartStiffness:
    """The second variation of the start's energy on the workpiece's admissible rigid motions.

    ``eigenvalues``: ascending, of the reduced Hessian (``dims`` of them: ``6 - rank`` of the
    fingers' out-of-plane constraints); ``stable``: none below ``-tolerance``, where ``tolerance`` is
    1e-6 of the largest magnitude (the finite differences' error is ~1e-10 of it).
    """

    eigenvalues: np.ndarray
    dims: int
    tolerance: float

    @property
    def min_eigenvalue(self) -> float:
        """The least eigenvalue of the stiffness (``eigenvalues`` are ascending)."""
        return float(self.eigenvalues[0])

    @property
    def stable(self) -> bool:
        """No eigenvalue below ``-tolerance``."""
        return bool(self.min_eigenvalue >= -self.tolerance)


def _tip_stiffness(scene: GripperScene, k: int, X: float, load: float, chain) -> np.ndarray:
    """``d(N1, N2)/d(X, Y)`` of finger ``k``'s chain with its tip at ``X``, carrying ``load``."""
    h = STIFFNESS_STEP

    def at(x, m):
        c = finger_chain(scene, scene.grip, X=x, finger=k, M=m, guess=chain.link_angles)
        if c is None:
            raise ValueError(f"scene: finger {k}'s chain has no equilibrium next to its start")
        return np.array([c.N1, c.tip[1]])

    dx = (at(X + h, load) - at(X - h, load)) / (2 * h)  # d(N1, Y)/dX at a fixed load
    dl = (at(X, load + h) - at(X, load - h)) / (2 * h)  # d(N1, Y)/dload at a fixed X
    dload_dx, dload_dy = -dx[1] / dl[1], 1.0 / dl[1]  # the load that keeps (X, Y): N2 = -load
    return np.array([[dx[0] + dl[0] * dload_dx, dl[0] * dload_dy], [-dload_dx, -dload_dy]])


def _cross_matrix(r) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def start_stiffness(scene: GripperScene) -> StartStiffness | None:
    """The start's second variation (see the module docstring); None when the start holds nothing.

    Box and cylinder only (a sphere's contact normal is not horizontal: ValueError naming ``scene``).
    """
    if not isinstance(scene, GripperScene):
        raise ValueError(f"scene must be a GripperScene, got {type(scene).__name__}")
    if scene.workpiece == "sphere":
        raise ValueError("scene: start_stiffness takes a box or a cylinder (vertical contact faces)")
    got = _start(scene, None)
    if got is None:
        return None
    chains, X, centre, _beta = got
    K, M = scene.fingers, float(scene.params.M)
    Y = np.array([c.tip[1] for c in chains])
    N1 = np.array([c.N1 for c in chains])
    load = -np.array([c.N2 for c in chains])
    N3 = np.zeros(K) if is_symmetric(scene) else balance_shares(scene.azimuths, X, Y, N1, centre, M)[1]
    c3 = np.array([centre[0], centre[1], float(np.mean(Y))])
    z = np.array([0.0, 0.0, 1.0])
    H = np.zeros((6, 6))
    C = np.zeros((K, 6))
    for k, a in enumerate(scene.azimuths):
        e1 = np.array([math.cos(a), math.sin(a), 0.0])
        e3 = np.array([-math.sin(a), math.cos(a), 0.0])
        r = X[k] * e1 + Y[k] * z - c3
        J = np.hstack([np.eye(3), -_cross_matrix(r)])  # first-order motion of the contact point
        PJ = np.vstack([e1, z]) @ J
        S = _tip_stiffness(scene, k, float(X[k]) - START_INSIDE, float(load[k]), chains[k])
        H += PJ.T @ S @ PJ
        F = N1[k] * e1 + N3[k] * e3 - load[k] * z
        H[3:, 3:] += 0.5 * (np.outer(F, r) + np.outer(r, F)) - float(F @ r) * np.eye(3)
        C[k] = e3 @ J
    H = 0.5 * (H + H.T)
    _u, sv, vt = np.linalg.svd(C)
    rank = int(np.sum(sv > 1e-12 * max(1.0, float(sv[0]))))
    Z = vt[rank:].T
    ev = np.linalg.eigvalsh(Z.T @ H @ Z)
    return StartStiffness(eigenvalues=ev, dims=int(Z.shape[1]), tolerance=1e-6 * float(np.max(np.abs(ev))))


def start_growth(scene: GripperScene, step_factor: float = 1.0) -> float | None:
    """Largest ``|eigenvalue|`` of the settle's one-step map linearised about its start; None if it holds nothing.

    The start is :func:`~simgrip.gripper.start.start_qpos` at the dynamics' step ``step_factor h``
    (:mod:`simgrip.gripper.dynamics`' options), at rest; MuJoCo's solver is run to round-off for the
    centred differences.  ``> 1 + UNSTABLE_GROWTH``: unstable (module docstring).  The model's options
    and state are restored.
    """
    import mujoco

    from simgrip.gripper.dynamics import GripperDynamics
    from simgrip.settle.statics import restore_options, save_options

    m, d = scene.model, scene.data
    saved, q_saved = save_options(m), np.array(d.qpos)
    tol, its = float(m.opt.tolerance), int(m.opt.iterations)
    try:
        q = start_qpos(scene)
        if q is None:
            return None
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        dyn = GripperDynamics(scene, float(step_factor))
        if not is_symmetric(scene) and scene.workpiece != "sphere":
            d.qpos[:] = start_qpos(scene, timestep=dyn.h)
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        n = 2 * m.nv + m.na
        A = np.zeros((n, n))
        m.opt.tolerance, m.opt.iterations = 0.0, max(its, 200)  # the solver to round-off: no noise to difference
        mujoco.mjd_transitionFD(m, d, FD_EPS, 1, A, None, None, None)
        return float(np.max(np.abs(np.linalg.eigvals(A))))
    finally:
        m.opt.tolerance, m.opt.iterations = tol, its
        restore_options(m, saved)
        d.qpos[:] = q_saved
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
