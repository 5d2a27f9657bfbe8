"""The pick environments' fingers as a damped linear system: the damping model's prediction and its measurement.

Every pick environment (:mod:`simgrip.envs.pick`, :mod:`simgrip.envs.pick_multi`) builds its fingers with
:func:`simgrip.sim.fingers.add_fingers`: hinge ``i`` has stiffness ``k_i = (EI/l) * springs.stiffness[i]``,
damping ``c_i = finger_damping_time * k_i`` and armature ``a`` added to the hinge's diagonal inertia; the palm
slides on a joint held by a critically damped position servo.  About a static equilibrium ``q*`` the
equations of motion linearise to

    M dv/dt + C v + K (q - q*) = B du,        C = tau K_s (hinges) + kv (palm servo),

with ``M`` MuJoCo's joint-space inertia (armature included), ``K = K_s + K_g`` the hinge springs plus the
geometric stiffness of gravity (and the palm servo's ``kp``), ``C = -df/dv`` and ``B`` the force of a change
``du`` of the rest angles (the curvature command).  **Damping model.**  ``C = tau K_s`` is
stiffness-proportional Rayleigh damping: were ``K = K_s`` (no gravity, palm held), the undamped modes
``K phi = omega^2 M phi`` would diagonalise ``C`` too and each mode would be damped at exactly

    zeta_i = omega_i tau / 2,

(:func:`modal_damping`); gravity's ``K_g`` and the palm servo make ``C`` non-proportional, and the
first-order estimate ``zeta_i = phi_i' C phi_i / (2 omega_i)`` (``phi_i`` mass-normalised) replaces it, while the exact
continuous-time poles are those of the quadratic eigenproblem ``det(s^2 M + s C + K) = 0``
(:func:`continuous_poles`).  **Integrator.**  MuJoCo's ``implicitfast`` step with joint damping is
semi-implicit Euler with the damping implicit: ``(M + dt C) v' = M v - dt K (q - q*)``, ``q' = q + dt v'``
(:func:`discrete_poles`).  For one mode (``a = omega dt``, ``b = 2 zeta omega dt``) its pole pair is stable
for ``a^2 < 4 + 2 b``: with ``C = tau K`` that is ``a^2 (1 - 2 tau/dt) < 4``, unconditional once ``tau >
dt/2``; without damping the limit is ``omega dt < 2``.  Its poles differ from the continuous ones at first
order in ``dt``: ``|mu|^2 = 1/(1 + b)`` gives a decay rate ``ln(1 + 2 zeta omega dt)/(2 dt)``, low by the
relative ``~ zeta omega dt``.

**Measurement** (:func:`release`, :func:`fit_damped_cosine`, :func:`fit_exponential`): the nonlinear MuJoCo
model is released from ``q*`` displaced along one pole's eigenvector of the discrete map and its fingertip's
height is fitted.  The tests (``tests/test_finger_damping.py``) compare the fit with both predictions and
assert the figures the environments' docstrings state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import scipy.linalg as sl
from scipy.optimize import least_squares

__all__ = [
    "LinearModel",
    "continuous_poles",
    "discrete_poles",
    "fit_damped_cosine",
    "fit_exponential",
    "forced_response",
    "input_force",
    "linearise",
    "modal_damping",
    "output_row",
    "release",
    "settling_time",
]

#: Central-difference step of the linearisation [rad or m]: the truncation error ``h^2 f'''`` and the
#: round-off ``eps f / h`` balance near ``h ~ eps^(1/3) ~ 6e-6``.
FD_STEP = 6e-6


@dataclass(frozen=True)
class LinearModel:
    """The linearisation of a MuJoCo model about a static state (SI units, MuJoCo's dof order).

    Attributes
    ----------
    dofs : ndarray (n,)
        The dofs kept (hinge or slide joints: one qpos each), in this order.
    M, C, K : ndarray (n, n)
        Joint-space inertia [kg m^2, kg m, kg], damping ``-df/dv`` and stiffness ``-df/dq``
        (``f = qfrc_passive + qfrc_actuator - qfrc_bias``).
    qpos : ndarray (nq,)
        The state linearised about.
    dt : float
        The model's time step [s].
    """

    dofs: np.ndarray
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    qpos: np.ndarray
    dt: float


def _dof_qpos(model: mujoco.MjModel, dofs) -> np.ndarray:
    """qpos addresses of ``dofs``; ValueError unless each is a hinge or slide joint's only dof."""
    dofs = np.asarray(dofs, dtype=int)
    if dofs.ndim != 1 or dofs.size == 0 or np.any(dofs < 0) or np.any(dofs >= model.nv):
        raise ValueError(f"dofs must be a non-empty 1-D array of dof indices in [0, {model.nv}), got {dofs!r}")
    jnt = model.dof_jntid[dofs]
    bad = ~np.isin(model.jnt_type[jnt], (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE))
    if np.any(bad):
        raise ValueError(f"dofs must belong to hinge or slide joints, dof {int(dofs[np.argmax(bad)])} does not")
    return np.asarray(model.jnt_qposadr[jnt], dtype=int)


def _force(model, scratch, qpos, qvel, ctrl, dofs) -> np.ndarray:
    """``qfrc_passive + qfrc_actuator - qfrc_bias`` on ``dofs`` at ``(qpos, qvel)`` (no contact forces)."""
    scratch.qpos[:] = qpos
    scratch.qvel[:] = qvel
    scratch.ctrl[:] = ctrl
    mujoco.mj_forward(model, scratch)
    return (scratch.qfrc_passive + scratch.qfrc_actuator - scratch.qfrc_bias)[dofs]


def linearise(model: mujoco.MjModel, data: mujoco.MjData, dofs) -> LinearModel:
    """``M``, ``C``, ``K`` of ``model`` about ``data.qpos`` (at rest, ``data.ctrl``) on ``dofs``.

    ``K`` and ``C`` by central differences of step :data:`FD_STEP` (relative error ``~1e-9``); ``M`` is
    :func:`mujoco.mj_fullM`.  Contact forces are left out: the state must hold the kept dofs without contact
    (the tests release fingers in the air).  ``data`` is not changed.
    """
    qadr = _dof_qpos(model, dofs)
    dofs = np.asarray(dofs, dtype=int)
    scratch = mujoco.MjData(model)
    q0, v0, ctrl = data.qpos.copy(), np.zeros(model.nv), data.ctrl.copy()
    n, h = dofs.size, FD_STEP
    K, C = np.empty((n, n)), np.empty((n, n))
    for j in range(n):
        qa, qb = q0.copy(), q0.copy()
        qa[qadr[j]] += h
        qb[qadr[j]] -= h
        K[:, j] = -(_force(model, scratch, qa, v0, ctrl, dofs) - _force(model, scratch, qb, v0, ctrl, dofs)) / (2 * h)
        va, vb = v0.copy(), v0.copy()
        va[dofs[j]] += h
        vb[dofs[j]] -= h
        C[:, j] = -(_force(model, scratch, q0, va, ctrl, dofs) - _force(model, scratch, q0, vb, ctrl, dofs)) / (2 * h)
    scratch.qpos[:] = q0
    scratch.qvel[:] = 0.0
    mujoco.mj_forward(model, scratch)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, scratch, full)
    return LinearModel(dofs=dofs, M=full[np.ix_(dofs, dofs)], C=C, K=K, qpos=q0, dt=float(model.opt.timestep))


def _order(s: np.ndarray) -> np.ndarray:
    """The order of poles ``s``: slowest decay first, then lowest ``|s|`` (equal decay rates, e.g. undamped
    poles, compared up to round-off)."""
    decay = np.round(-s.real / (1e-9 * np.abs(s).max()))
    return np.lexsort((np.abs(s), decay))


def _sorted(s: np.ndarray) -> np.ndarray:
    """Poles with ``Im s >= 0`` (one of each complex pair), in :func:`_order`."""
    s = s[s.imag >= -1e-9 * np.abs(s)]
    return s[_order(s)]


def continuous_poles(M, C, K) -> np.ndarray:
    """Poles ``s`` of ``M x'' + C x' + K x = 0`` [1/s]: one of each complex pair (``Im s > 0``) and the real ones,
    slowest decay (largest ``Re s``) first, then lowest ``|s|``.  A pair gives ``omega_n = |s|``,
    ``zeta = -Re s / |s|``."""
    n = len(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    return _sorted(np.linalg.eigvals(A))


def discrete_map(M, C, K, dt: float) -> np.ndarray:
    """The ``2n x 2n`` map ``(x, v) -> (x', v')`` of semi-implicit Euler with implicit damping (MuJoCo's
    ``implicitfast`` with joint damping): ``(M + dt C) v' = M v - dt K x``, ``x' = x + dt v'``."""
    n = len(M)
    lhs = M + dt * C
    Av = np.linalg.solve(lhs, np.hstack([-dt * K, M]))  # v' = Av @ (x, v)
    Ax = np.hstack([np.eye(n), np.zeros((n, n))]) + dt * Av
    return np.vstack([Ax, Av])


def discrete_poles(M, C, K, dt: float, *, vectors: bool = False):
    """The poles of :func:`discrete_map` as continuous rates ``s = ln(mu)/dt`` [1/s], sorted as
    :func:`continuous_poles`; with ``vectors``, also the eigenvectors ``(2n, k)`` (columns, state ``(x, v)``)."""
    mu, V = np.linalg.eig(discrete_map(M, C, K, dt))
    s = np.log(mu.astype(complex)) / dt
    keep = s.imag >= -1e-9 * np.abs(s)
    s, V = s[keep], V[:, keep]
    order = _order(s)
    return (s[order], V[:, order]) if vectors else s[order]


def modal_damping(M, K, C) -> tuple[np.ndarray, np.ndarray]:
    """Undamped angular frequencies ``omega_i`` [rad/s] of ``(K, M)`` (ascending) and the modal damping ratios
    ``zeta_i = phi_i' C phi_i / (2 omega_i)`` (``phi_i`` mass-normalised).  For Rayleigh damping ``C = tau K``
    this is exact, ``zeta_i = omega_i tau / 2``; otherwise it is first order in ``C``'s non-proportional part."""
    K = 0.5 * (np.asarray(K) + np.asarray(K).T)  # the finite differences' asymmetry is round-off
    w2, phi = sl.eigh(K, M)
    if np.any(w2 <= 0):
        raise ValueError("K must be positive definite on the dofs kept (a static, stable state)")
    w = np.sqrt(w2)
    zeta = np.einsum("ij,ik,kj->j", phi, np.asarray(C), phi) / (2.0 * w)
    return w, zeta


def input_force(model: mujoco.MjModel, data: mujoco.MjData, dofs, set_input, u0: float) -> np.ndarray:
    """``B = df/du`` on ``dofs`` [N m or N per unit of ``u``] at ``data``'s state, at rest: the force of an input
    ``u`` that ``set_input(u)`` writes into ``model`` (e.g. the rest angles of a curvature command), by central
    differences about ``u0``; ``set_input(u0)`` is called last (the model is left as it was)."""
    _dof_qpos(model, dofs)
    dofs = np.asarray(dofs, dtype=int)
    scratch = mujoco.MjData(model)
    q0, v0, ctrl = data.qpos.copy(), np.zeros(model.nv), data.ctrl.copy()
    h = FD_STEP * max(1.0, abs(u0))
    try:
        set_input(u0 + h)
        fa = _force(model, scratch, q0, v0, ctrl, dofs)
        set_input(u0 - h)
        fb = _force(model, scratch, q0, v0, ctrl, dofs)
    finally:
        set_input(u0)
    return (fa - fb) / (2 * h)


def output_row(model: mujoco.MjModel, data: mujoco.MjData, dofs, probe) -> np.ndarray:
    """``d probe / d q`` on ``dofs`` at ``data.qpos`` (central differences; ``probe(data)`` a float read after
    :func:`mujoco.mj_kinematics`); ``data`` is not changed."""
    qadr = _dof_qpos(model, dofs)
    scratch = mujoco.MjData(model)
    row = np.empty(qadr.size)
    for j, a in enumerate(qadr):
        vals = []
        for sgn in (1.0, -1.0):
            scratch.qpos[:] = data.qpos
            scratch.qpos[a] += sgn * FD_STEP
            mujoco.mj_kinematics(model, scratch)
            vals.append(float(probe(scratch)))
        row[j] = (vals[0] - vals[1]) / (2 * FD_STEP)
    return row


def forced_response(lin: LinearModel, B, u, hold: int) -> np.ndarray:
    """States ``x`` (displacements from ``lin.qpos`` on ``lin.dofs``) of :func:`discrete_map`'s scheme forced
    by ``B u_k``, started at rest: ``u[k]`` is held for ``hold`` steps (a control step of ``hold`` physics
    steps, as the environments hold their rest angles); returns ``(len(u) * hold, n)``, one row per step."""
    hold = int(hold)
    if hold < 1:
        raise ValueError(f"hold must be a positive number of steps, got {hold!r}")
    M, C, K, dt = lin.M, lin.C, lin.K, lin.dt
    lu = sl.lu_factor(M + dt * C)
    B = np.asarray(B, dtype=float)
    x, v = np.zeros(len(M)), np.zeros(len(M))
    out = []
    for uk in np.asarray(u, dtype=float):
        for _ in range(hold):
            v = sl.lu_solve(lu, M @ v + dt * (B * uk - K @ x))
            x = x + dt * v
            out.append(x)
    return np.asarray(out)


def release(model: mujoco.MjModel, data: mujoco.MjData, dofs, dx, dv, duration: float, probe) -> tuple:
    """Step ``model`` for ``duration`` [s] from ``data``'s state with ``dx`` added to the ``dofs``' qpos and
    ``dv`` to their qvel; return ``(t, y)``: times [s] and ``probe(data)`` after each step (``data`` is left at
    the end state).  MuJoCo warnings and non-finite states raise :class:`simgrip.sim.checks.PhysicsError`."""
    from simgrip.sim.checks import check_invalid_state

    qadr = _dof_qpos(model, dofs)
    if not duration > 0 or not math.isfinite(duration):
        raise ValueError(f"duration must be a positive number of seconds, got {duration!r}")
    data.qpos[qadr] += np.asarray(dx, dtype=float)
    data.qvel[np.asarray(dofs, dtype=int)] += np.asarray(dv, dtype=float)
    steps = int(round(duration / model.opt.timestep))
    out = []
    with check_invalid_state(data, "release"):
        mujoco.mj_forward(model, data)
        for _ in range(steps):
            mujoco.mj_step(model, data)
            out.append(probe(data))
    return model.opt.timestep * np.arange(1, steps + 1), np.asarray(out, dtype=float)


@dataclass(frozen=True)
class DampedFit:
    """A fit ``y = A exp(-sigma t) cos(omega_d t + phase)`` (or ``A exp(-sigma t)`` with ``omega_d = 0``).

    ``sigma`` [1/s], ``omega_d`` [rad/s]; ``omega_n = hypot(sigma, omega_d)``, ``zeta = sigma / omega_n``;
    ``residual``: rms misfit over the rms of ``y``.
    """

    sigma: float
    omega_d: float
    amplitude: float
    phase: float
    residual: float

    @property
    def omega_n(self) -> float:
        return math.hypot(self.sigma, self.omega_d)

    @property
    def zeta(self) -> float:
        return self.sigma / self.omega_n

    @property
    def pole(self) -> complex:
        return complex(-self.sigma, self.omega_d)


def _check_series(t, y):
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size < 8 or not np.all(np.isfinite(y)) or not np.all(np.diff(t) > 0):
        raise ValueError("t and y must be finite 1-D series of the same length (>= 8 samples, t increasing)")
    return t, y


def fit_damped_cosine(t, y, guess: complex, *, offset: bool = False) -> DampedFit:
    """Least-squares fit of ``A exp(-sigma t) cos(omega_d t + phase)`` (plus a constant with ``offset``: an
    equilibrium not known beforehand) to ``(t, y)`` started at the pole ``guess = -sigma + i omega_d``; the
    amplitude, phase and offset enter linearly and are eliminated.  ``residual`` is over the rms of ``y``
    about the fitted offset."""
    t, y = _check_series(t, y)
    t0 = t[0]

    def basis(p):
        env = np.exp(-p[0] * (t - t0))
        cols = [env * np.cos(p[1] * (t - t0)), env * np.sin(p[1] * (t - t0))]
        return np.stack(cols + [np.ones_like(t)] if offset else cols, axis=1)

    def resid(p):
        B = basis(p)
        return B @ np.linalg.lstsq(B, y, rcond=None)[0] - y

    sol = least_squares(resid, [-guess.real, guess.imag], x_scale=abs(guess), xtol=1e-14, ftol=1e-14, gtol=1e-14)
    c = np.linalg.lstsq(basis(sol.x), y, rcond=None)[0]
    if offset:
        y = y - c[2]
    amp, phase = math.hypot(c[0], c[1]), math.atan2(-c[1], c[0])
    # referred back to t = 0
    amp *= math.exp(sol.x[0] * t0)
    phase -= sol.x[1] * t0
    rms = float(np.sqrt(np.mean(y**2)))
    return DampedFit(float(sol.x[0]), float(sol.x[1]), amp, phase, float(np.sqrt(np.mean(sol.fun**2))) / rms)


def fit_exponential(t, y) -> DampedFit:
    """Fit ``A exp(-sigma t)`` to ``(t, y)`` (``y`` of one sign) by least squares on ``ln |y|``."""
    t, y = _check_series(t, y)
    if not (np.all(y > 0) or np.all(y < 0)):
        raise ValueError("y must keep one sign for an exponential fit")
    slope, icpt = np.polyfit(t, np.log(np.abs(y)), 1)
    fit = np.sign(y[0]) * np.exp(icpt + slope * t)
    rms = float(np.sqrt(np.mean(y**2)))
    return DampedFit(float(-slope), 0.0, float(np.sign(y[0]) * np.exp(icpt)), 0.0,
                     float(np.sqrt(np.mean((fit - y) ** 2))) / rms)


def settling_time(t, y, final: float, band: float = 0.02) -> float:
    """The last time [s] at which ``|y - final|`` exceeds ``band`` times its largest value (0 if never)."""
    t, y = _check_series(t, y)
    if not 0 < band < 1:
        raise ValueError(f"band must be in (0, 1), got {band!r}")
    dev = np.abs(y - final)
    out = np.nonzero(dev > band * dev.max())[0]
    return float(t[out[-1]]) if out.size else 0.0
