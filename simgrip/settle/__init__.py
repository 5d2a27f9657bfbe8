"""Drive a scene to static equilibrium, fast, and read the settled state.

Design
------
The settled state depends only on the potential forces (hinge springs,
gravity) and on the contact forces, not on inertia or damping, so
:func:`settle` integrates no dynamics at all: it solves the statics of the
MuJoCo model with Newton's method on MuJoCo's own generalised forces.

* **Forces.**  ``mj_inverse`` at ``qvel = qacc = 0`` gives the generalised
  force that holds a configuration, ``qfrc_inverse = qfrc_bias - qfrc_passive
  - qfrc_constraint``; the imbalance ``r(q) = qfrc_applied - qfrc_inverse``
  holds the springs (``qpos_spring``), gravity and MuJoCo's contact forces.
  MuJoCo's soft contact is analytically invertible: at rest a contact with
  penetration ``p`` pushes with ``K_c p`` (``K_c`` from ``solref``/``solimp``
  and the exact ``A`` diagonal, chosen ~:data:`CONTACT_STIFFNESS` ``rho g`` so
  that ``p ~ 1e-6 l``).
* **Contacts as compliant constraints.**  A stiff penalty makes plain Newton
  crawl (the linearisation of a tip sliding along a face is exact only over
  ``sqrt(p l)``).  Each touching pair instead carries an unknown normal force
  ``N`` with the constraint ``K_c dist(q) + N = 0`` -- MuJoCo's contact law,
  with ``dist`` from ``mj_geomDistance`` and its gradient ``n'(J_2 - J_1)`` at
  the witness points.  ``K_c`` is read back from MuJoCo's contact force at the
  solution and the solve repeated until they agree, so the reported residual
  is MuJoCo's own force balance (contacts on).  Unilateral: a pair with
  ``N < 0`` leaves the set, a penetrating one joins it.
* **Static friction.**  MuJoCo's friction is velocity based (its soft friction
  creeps at rest: 1e-5 of the weight with impratio 1; the no-slip post-solve
  had no effect on these pair contacts in MuJoCo 4.0.0 and ``mjd_inverseFD``
  rejects it), so a *sticking* contact is a constraint: the contact points of
  finger and workpiece do not slide tangentially (re-anchored at the current
  contact point every iteration, so round geoms roll and the friction acts at
  the contact point).  Its multiplier is the friction force; MuJoCo's
  friction cone (the pair's coefficient and ``N``) decides: ``|lambda| <= mu
  N`` holds, else the contact slips -- Grips I/II drop the workpiece
  (``held = False``), Grip III slides with friction ``mu N`` to where it holds.
* **Newton-KKT.**  ``dr/dq`` by ``mjd_inverseFD`` (one C call), the
  constraints' curvature by differences of ``G' multipliers``, a least-squares
  KKT step (sticking leaves the sliding direction singular, the two-finger
  workpiece is neutral in ``x``), a backtracking line search on the residual
  (constraint rows in length units) and a tunnelling guard for pairs not yet
  touching (a step closes at most half their gap; :data:`PEN_MAX`).  3-5
  iterations per solve for a free rod at any ``n``.

Residual and tolerance: ``max |r_i|`` over the dofs, hinge moments over
``rho g l^2`` and workpiece forces over ``rho g l``; contact-law rows are
accepted at their round-off floor (``K_c`` times the ~1e-14 l resolution of a
geom distance, :data:`FLOOR_ULPS` ulps of ``K_c l``: ~1e-7 at ``K_c ~ 1e6 rho
g``, independent of ``n``).  The reported residual is MuJoCo's own (contacts
on, plus the friction forces); ``converged`` means ``residual <= tolerance``
(:attr:`SettledState.tolerance`), where the tolerance of a held grip is ``tol``
raised to that floor (capped at :data:`RESIDUAL_FLOOR_MAX`) and is ``tol``
otherwise; a state above it raises :class:`SettleError` unless
``allow_unconverged``.  A grip's residual is ~1e-11 to 2e-8, a free rod's
~1e-15.  :func:`naive_settle` is the plain dynamic settle it is measured
against.

Budgets: ``max_steps`` bounds the Newton iterations of the whole settle
(closing, release, finger alone; default :data:`NEWTON_BUDGET`), one solve
gets at most :data:`SOLVE_ITERS`, a closing continuation stage
:data:`CLOSE_STAGE_ITERS` (then it is halved, at most 4 times), the line search
50 halvings, the contact-set and friction loops 8 and 6 rounds; a spent budget
raises :class:`SettleError` naming it.  The dynamic settle's ``max_steps``
bounds its physics steps in total, restarts included.  Each Newton iteration
costs ``O(n^2)`` forward calls (~0.15 s at ``n = 256``), so the Newton budget
is not a wall-time bound at large ``n``.  The linear algebra runs with one
BLAS thread (:mod:`simgrip.threads`).

Grips
-----
* I/II: the finger curls with contact off until its tip reaches ``X = b/2``
  (secant on the curvature factor); the workpiece is placed there and held
  (frozen, weight cancelled, frictionless) while the curvature goes to its
  final value by continuation (halving failed increments).  The stages up to
  the penultimate one run on the hinge chain (``solve_chain`` with ``M = 0``,
  ~1 ms each, warm-started stage to stage) and MuJoCo's Newton takes over
  there for the last stage (:func:`_close_predicted`: the same end state,
  ~half the Newton iterations); a fold of the path (softening stability,
  kink) or a failing MuJoCo stage hands the whole closing to the MuJoCo ramp,
  so the answer stays the ramp's.  Then it is released:
  stick constraint at the tip's contact, workpiece free, full weight.  If the
  frictionless closing path folds (large ``|kappa|``), the start is the hinge
  chain's grip equilibrium instead.
* III: the scene starts from the shape it was built with (by default the hinge
  chain's equilibrium with the contact at ``params.gamma``) with the corner on
  the rod; it is released the same way; the contact settles at the
  simulation's own ``gamma_sim``.
* A warm start (:func:`settle_sweep`) releases from the previous equilibrium.
* III condition (23): the corner pairs only with links near the initial
  contact, so a tip that curls back into the workpiece is not stopped by
  MuJoCo; the settled state flags it (``tip_clear = False`` and a message in
  ``warnings``) instead of returning it quietly.  The standard ``kappa = -6``,
  ``gamma = 0.8`` cradle violates it (tip ~0.01 l above the bottom face).

``method="dynamics"``
---------------------
A settle that really simulates, with MuJoCo's own contact and friction (no
simgrip friction enforcement), everything chosen from the model:

* **Integrator** ``mjINT_DISCRETE``: the constraint solve and the implicit
  velocity update share the metric ``M + h D + h^2 K``, so hinge stiffness is
  implicit and contacts with a time constant far below the step
  (``DYN_TIMECONST h``, refsafe off) stay stable.  ``implicitfast`` was
  measured and rejected: its stiffness is explicit (a free rod diverges for
  ``h > c``) and, with refsafe off, contacts with ``timeconst < 2h`` blow up
  (with refsafe on they are soft: mm-scale penetration at useful steps).
* **Damping and step**: hinge damping ``D = h K`` (stiffness-proportional, so
  the over-damped flow is preconditioned by the spring matrix and the number
  of steps does not grow with ``n``: 35 steps to 1e-10 for a free rod at any
  ``n``; with ``M << h D + h^2 K`` each step is a relaxed Newton step for the
  springs, gravity explicit); ``h = 1 / omega_min`` of the hinge chain with
  its physical inertia (no armature needed: inertia is negligible in the
  metric).  The workpiece has no stiffness: damping ``3 m / h``; Grip III
  (thin capsules) raises it, and the finger's with it, so that a free-falling
  workpiece moves at most 0.3 contact radii per step (else it tunnels).
* **Contacts**: elliptic cone, ``impratio = 1e4`` (MuJoCo's sticking friction
  creeps at a speed ~ 1/impratio: 1.2e-4, ..., 1.2e-8 sqrt(g l) for 1 ... 1e4,
  breaking down at 1e5; it leaves ~1e-5 of the weight unbalanced, hence the
  default ``DYN_TOL = 1e-5``), no-slip off (no effect under
  ``mjINT_DISCRETE``: measured), impedance 0.9999.  Penetration is set by the
  step (timeconst-insensitive): 5.5e-5 l (I), 2.9e-5 l (II), 1e-5 l (III) at
  the standard case; a state at or above 1e-4 l restarts with half the step.
* **Closing** (I/II): contact on, frictionless (``pair_dim = 1``), workpiece
  held, rest angles ramped at <= 0.05 rad of total rotation per step (a tip
  jumping >~0.05 l into the face in one step is not pushed back); the
  holding force then fades out over 20 steps (friction on).  III starts loaded
  (the workpiece lowered onto the rod so the first step sees the contact).
  Warm starts ramp the rest angles from the previous state's.
* **Stop**: the static residual at rest, ``qfrc_smooth + qfrc_constraint`` at
  ``qvel = 0`` with the settle's contact settings (MuJoCo's friction
  included; :func:`static_residual` omits friction and uses the scene's own
  contact settings), below ``tol`` and velocities below ``DYN_VTOL``.  Drop:
  the tip slips 0.02 l along the face (I/II), or the workpiece falls 0.02 l
  out of contact; then the finger settles alone.  NaN, MuJoCo warnings raise
  :class:`SettleError`, so does a spent step budget (``max_steps``).
* **Measured** (standard case, n = 32, Grip I, loaded 2-core machine):
  Newton 42 iterations, 2907 forward calls, ~0.045-0.06 s (82 iterations,
  ~0.075 s before the closing predictor :func:`_close_predicted`), residual 4e-10,
  penetration 7e-7 l; dynamics 203 steps, ~0.01-0.02 s, residual 1e-5,
  penetration 5.5e-5 l, angles within 1.7e-4 (~3 p) of the Newton settle and
  N1 within 3e-5.  Both are discretisation-limited against the BVP (8e-4 in N1
  at n = 32).  Hold/drop of I/II is sharp to +-0.5 % of mg/N.  Grip III: a
  cone violated at release makes the over-damped dynamics lose the workpiece
  (the rod springs away in the step), where the Newton path slides it to a
  nearby gamma that holds.  Newton stays the default (more accurate,
  friction exact); dynamics is ~3-5x faster.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import link_positions
from simgrip.sim.scene import BOX_HEIGHT, Scene, set_curvature
from simgrip.threads import blas_threads

__all__ = [
    "DYN_TOL",
    "SettleError",
    "SettledState",
    "FingerContact",
    "settle",
    "settle_sweep",
    "static_residual",
    "naive_settle",
    "DEFAULT_TOL",
]

#: Default static residual tolerance (over rho g l^2 and rho g l).
DEFAULT_TOL = 1e-10
#: Contact impedance during settle (MuJoCo's maximum is 0.9999).
CONTACT_IMPEDANCE = 0.9999
#: Target contact stiffness over rho g (force per length, dimensionless).
CONTACT_STIFFNESS = 1e6
#: A Newton step may not push a pair that was not touching deeper than this (over l).
PEN_MAX = 1e-4
#: Curvature ramp stages while closing on the held workpiece.
CLOSE_STAGES = 8
_FD_EPS = 1e-9
#: Contact-law residuals ``K_c dist + N`` below this many ulps of ``K_c l`` are round-off
#: (geom distances carry ~1e-14 l of round-off: capsule-capsule closest points).  With 1024
#: the reported residual of a grip reached 2.5e-6 (stress run); 64 brings it to ~1e-9.
FLOOR_ULPS = 64.0
#: ``K_c`` read back from MuJoCo is updated when it moved by more than this (relative): a heavily
#: loaded contact (``N`` ~ 1e3 ``rho g l``, large ``D``) left 4e-7 of residual at 1e-9.
KC_RTOL = 1e-13
#: The contact floor raises the effective tolerance at most to this (a bogus ``K_c`` read back
#: from a deep contact must not make every residual "converged").
RESIDUAL_FLOOR_MAX = 1e-6
#: Default total Newton iteration budget of one settle (``max_steps``): closing, release and
#: the finger-alone settle together (the 500-case stress run needed at most ~1200).
NEWTON_BUDGET = 2000
#: Newton iterations allowed to one solve (quadratic convergence: a solve needing more is failing).
SOLVE_ITERS = 200
#: Newton iterations allowed to one continuation stage while closing (a failing stage is halved).
CLOSE_STAGE_ITERS = 40
#: The closing predictor (:func:`_close_predicted`) hands over to the staged ramp when a chain
#: stage's stability margin (smallest projected Hessian eigenvalue) falls below this fraction of
#: the first stage's, or when a stage's change of the link angles differs from the previous
#: stage's by more than :data:`FOLD_KINK` times the latter (a fold or branch jump of the path).
FOLD_MARGIN = 0.5
FOLD_KINK = 0.5


class SettleError(RuntimeError):
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
    #: ``"newton"`` or ``"dynamics"``.
    method: str = "newton"
    #: Largest velocity at the end (dynamics; rad or l per sqrt(l/g)); 0 for Newton.
    velocity: float = 0.0
    #: Time step of the dynamic settle [s]; 0 for Newton.
    timestep: float = 0.0
    #: Grip III condition (23): no link beyond the contact reaches the workpiece's bottom face.
    tip_clear: bool = True
    #: Conditions the state violates that the solve itself does not enforce (e.g. condition (23)).
    warnings: list = field(default_factory=list)
    #: Hinge rest angles (``springs.rest``) the state was settled with (a dynamic warm start ramps from them).
    rest: np.ndarray | None = field(default=None, repr=False)
    #: Effective residual tolerance: ``converged`` means ``residual <= tolerance``.  ``max(tol, floor)``
    #: with the contact-law round-off floor (Newton, :meth:`_Newton.noise_floor`, capped at
    #: :data:`RESIDUAL_FLOOR_MAX`); the requested ``tol`` for dynamics and contact-free states.
    tolerance: float = math.nan

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


# ---------------------------------------------------------------------------
# statics


def _scales(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Per-dof force scale (rho g l^2 hinges, rho g l slides) and length scale (1, l)."""
    m = scene.model
    force = np.full(m.nv, scene.moment_scale)
    length = np.ones(m.nv)
    for j in range(m.njnt):
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
            force[m.jnt_dofadr[j]] = scene.force_scale
            length[m.jnt_dofadr[j]] = scene.length
    return force, length


@dataclass
class _Stick:
    """Sticking friction: a finger point and a workpiece point that may not slide along ``t``."""

    finger: int  # finger index
    body_f: int
    local_f: np.ndarray
    body_w: int
    local_w: np.ndarray
    t_body: int  # body whose frame carries the tangent
    t_local: np.ndarray
    geoms: tuple  # (finger geom, workpiece geom) of the contact pair
    offset: float = 0.0  # over l: keeps g continuous when the anchors move

    def reanchor(self, d, point) -> None:
        """Move both anchors to ``point`` (the current contact), keeping ``g`` unchanged.

        Round geoms roll: friction acts at the current contact point, not at a
        material point; re-anchoring every Newton iteration integrates the
        no-slip condition of the contact point along the path.
        """
        t = self.tangent(d)
        pf, pw = self.points(d)
        g_old = float(t @ (pf - pw))
        self.local_f = d.xmat[self.body_f].reshape(3, 3).T @ (point - d.xpos[self.body_f])
        self.local_w = d.xmat[self.body_w].reshape(3, 3).T @ (point - d.xpos[self.body_w])
        self.offset += g_old  # new anchors coincide: t . (pf - pw) = 0

    def tangent(self, d) -> np.ndarray:
        return d.xmat[self.t_body].reshape(3, 3) @ self.t_local

    def points(self, d) -> tuple[np.ndarray, np.ndarray]:
        pf = d.xpos[self.body_f] + d.xmat[self.body_f].reshape(3, 3) @ self.local_f
        pw = d.xpos[self.body_w] + d.xmat[self.body_w].reshape(3, 3) @ self.local_w
        return pf, pw


class _Statics:
    """Static residual of the model plus sticking constraints, on a scratch MjData."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.m = scene.model
        self.d = mujoco.MjData(self.m)
        self.fscale, self.lscale = _scales(scene)
        self.calls = 0

    def forces(self, q) -> np.ndarray:
        """``r(q) = qfrc_applied - qfrc_inverse`` at rest, dimensional."""
        m, d = self.m, self.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        d.qfrc_applied[:] = self.scene.data.qfrc_applied
        mujoco.mj_inverse(m, d)
        self.calls += 1
        return d.qfrc_applied - d.qfrc_inverse

    def stick_rows(self, sticks) -> tuple[np.ndarray, np.ndarray]:
        """Constraint values ``g`` (over l) and gradients ``G`` (n_stick x nv) at the scratch state."""
        m, d = self.m, self.d
        g = np.zeros(len(sticks))
        G = np.zeros((len(sticks), m.nv))
        jf = np.zeros((3, m.nv))
        jw = np.zeros((3, m.nv))
        for i, s in enumerate(sticks):
            t = s.tangent(d)
            pf, pw = s.points(d)
            g[i] = (float(t @ (pf - pw)) + s.offset) / self.scene.length
            mujoco.mj_jac(m, d, jf, None, pf, s.body_f)
            mujoco.mj_jac(m, d, jw, None, pw, s.body_w)
            G[i] = t @ (jf - jw)
        return g, G

    def jacobian(self, q) -> np.ndarray:
        """``dr/dq`` (nv x nv, rows = force components) by ``mjd_inverseFD``."""
        m, d = self.m, self.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        d.qfrc_applied[:] = self.scene.data.qfrc_applied
        DfDq = np.zeros((m.nv, m.nv))
        mujoco.mjd_inverseFD(m, d, _FD_EPS, False, DfDq, None, None, None, None, None, None)
        self.calls += 2 * m.nv + 1
        return -DfDq.T


def static_residual(scene: Scene, qpos=None) -> np.ndarray:
    """Dimensionless static generalised-force imbalance at ``qpos`` (no friction; default: the scene's)."""
    st = _Statics(scene)
    q = scene.data.qpos if qpos is None else qpos
    return st.forces(q) / st.fscale


# ---------------------------------------------------------------------------
# solver options (set for the solve, restored afterwards)


@dataclass
class _Saved:
    solref: np.ndarray
    solimp: np.ndarray
    noslip: int
    disableflags: int
    ccd: tuple
    dynamics: tuple = ()


def _save(m) -> _Saved:
    dyn = (int(m.opt.integrator), float(m.opt.timestep), int(m.opt.cone), float(m.opt.impratio),
           m.dof_damping.copy(), m.pair_dim.copy(), m.pair_friction.copy())
    return _Saved(m.pair_solref.copy(), m.pair_solimp.copy(), int(m.opt.noslip_iterations), int(m.opt.disableflags),
                  (float(m.opt.ccd_tolerance), int(m.opt.ccd_iterations)), dyn)


def _restore(m, s: _Saved) -> None:
    m.pair_solref[:] = s.solref
    m.pair_solimp[:] = s.solimp
    m.opt.noslip_iterations = s.noslip
    m.opt.disableflags = s.disableflags
    m.opt.ccd_tolerance, m.opt.ccd_iterations = s.ccd
    if s.dynamics:
        m.opt.integrator, m.opt.timestep, m.opt.cone, m.opt.impratio = s.dynamics[:4]
        m.dof_damping[:], m.pair_dim[:], m.pair_friction[:] = s.dynamics[4:]


def _configure(scene: Scene) -> None:
    """Contact settings of the static solve (see the module docstring)."""
    m = scene.model
    m.opt.noslip_iterations = 0  # a dynamics post-process; mjd_inverseFD rejects it
    m.opt.ccd_tolerance = 1e-14  # distances exact to round-off (Newton differentiates them)
    m.opt.ccd_iterations = 200
    if m.npair == 0:
        return
    # at rest K_c = 1 / (d (1 - d) timeconst^2 A), A ~ 3 / (link mass): pick timeconst for K_c
    imp = CONTACT_IMPEDANCE
    m_eff = scene.physical.rho * scene.length / scene.n / 3.0
    k_c = CONTACT_STIFFNESS * scene.physical.rho * scene.physical.g
    m.pair_solref[:] = [math.sqrt(m_eff / (imp * (1.0 - imp) * k_c)), 1.0]
    m.pair_solimp[:, 0] = imp
    m.pair_solimp[:, 1] = imp
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)


def _check_warnings(d) -> None:
    warn = [mujoco.mjtWarning(i).name for i in range(len(d.warning)) if d.warning[i].number > 0]
    if warn:
        raise SettleError(f"settle diverged (MuJoCo warnings {', '.join(warn)})")


def _pair_contacts(d, g1: int, g2: int) -> list[int]:
    return [i for i in range(d.ncon) if {int(d.contact.geom1[i]), int(d.contact.geom2[i])} == {g1, g2}]


def _normal_force(m, d, i) -> float:
    f = np.zeros(6)
    mujoco.mj_contactForce(m, d, i, f)
    return float(f[0])


def _contact_world_force(m, d, i) -> np.ndarray:
    """World force that geom1 (finger) receives from geom2 (workpiece) in contact ``i``."""
    f = np.zeros(6)
    mujoco.mj_contactForce(m, d, i, f)
    frame = np.asarray(d.contact.frame[i]).reshape(3, 3)
    return -(frame.T @ f[:3])


# ---------------------------------------------------------------------------
# Newton-KKT


class _Newton:
    """Newton-KKT on the static equilibrium with contact and friction constraints.

    Unknowns: the free dofs' positions, a normal force ``N`` per touching
    contact pair and a friction force ``lambda`` per sticking contact.
    Equations (dimensional)::

        r_free(q) + G_n(q)' N + G_s(q)' lambda (+ sliding friction) = 0
        dist(q) + N / K_c = 0              (MuJoCo's contact law at rest)
        t . (p_f(q) - p_w(q)) = 0          (sticking)

    ``r_free`` is MuJoCo's generalised force with contacts off; ``K_c`` is read
    from MuJoCo's own contact force (``efc_force / penetration``) so that, at
    convergence, the full MuJoCo residual (contacts on) vanishes: that residual
    is what :func:`settle` checks and reports.  Writing the stiff contact as
    a compliant constraint keeps Newton well conditioned (a pure penalty would
    force tiny steps along the face).
    """

    def __init__(self, scene: Scene):
        self.scene = scene
        self.st = _Statics(scene)
        self.iterations = 0
        m = scene.model
        self.pairs = [(int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in range(m.npair)]
        self.kc = np.full(m.npair, CONTACT_STIFFNESS * scene.physical.rho * scene.physical.g)
        self.normal_active: list[int] = []
        self.N = np.zeros(0)
        self.sticks: list[_Stick] = []
        self.lam = np.zeros(0)
        self.sliding: dict = {}
        #: Total Newton iterations allowed (all solves together); None: unlimited.
        self.budget: int | None = None

    @property
    def static(self):
        return self.st

    def spent(self) -> bool:
        """The settle's Newton iteration budget is used up."""
        return self.budget is not None and self.iterations >= self.budget

    def _contacts_on(self) -> bool:
        m = self.scene.model
        return bool(self.pairs) and not (self._flags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT))

    # -- geometry -------------------------------------------------------------
    def _dists(self, q) -> np.ndarray:
        """Signed distance of every pair at ``q`` (dimensional); kinematics on the scratch data."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        L = self.scene.length
        return np.array([mujoco.mj_geomDistance(m, sd, g1, g2, L, None) for g1, g2 in self.pairs])

    def _dist_grad(self, q, pairs) -> np.ndarray:
        """Gradient of the listed pairs' signed distances over all dofs: ``n' (J_2 - J_1)``.

        ``n`` is the unit normal from geom1 to geom2 and ``J_i`` the Jacobians
        of the witness points (``mj_geomDistance``'s ``fromto``); central
        differences when the witness points coincide.
        """
        m, sd = self.scene.model, self.st.d
        L = self.scene.length
        G = np.zeros((len(pairs), m.nv))
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        mujoco.mj_comPos(m, sd)
        j1 = np.zeros((3, m.nv))
        j2 = np.zeros((3, m.nv))
        ft = np.zeros(6)
        for row, p in enumerate(pairs):
            g1, g2 = self.pairs[p]
            dist = mujoco.mj_geomDistance(m, sd, g1, g2, L, ft)
            seg = ft[3:] - ft[:3]
            if np.linalg.norm(seg) < 1e-12 * L:
                G[row] = self._dist_grad_fd(q, p)
                sd.qpos[:] = q
                mujoco.mj_kinematics(m, sd)
                mujoco.mj_comPos(m, sd)
                continue
            n = seg / np.linalg.norm(seg) * math.copysign(1.0, dist)
            mujoco.mj_jac(m, sd, j1, None, ft[:3], int(m.geom_bodyid[g1]))
            mujoco.mj_jac(m, sd, j2, None, ft[3:], int(m.geom_bodyid[g2]))
            G[row] = n @ (j2 - j1)
        return G

    def _dist_grad_fd(self, q, p) -> np.ndarray:
        m = self.scene.model
        out = np.zeros(m.nv)
        for c in range(m.nv):
            h = 1e-6 * self.st.lscale[c]
            v = np.zeros(m.nv)
            v[c] = h
            qp, qm = q.copy(), q.copy()
            mujoco.mj_integratePos(m, qp, v, 1.0)
            mujoco.mj_integratePos(m, qm, -v, 1.0)
            out[c] = (self._dists(qp)[p] - self._dists(qm)[p]) / (2 * h)
        return out

    # -- residual --------------------------------------------------------------
    def _residual(self, q, N, lam, idx):
        """Scaled KKT residual and the pieces needed for the Jacobian."""
        m = self.scene.model
        L = self.scene.length
        # MuJoCo's forces with contacts off (springs, gravity, applied)
        m.opt.disableflags = self._flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        r = self.st.forces(q)
        m.opt.disableflags = self._flags
        _check_warnings(self.st.d)
        act = self.normal_active
        dist = self._dists(q)
        total = r.copy()
        Gn = Gs = None
        gs = np.zeros(0)
        if act:
            Gn = self._dist_grad_cached(q, act)
            total += Gn.T @ N
        stick_act = [i for i in range(len(self.sticks)) if i not in self.sliding]
        if self.sticks:
            self.st.d.qpos[:] = q
            mujoco.mj_kinematics(m, self.st.d)
            gs_all, Gs_all = self.st.stick_rows(self.sticks)
            gs, Gs = gs_all[stick_act], Gs_all[stick_act]
            total += Gs.T @ lam
            for i, sign in self.sliding.items():
                p = self._pair_of(self.sticks[i])
                if p not in act:  # the pair has separated: N = 0, no sliding friction
                    continue
                k = act.index(p)
                mu = float(m.pair_friction[p][0])
                total += Gs_all[i] * sign * mu * N[k]
        F = total[idx] / self.st.fscale[idx]
        W = self.scene.force_scale
        gn = (self.kc[act] * dist[act] + N) / W if act else np.zeros(0)
        self._merit_weights = np.concatenate([np.ones(F.size), W / (self.kc[act] * L) if act else np.zeros(0),
                                              np.ones(gs.size)])
        return np.concatenate([F, gn, gs]), dist, Gn, Gs

    def _dist_grad_cached(self, q, act):
        key = (q.tobytes(), tuple(act))
        if getattr(self, "_gcache_key", None) != key:
            self._gcache_key = key
            self._gcache = self._dist_grad(q, act)
        return self._gcache

    def _pair_of(self, s: _Stick) -> int:
        for i, (g1, g2) in enumerate(self.pairs):
            if {g1, g2} == set(s.geoms):
                return i
        raise KeyError(s.geoms)

    # -- Newton -----------------------------------------------------------------
    def solve(self, tol: float, max_iter: int, *, frozen=()) -> tuple[bool, str]:
        """Newton-KKT until the scaled residual is below ``tol`` with a consistent contact set."""
        sc = self.scene
        m, d = sc.model, sc.data
        self._flags = int(m.opt.disableflags)
        contacts = self._contacts_on()
        free = np.ones(m.nv, bool)
        free[list(frozen)] = False
        idx = np.flatnonzero(free)
        q = d.qpos.copy()
        if not contacts:
            self.normal_active, self.N = [], np.zeros(0)
        limit = self.iterations + max_iter
        if self.budget is not None:
            limit = min(limit, self.budget)
        if contacts:  # initial contact set: touching pairs and the sticks' pairs
            dist = self._dists(q)
            need = {p for p in range(len(self.pairs)) if dist[p] <= 0.0}
            need |= {self._pair_of(s) for s in self.sticks}
            for p in sorted(need - set(self.normal_active)):
                self.normal_active.append(p)
                self.N = np.append(self.N, 0.0)
        for _outer in range(8):
            conv, why, q = self._newton(q, idx, tol, limit, contacts)
            if not conv:
                self._commit(q)
                return False, why
            if not contacts:
                self._commit(q)
                return True, "ok"
            # contact set and MuJoCo consistency
            dist = self._dists(q)
            changed = False
            keep = [k for k, p in enumerate(self.normal_active) if self.N[k] >= 0.0]
            if len(keep) != len(self.normal_active):
                self.normal_active = [self.normal_active[k] for k in keep]
                self.N = self.N[keep]
                changed = True
            for p in range(len(self.pairs)):
                if p not in self.normal_active and dist[p] < 0.0:
                    self.normal_active.append(p)
                    self.N = np.append(self.N, 0.0)
                    changed = True
            if not changed and self._update_kc(q):
                changed = True
            if not changed:
                self._commit(q)
                return True, "ok"
        self._commit(q)
        return False, "contact set did not settle"

    def noise_floor(self) -> float:
        """Round-off floor of the contact force residual: ``K_c`` times the resolution of a distance."""
        if not self.normal_active:
            return 0.0
        kc = float(np.max(self.kc[self.normal_active]))
        return FLOOR_ULPS * np.finfo(float).eps * kc * self.scene.length / self.scene.force_scale

    def _update_kc(self, q) -> bool:
        """Read MuJoCo's contact stiffness at ``q``; True if it moved enough to matter."""
        m, sd = self.scene.model, self.st.d
        self.st.forces(q)
        moved = False
        for k, p in enumerate(self.normal_active):
            cons = _pair_contacts(sd, *self.pairs[p])
            if not cons:
                continue
            pen = -min(float(sd.contact.dist[c]) for c in cons)
            fn = sum(_normal_force(m, sd, c) for c in cons)
            if pen > 0 and fn > 0:
                kc = fn / pen
                if abs(kc - self.kc[p]) > KC_RTOL * kc:
                    moved = moved or abs(kc - self.kc[p]) * pen > 0.1 * self.noise_floor() * self.scene.force_scale
                    self.kc[p] = kc
        return moved

    def _newton(self, q, idx, tol, max_iter, contacts):
        sc = self.scene
        m = sc.model
        L = sc.length
        N = self.N.copy()
        stick_act = [i for i in range(len(self.sticks)) if i not in self.sliding]
        if self.lam.size != len(self.sticks):
            self.lam = np.zeros(len(self.sticks))
        lam = self.lam[stick_act].copy()
        R, dist, Gn, Gs = self._residual(q, N, lam, idx)
        while True:
            res = float(np.max(np.abs(R))) if R.size else 0.0
            if not math.isfinite(res):
                raise SettleError("settle diverged (non-finite residual)")
            nf = idx.size
            res_f = float(np.max(np.abs(R[:nf]))) if nf else 0.0
            res_c = float(np.max(np.abs(R[nf:]))) if R.size > nf else 0.0
            if res_f < tol and res_c < max(tol, self.noise_floor()):
                break
            if self.iterations >= max_iter:
                self.N, self.lam[stick_act] = N, lam
                if self.budget is not None and self.iterations >= self.budget:
                    return False, f"Newton iteration budget max_steps={self.budget} spent", q
                return False, "max_iter", q
            self.iterations += 1
            if self.sticks:
                self._reanchor(q)
                R, dist, Gn, Gs = self._residual(q, N, lam, idx)
            m.opt.disableflags = self._flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
            H = self.st.jacobian(q)
            m.opt.disableflags = self._flags
            act = self.normal_active
            if act:  # curvature of the constraints: d(G' mult)/dq by FD
                H = H + self._constraint_curvature(q, N, lam, stick_act)
            fs, ls = self.st.fscale[idx], self.st.lscale[idx]
            nf, nn, ns = idx.size, len(act), len(stick_act)
            K = np.zeros((nf + nn + ns, nf + nn + ns))
            K[:nf, :nf] = H[np.ix_(idx, idx)] * ls[None, :] / fs[:, None]
            if nn:
                Gi = Gn[:, idx]
                K[:nf, nf:nf + nn] = Gi.T / fs[:, None]
                W = sc.force_scale
                K[nf:nf + nn, :nf] = Gi * ls[None, :] * self.kc[act][:, None] / W
                K[nf:nf + nn, nf:nf + nn] = np.eye(nn) / W
            if ns:
                Gi = Gs[:, idx]
                K[:nf, nf + nn:] = Gi.T / fs[:, None]
                K[nf + nn:, :nf] = Gi * ls[None, :] / L
            if self.sliding and nn:  # sliding friction sign * mu * N depends on N
                _, Gs_all = self.st.stick_rows(self.sticks)
                for i, sign in self.sliding.items():
                    p = self._pair_of(self.sticks[i])
                    if p not in act:  # separated pair: no friction (see _residual)
                        continue
                    k = act.index(p)
                    mu = float(m.pair_friction[p][0])
                    K[:nf, nf + k] += Gs_all[i][idx] * sign * mu / fs
            sol, *_ = np.linalg.lstsq(K, -R, rcond=1e-14)
            dq = sol[:nf] * ls
            dN = sol[nf:nf + nn]
            dl = sol[nf + nn:]
            wts = self._merit_weights.copy()
            merit = float(np.linalg.norm(R * wts))
            d0 = dist
            step = 1.0
            accepted = False
            for _ in range(50):
                v = np.zeros(m.nv)
                v[idx] = step * dq
                qn = q.copy()
                mujoco.mj_integratePos(m, qn, v, 1.0)
                Nn, ln = N + step * dN, lam + step * dl
                Rn, distn, Gnn, Gsn = self._residual(qn, Nn, ln, idx)
                ok = bool(np.all(np.isfinite(Rn)))
                if ok and contacts:
                    # inactive pairs: no tunnelling (move at most half their gap)
                    inact = [p for p in range(len(self.pairs)) if p not in act]
                    if inact:
                        ok = all(distn[p] > -PEN_MAX * L or d0[p] <= 0 for p in inact) and all(
                            d0[p] - distn[p] <= max(0.5 * d0[p], 0.0) + PEN_MAX * L for p in inact if d0[p] > 0
                        )
                mn = float(np.linalg.norm(Rn * wts))
                # Armijo on the weighted merit, or (near round-off) a halved max residual
                if ok and (mn < (1.0 - 1e-4 * step) * merit or (
                        float(np.max(np.abs(Rn))) < 0.5 * res and mn < max(2.0 * merit, 1e-3 * tol ** 0.5))):
                    accepted = True
                    break
                step *= 0.5
            if not accepted:
                self.N, self.lam[stick_act] = N, lam
                return False, "stalled", q
            q, N, lam, R, dist, Gn, Gs = qn, Nn, ln, Rn, distn, Gnn, Gsn
            # a pair that starts touching joins the set at once
            if contacts:
                newp = [p for p in range(len(self.pairs)) if p not in self.normal_active and dist[p] < 0.0]
                if newp:
                    self.normal_active = self.normal_active + newp
                    N = np.append(N, np.zeros(len(newp)))
                    R, dist, Gn, Gs = self._residual(q, N, lam, idx)
        self.N = N
        self.lam[stick_act] = lam
        return True, "ok", q

    def _reanchor(self, q) -> None:
        """Move every stick's anchors to its pair's current contact point."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        ft = np.zeros(6)
        for s in self.sticks:
            mujoco.mj_geomDistance(m, sd, s.geoms[0], s.geoms[1], self.scene.length, ft)
            s.reanchor(sd, 0.5 * (ft[:3] + ft[3:]))

    def _constraint_curvature(self, q, N, lam, stick_act) -> np.ndarray:
        """FD of ``G_n' N + G_s' lambda`` over q (geometric stiffness of the constraints)."""
        m = self.scene.model
        act = self.normal_active

        def gen(qq):
            out = np.zeros(m.nv)
            if act:
                out += self._dist_grad(qq, act).T @ N
            if stick_act:
                self.st.d.qpos[:] = qq
                mujoco.mj_kinematics(m, self.st.d)
                _, Gs = self.st.stick_rows(self.sticks)
                out += Gs[stick_act].T @ lam
            return out

        base = gen(q)
        C = np.zeros((m.nv, m.nv))
        for c in range(m.nv):
            h = 1e-6 * self.st.lscale[c]
            v = np.zeros(m.nv)
            v[c] = h
            qp = q.copy()
            mujoco.mj_integratePos(m, qp, v, 1.0)
            C[:, c] = (gen(qp) - base) / h
        return C

    def _commit(self, q) -> None:
        d = self.scene.data
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(self.scene.model, d)
        self.st.forces(q)

    # -- friction bookkeeping ------------------------------------------------
    def stick_now(self) -> int:
        """Sticking constraints at every current finger-workpiece contact; returns how many."""
        sc = self.scene
        m, sd = sc.model, self.st.d
        self.st.forces(sc.data.qpos)
        self.sticks, self.sliding = [], {}
        wg = set(int(g) for g in sc.workpiece_geoms)
        for f in range(sc.fingers):
            mine = set(int(g) for g in sc.contact_geoms[f])
            best = None
            for i in range(sd.ncon):
                g1, g2 = int(sd.contact.geom1[i]), int(sd.contact.geom2[i])
                if g1 in mine and g2 in wg:
                    fn = _normal_force(m, sd, i)
                    if best is None or fn > best[0]:
                        best = (fn, i, g1, g2)
            if best is None:
                continue
            _, i, g1, g2 = best
            p = np.array(sd.contact.pos[i])
            bf, bw = int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])
            normal = np.array(sd.contact.frame[i][:3])
            t = np.cross(np.array([0.0, 1.0, 0.0]), normal)  # in-plane tangent
            if np.linalg.norm(t) < 1e-6:  # out-of-plane normal (tip deep in the box): no planar stick
                continue
            t /= np.linalg.norm(t)
            tb = bw if sc.grip in ("I", "II") else bf
            self.sticks.append(
                _Stick(
                    finger=f,
                    body_f=bf,
                    local_f=sd.xmat[bf].reshape(3, 3).T @ (p - sd.xpos[bf]),
                    body_w=bw,
                    local_w=sd.xmat[bw].reshape(3, 3).T @ (p - sd.xpos[bw]),
                    t_body=tb,
                    t_local=sd.xmat[tb].reshape(3, 3).T @ t,
                    geoms=(g1, g2),
                )
            )
        self.lam = np.zeros(len(self.sticks))
        return len(self.sticks)

    def normals_of_sticks(self) -> np.ndarray:
        out = np.zeros(len(self.sticks))
        for i, s in enumerate(self.sticks):
            p = self._pair_of(s)
            if p in self.normal_active:
                out[i] = self.N[self.normal_active.index(p)]
        return out

    def cone_violations(self) -> list[tuple[int, float]]:
        """``(stick index, sign of lambda)`` for sticks whose friction exceeds ``mu N``."""
        m = self.scene.model
        normals = self.normals_of_sticks()
        out = []
        for i, s in enumerate(self.sticks):
            if i in self.sliding:
                continue
            mu = float(m.pair_friction[self._pair_of(s)][0])
            if normals[i] <= 0.0 or abs(self.lam[i]) > mu * normals[i] * (1.0 + 1e-9):
                out.append((i, math.copysign(1.0, self.lam[i])))
        return out

    def friction_forces(self) -> np.ndarray:
        """Friction force on each stick's finger along its tangent (sticking or sliding)."""
        m = self.scene.model
        normals = self.normals_of_sticks()
        out = self.lam.copy()
        for i, sign in self.sliding.items():
            out[i] = sign * float(m.pair_friction[self._pair_of(self.sticks[i])][0]) * normals[i]
        return out

    def full_residual(self, q) -> np.ndarray:
        """MuJoCo's own static residual (contacts on) plus the friction forces, scaled."""
        m = self.scene.model
        r = self.st.forces(q)
        if self.sticks:
            _, G = self.st.stick_rows(self.sticks)
            r = r + G.T @ self.friction_forces()
        return r / self.st.fscale


# ---------------------------------------------------------------------------
# reading the state


def _read(scene: Scene, run: _Newton, t0: float, held: bool, converged: bool) -> SettledState:
    m, d = scene.model, scene.data
    mujoco.mj_forward(m, d)
    L, W = scene.length, scene.force_scale
    n = scene.n
    q = np.array(d.qpos[scene.joint_qpos])
    phi = np.cumsum(q, axis=1)
    nodes = np.stack([link_positions(p, 1.0 / n) for p in phi])
    st = run.st
    fric = run.friction_forces() if (run.sticks and held) else np.zeros(0)
    if not held:
        run.sticks, run.sliding = [], {}
    full = run.full_residual(d.qpos)
    if not held:
        full[np.asarray(scene.workpiece_dof, dtype=int)] = 0.0  # parked
    residual = float(np.max(np.abs(full)))
    sd = st.d
    contacts = []
    pen_max = 0.0
    wg = set(int(g) for g in scene.workpiece_geoms)
    for f in range(scene.fingers if held else 0):
        mine = set(int(g) for g in scene.contact_geoms[f])
        cons = [i for i in range(sd.ncon) if int(sd.contact.geom1[i]) in mine and int(sd.contact.geom2[i]) in wg]
        if not cons:
            continue
        Fw = np.zeros(3)
        point = np.zeros(3)
        wsum = 0.0
        pen = 0.0
        for i in cons:
            fw = _contact_world_force(m, sd, i)
            Fw += fw
            w = max(float(np.linalg.norm(fw)), 1e-300)
            point += w * np.asarray(sd.contact.pos[i])
            wsum += w
            pen = max(pen, -float(sd.contact.dist[i]) / L)
        point /= wsum
        for k, s in enumerate(run.sticks):
            if s.finger == f and k < fric.size:
                Fw += fric[k] * s.tangent(sd)
        pen_max = max(pen_max, pen)
        contacts.append(_finger_contact(scene, f, Fw, point, pen, nodes, phi, _contact_mu(run, f, fric)))
    pose = _workpiece_pose(scene)
    return SettledState(
        grip=scene.grip,
        links=n,
        fingers=scene.fingers,
        joint_angles=q,
        link_angles=phi,
        nodes=nodes,
        tip=nodes[:, -1].copy(),
        contacts=contacts,
        workpiece_pose=pose,
        held=held,
        steps=run.iterations,
        newton_iterations=run.iterations,
        forward_calls=st.calls,
        wall_time_s=time.perf_counter() - t0,
        residual=residual,
        penetration=pen_max,
        converged=converged,
        qpos=d.qpos.copy(),
    )


def _workpiece_pose(scene: Scene):
    if not scene.has_workpiece:
        return None
    d, L = scene.data, scene.length
    x = d.xpos[scene.workpiece_body]
    rot = d.xmat[scene.workpiece_body].reshape(3, 3)
    return np.array([x[0] / L, x[2] / L, math.atan2(rot[0, 2], rot[0, 0])])


def _finger_contact(scene: Scene, f: int, Fw, point, pen: float, nodes, phi, mu_contact: float) -> FingerContact:
    """Theory-frame reading of the workpiece's world force ``Fw`` on finger ``f`` acting at ``point``."""
    L, W, n = scene.length, scene.force_scale, scene.n
    F = np.array([scene.mirror[f] * Fw[0], Fw[2]]) / W
    p2 = np.array([scene.mirror[f] * point[0], point[2]]) / L
    if scene.grip in ("I", "II"):
        gamma, theta = 1.0, float(phi[f, -1])
        cpoint = nodes[f, -1]
        normal, friction = F[0], F[1]
    else:
        li = _link_of(scene, f, p2, nodes[f], phi[f])
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
    return FingerContact(
        N1=float(F[0]),
        N2=float(F[1]),
        normal=float(normal),
        friction=float(friction),
        gamma=float(gamma),
        point=np.array(cpoint),
        theta=theta,
        moment=float(arm[0] * F[1] - arm[1] * F[0]),
        penetration=pen,
        required_mu=abs(friction) / normal if normal > 0 else math.inf,
        required_mu_contact=mu_contact,
    )


def _contact_mu(run, finger, fric) -> float:
    """|friction| / normal in MuJoCo's contact frame (the one its friction cone uses)."""
    normals = run.normals_of_sticks() if run.sticks else np.zeros(0)
    for k, s in enumerate(run.sticks):
        if s.finger == finger and k < fric.size and normals[k] > 0:
            return abs(float(fric[k])) / float(normals[k])
    return math.nan


def _link_of(scene, f, point, nodes, phi) -> int:
    n = scene.n
    best, bi = math.inf, 0
    for i in range(n):
        t = np.array([math.cos(phi[i]), math.sin(phi[i])])
        u = float(np.clip(np.dot(point - nodes[i], t), 0.0, 1.0 / n))
        dist = float(np.linalg.norm(point - nodes[i] - u * t))
        if dist < best:
            best, bi = dist, i
    return bi


# ---------------------------------------------------------------------------
# method="dynamics": MuJoCo's own contact and friction, over-damped


#: Time step over ``1 / omega_min`` (lowest hinge mode with the physical inertia).
DYN_STEP = 1.0
#: Hinge damping time over the time step: ``D = DYN_DAMPING h K`` (over-damped, n-independent).
DYN_DAMPING = 1.0
#: Workpiece damping: ``D_w = DYN_WORKPIECE_DAMPING m_w / h`` (over-damped, no stiffness to scale by).
DYN_WORKPIECE_DAMPING = 3.0
#: Grip III: largest free fall of the workpiece per step, over the contact radii ``r_link + r_corner``.
DYN_FALL_STEP = 0.3
#: Contact time constant over the time step (refsafe off: mjINT_DISCRETE solves contacts implicitly).
DYN_TIMECONST = 1e-2
#: Friction-to-normal impedance ratio: MuJoCo's sticking friction creeps at a speed ~ 1/impratio.
DYN_IMPRATIO = 1e4
#: Default static residual tolerance of the dynamic settle (the creep floor is ~2e-6).
DYN_TOL = 1e-5
#: Velocity tolerance (rad or l per sqrt(l/g)).
DYN_VTOL = 1e-6
#: Closing ramp: largest change of the total rest rotation per physics step [rad] (one step moves
#: the finger most of the way to the new equilibrium, and a tip jumping deeper than ~0.05 l
#: into the face in one step is not pushed back: measured).
DYN_CLOSE_RATE = 0.05
#: Penetration (over l) above which the dynamic settle restarts with half the time step.
DYN_PEN_LIMIT = 1e-4
#: Physics steps over which the workpiece's holding force fades out at release.
DYN_RELEASE_STEPS = 20
#: Tangential slip (over l) of the tip on the workpiece after release that counts as a drop.
DYN_DROP_SLIP = 0.02


class _Dyn:
    """Over-damped MuJoCo dynamics (``mjINT_DISCRETE``) configured from the model's scales."""

    def __init__(self, scene: Scene, step_factor: float = 1.0):
        self.scene = scene
        m, d = scene.model, scene.data
        self.m, self.d = m, d
        self.fscale, self.lscale = _scales(scene)
        self.vscale = self.lscale / math.sqrt(scene.length / scene.physical.g)
        self.rd = mujoco.MjData(m)
        self.steps = 0
        self.calls = 0
        k = m.jnt_stiffness[m.dof_jntid].copy()
        sprung = np.flatnonzero(k > 0)
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        w2 = np.linalg.eigvals(np.linalg.solve(M[np.ix_(sprung, sprung)], np.diag(k[sprung]))).real
        self.omega_min = math.sqrt(float(w2[w2 > 0].min()))
        h = step_factor * DYN_STEP / self.omega_min
        self.h = h
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        m.opt.timestep = h
        m.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        m.opt.impratio = DYN_IMPRATIO
        m.opt.noslip_iterations = 0  # no effect on pair contacts with mjINT_DISCRETE (measured)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
        m.dof_damping[:] = DYN_DAMPING * h * k
        wd = np.asarray(scene.workpiece_dof, dtype=int)
        if wd.size:
            dw = DYN_WORKPIECE_DAMPING / h
            if scene.grip == "III":
                # the corner meets thin capsules: falling freely, the workpiece may move at most
                # DYN_FALL_STEP contact radii per step (else it tunnels through the rod)
                r = (scene.r_link + scene.r_corner) * scene.length
                slow = max(1.0, scene.physical.g * h / (DYN_FALL_STEP * r) / dw)
                dw *= slow
                # the finger slowed alike: a sliding corner must not see the rod spring away
                m.dof_damping[:] *= slow
            m.dof_damping[wd] = dw * scene.workpiece_mass
            for j, name in zip(wd, scene.workpiece_joints):
                if name == "ry":  # rotation: inertia about y instead of mass
                    m.dof_damping[j] = DYN_WORKPIECE_DAMPING * float(M[j, j]) / h
        if m.npair:
            m.pair_solref[:] = [DYN_TIMECONST * h, 1.0]
            m.pair_solimp[:, 0] = CONTACT_IMPEDANCE
            m.pair_solimp[:, 1] = CONTACT_IMPEDANCE
        self.held_q = None

    def residual(self) -> float:
        """Static residual at rest: ``qfrc_smooth + qfrc_constraint`` at ``qvel = 0`` (MuJoCo's friction included)."""
        m, d, rd = self.m, self.d, self.rd
        rd.qpos[:] = d.qpos
        rd.qvel[:] = 0.0
        rd.qfrc_applied[:] = d.qfrc_applied
        mujoco.mj_forward(m, rd)
        self.calls += 1
        r = (rd.qfrc_smooth + rd.qfrc_constraint) / self.fscale
        if self.held_q is not None:
            r[np.asarray(self.scene.workpiece_dof, dtype=int)] = 0.0
        return float(np.max(np.abs(r)))

    def velocity(self) -> float:
        v = np.array(self.d.qvel) / self.vscale
        if self.held_q is not None:
            v[np.asarray(self.scene.workpiece_dof, dtype=int)] = 0.0
        return float(np.max(np.abs(v))) if v.size else 0.0

    def step(self) -> None:
        m, d = self.m, self.d
        mujoco.mj_step(m, d)
        self.steps += 1
        self.calls += 1
        if self.held_q is not None:
            d.qpos[self.scene.workpiece_qpos] = self.held_q
            d.qvel[self.scene.workpiece_dof] = 0.0
        if not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel)):
            raise SettleError("dynamic settle diverged (non-finite state)")
        _check_warnings(d)

    def hold(self, on: bool) -> None:
        _hold(self.scene, on)
        self.held_q = np.array(self.d.qpos[self.scene.workpiece_qpos]) if on else None

    def run(self, tol, vtol, budget, watch=None) -> tuple[bool, str]:
        """Step until residual < tol and velocity < vtol; ``watch()`` returning a reason stops early."""
        while True:
            # the residual (one more forward pass) only once at rest: halves the cost of a step
            if self.velocity() < vtol:
                r = self.residual()
                if not math.isfinite(r):
                    raise SettleError("dynamic settle diverged (non-finite residual)")
                if r < tol:
                    return True, "ok"
            if watch is not None:
                why = watch()
                if why:
                    return False, why
            if self.steps >= budget:
                return False, "max_steps"
            self.step()


def _slip_coordinate(scene: Scene) -> float:
    """Tangential position (over l) of the contact on the workpiece: tip height minus workpiece height."""
    d = scene.data
    if scene.grip in ("I", "II"):
        return float(d.geom_xpos[scene.tip_geom[0]][2] - d.xpos[scene.workpiece_body][2]) / scene.length
    return 0.0


def _lower_onto(scene: Scene) -> None:
    """Lower a hovering workpiece (placement round-off) until its nearest pair touches (1e-9 l deep)."""
    m, d = scene.model, scene.data
    wz = [qa for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos) if name == "z"]
    if not wz or m.npair == 0:
        return
    L = scene.length
    for _ in range(3):
        mujoco.mj_kinematics(m, d)
        gap = min(mujoco.mj_geomDistance(m, d, int(m.pair_geom1[i]), int(m.pair_geom2[i]), L, None)
                  for i in range(m.npair))
        if gap < 0.0:
            break
        d.qpos[wz[0]] -= gap + 1e-9 * L
    mujoco.mj_forward(m, d)


def _finger_pairs_touching(scene: Scene) -> bool:
    d = scene.data
    mine = set(int(g) for f in range(scene.fingers) for g in scene.contact_geoms[f])
    wg = set(int(g) for g in scene.workpiece_geoms)
    return any((int(d.contact.geom1[i]) in mine and int(d.contact.geom2[i]) in wg) for i in range(d.ncon))


def _settle_dynamics(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                     allow_unconverged: bool, t0: float) -> SettledState:
    """Over-damped settle; the time step halves (from the start) while penetration >= DYN_PEN_LIMIT."""
    d = scene.data
    q0 = d.qpos.copy()
    steps = calls = 0
    factor = 1.0
    for _attempt in range(4):
        # max_steps is the budget of the whole settle: a restart gets what the earlier attempts left
        state = _settle_dynamics_once(scene, tol, max_steps - steps, warm_start, close, allow_unconverged, t0, factor)
        steps += state.steps
        calls += state.forward_calls
        if state.penetration < DYN_PEN_LIMIT or _attempt == 3 or steps >= max_steps or not state.converged:
            break
        d.qpos[:] = q0
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        mujoco.mj_forward(scene.model, d)
        factor *= 0.5
    state.steps, state.forward_calls = steps, calls
    return state


def _settle_dynamics_once(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                          allow_unconverged: bool, t0: float, step_factor: float) -> SettledState:
    m, d = scene.model, scene.data
    dyn = _Dyn(scene, step_factor)
    vtol = DYN_VTOL
    held = scene.has_workpiece
    converged, why = True, "ok"
    if warm_start is not None:
        held = warm_start.held and scene.has_workpiece
    contact_off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    flags = int(m.opt.disableflags)
    dim = m.pair_dim.copy()
    closed = False
    if scene.has_workpiece and held:
        if scene.grip in ("I", "II") and warm_start is None and close:
            # ramp the curvature with contact on, the workpiece held and frictionless
            target = scene.profile
            dyn.hold(True)
            m.pair_dim[:] = 1
            try:
                stages = max(1, math.ceil(float(np.sum(np.abs(scene.springs.rest))) / DYN_CLOSE_RATE))
                for i in range(1, stages + 1):
                    if dyn.steps >= max_steps:
                        break
                    set_curvature(scene, target.scaled(i / stages))
                    dyn.step()
                conv, why = dyn.run(max(tol, 1e-8), vtol, max_steps)
            finally:
                set_curvature(scene, target)
                m.pair_dim[:] = dim
            if not conv:
                converged = False
            held = _finger_pairs_touching(scene)
            closed = True
        if held and converged and not scene.free_workpiece:  # fixed workpiece: settle against it
            dyn.hold(False)
            converged, why = dyn.run(tol, vtol, max_steps)
        elif held and converged:
            s0 = _slip_coordinate(scene)
            z0 = float(d.xpos[scene.workpiece_body][2])
            # let go gently: the holding force fades out over DYN_RELEASE_STEPS steps, so the
            # workpiece never moves more than a contact radius in one step (no tunnelling)
            # (after closing: the finger carries no load yet).  A loaded start (Grip III,
            # warm start) is released at once, the workpiece lowered onto the rod first so
            # that MuJoCo sees the contact in the first step.
            if closed:
                dyn.hold(True)
                dyn.held_q = None
                wz = [dof for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof) if name == "z"]
                weight = scene.workpiece_mass * scene.physical.g
                for i in range(1, DYN_RELEASE_STEPS + 1):
                    d.qfrc_applied[wz] = weight * (1.0 - i / DYN_RELEASE_STEPS)
                    dyn.step()  # 20 steps: counted, and run() below stops at the budget
            else:
                _lower_onto(scene)
            dyn.hold(False)
            if warm_start is not None and warm_start.rest is not None and warm_start.rest.shape == (scene.n,):
                # warm start: ramp the rest angles from the previous state's (loaded, friction on)
                target = scene.springs.rest.copy()
                stages = max(1, math.ceil(float(np.sum(np.abs(target - warm_start.rest))) / DYN_CLOSE_RATE))
                for i in range(1, stages + 1):
                    if dyn.steps >= max_steps:
                        break
                    m.qpos_spring[scene.joint_qpos] = (warm_start.rest + (target - warm_start.rest) * i / stages)[None, :]
                    dyn.step()
                m.qpos_spring[scene.joint_qpos] = target[None, :]

            def watch():
                fell = (z0 - float(d.xpos[scene.workpiece_body][2])) / scene.length > DYN_DROP_SLIP
                if fell and not _finger_pairs_touching(scene):
                    return "lost contact"
                if scene.grip in ("I", "II") and abs(_slip_coordinate(scene) - s0) > DYN_DROP_SLIP:
                    return "slipped"
                return None

            converged, why = dyn.run(tol, vtol, max_steps, watch)
            if why in ("lost contact", "slipped"):
                held, converged = False, True
    if not (scene.has_workpiece and held) and converged:
        if scene.has_workpiece:  # park the workpiece, settle the finger alone
            dyn.hold(True)
            m.opt.disableflags = flags | contact_off
        converged, why = dyn.run(tol, vtol, max_steps)
    if not converged and not allow_unconverged:
        raise SettleError(f"dynamic settle did not converge ({why} after {dyn.steps} steps)")
    return _read_dynamics(scene, dyn, t0, held, converged)


def _read_dynamics(scene: Scene, dyn: _Dyn, t0: float, held: bool, converged: bool) -> SettledState:
    """The settled state from MuJoCo's own contact forces (friction included), at rest."""
    m, d = scene.model, scene.data
    residual = dyn.residual()
    vmax = dyn.velocity()
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    L, W = scene.length, scene.force_scale
    n = scene.n
    q = np.array(d.qpos[scene.joint_qpos])
    phi = np.cumsum(q, axis=1)
    nodes = np.stack([link_positions(p, 1.0 / n) for p in phi])
    contacts, pen_max = [], 0.0
    wg = set(int(g) for g in scene.workpiece_geoms)
    for f in range(scene.fingers if held else 0):
        mine = set(int(g) for g in scene.contact_geoms[f])
        cons = [i for i in range(d.ncon) if int(d.contact.geom1[i]) in mine and int(d.contact.geom2[i]) in wg]
        if not cons:
            continue
        Fw, point, wsum, pen, fn, ft = np.zeros(3), np.zeros(3), 0.0, 0.0, 0.0, np.zeros(2)
        for i in cons:
            fw = _contact_world_force(m, d, i)
            Fw += fw
            w = max(float(np.linalg.norm(fw)), 1e-300)
            point += w * np.asarray(d.contact.pos[i])
            wsum += w
            pen = max(pen, -float(d.contact.dist[i]) / L)
            fc = np.zeros(6)
            mujoco.mj_contactForce(m, d, i, fc)
            fn += fc[0]
            ft += fc[1:3]
        point /= wsum
        contacts.append(_finger_contact(scene, f, Fw, point, pen, nodes, phi,
                                        float(np.linalg.norm(ft)) / fn if fn > 0 else math.inf))
        pen_max = max(pen_max, pen)
    pose = _workpiece_pose(scene)
    return SettledState(
        grip=scene.grip, links=n, fingers=scene.fingers, joint_angles=q, link_angles=phi, nodes=nodes,
        tip=nodes[:, -1].copy(), contacts=contacts, workpiece_pose=pose, held=held, steps=dyn.steps,
        newton_iterations=0, forward_calls=dyn.calls, wall_time_s=time.perf_counter() - t0, residual=residual,
        penetration=pen_max, converged=converged, qpos=d.qpos.copy(), method="dynamics", velocity=vmax,
        timestep=dyn.h,
    )


def _check_tip(scene: Scene, state: SettledState) -> None:
    """Grip III condition (23): flag links beyond the contact that reach the workpiece's bottom face.

    The corner contact is only on the links near the initial contact (no pair
    elsewhere), so MuJoCo lets a curling tip pass through the workpiece; the
    theory requires the rod beyond ``gamma`` to stay below the bottom face.
    A node beyond the contact that lies under the box (``|x| < b/2``, finger
    frame) within ``r_link`` of the bottom face or above it violates (23).
    """
    if scene.grip != "III" or not state.held or state.workpiece_pose is None:
        return
    L = scene.length
    bottom = state.workpiece_pose[1] - scene.box_half[2] / L
    half = scene.box_half[0] / L
    for f, c in enumerate(state.contacts):
        nodes = state.nodes[f]
        s = np.arange(scene.n + 1) / scene.n
        beyond = nodes[s > c.gamma + 1e-12]
        x = beyond[:, 0] - state.workpiece_pose[0] * scene.mirror[f]
        bad = (np.abs(x) < half) & (beyond[:, 1] + scene.r_link >= bottom)
        if np.any(bad):
            state.tip_clear = False
            state.warnings.append(
                f"finger {f}: the rod beyond the contact (s > {c.gamma:.4f}) reaches the workpiece's bottom face "
                f"(condition (23) violated: the tip passes through the box, no contact pair there)"
            )


# ---------------------------------------------------------------------------
# public entry points


def _check_settle_args(scene, tol, max_steps):
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a simgrip.sim.scene.Scene, got {type(scene).__name__}")
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise ValueError(f"tol must be a real number, got {tol!r}") from None
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be positive and finite, got {tol!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
    return tol, int(max_steps)


def settle(scene: Scene, **kw) -> SettledState:  # signature and docstring: _settle's (functools.wraps below)
    with blas_threads(1):  # small dense Newton systems: multithreaded OpenBLAS only spins (simgrip.threads)
        return _settle(scene, **kw)


def _settle(
    scene: Scene,
    *,
    tol: float | None = None,
    max_steps: int | None = None,
    warm_start: SettledState | None = None,
    close: bool = True,
    allow_unconverged: bool = False,
    method: str = "newton",
) -> SettledState:
    """Drive ``scene`` to static equilibrium (see the module docstring).

    Parameters
    ----------
    scene : Scene
    tol : float, optional
        Static residual tolerance (generalised forces over ``rho g l^2`` / ``rho g l``);
        default :data:`DEFAULT_TOL` (Newton) or :data:`DYN_TOL` (dynamics).
    max_steps : int, optional
        Newton iterations (default :data:`NEWTON_BUDGET`, one solve at most
        :data:`SOLVE_ITERS`) or physics steps (dynamics, default 20000)
        allowed to the whole settle; a spent budget raises :class:`SettleError`.
    warm_start : SettledState, optional
        Start from this state (same scene layout); skips the closing phase and
        sticks the workpiece where it touches.
    close : bool
        Grips I/II: run the closing procedure (curl, place and hold the
        workpiece, ramp, release).  ``False`` releases from the current state.
    allow_unconverged : bool
        Return ``converged=False`` instead of raising when the solve does not
        converge or the final residual is above :attr:`SettledState.tolerance`.
    method : {"newton", "dynamics"}
        ``"newton"`` (default): the static Newton-KKT solve with simgrip's
        sticking constraints.  ``"dynamics"``: over-damped MuJoCo dynamics
        with MuJoCo's own contact and friction (see :class:`_Dyn` and the
        module docstring); ``steps`` counts physics steps.

    Returns
    -------
    SettledState

    Raises
    ------
    ValueError
        Bad arguments.
    SettleError
        Divergence (non-finite residual, MuJoCo warning), or no convergence
        unless ``allow_unconverged``.
    """
    if method not in ("newton", "dynamics"):
        raise ValueError(f"method must be 'newton' or 'dynamics', got {method!r}")
    if tol is None:
        # dynamics: MuJoCo's sticking friction creeps (~1e-5 of the weight), so a
        # scene with a workpiece stops at DYN_TOL; without contact it goes as far as Newton.
        tol = DEFAULT_TOL if method == "newton" or not scene.has_workpiece else DYN_TOL
    if max_steps is None:
        max_steps = NEWTON_BUDGET if method == "newton" else 20_000
    tol, max_steps = _check_settle_args(scene, tol, max_steps)
    if warm_start is not None and not isinstance(warm_start, SettledState):
        raise ValueError(f"warm_start must be a SettledState or None, got {type(warm_start).__name__}")
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved = _save(m)
    for i in range(len(d.warning)):
        d.warning[i].number = 0
    run = _Newton(scene)
    run.budget = max_steps  # every Newton iteration of this settle counts against max_steps
    per = min(SOLVE_ITERS, max_steps)  # one solve's share
    held = scene.has_workpiece
    converged, why = True, "ok"
    try:
        if warm_start is not None:
            if warm_start.qpos.shape != d.qpos.shape:
                raise ValueError("warm_start does not match the scene's layout (qpos size)")
            d.qpos[:] = warm_start.qpos
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            held = warm_start.held and scene.has_workpiece
        if method == "dynamics":
            state = _settle_dynamics(scene, tol, max_steps, warm_start, close, allow_unconverged, t0)
            state.tolerance = tol
            if state.converged and not state.residual <= tol:  # converged means residual <= tol
                state.converged = False
                if not allow_unconverged:
                    raise SettleError(f"dynamic settle did not converge (static residual {state.residual:.3g} above "
                                      f"the tolerance {tol:.3g} after {state.steps} steps)")
            _check_tip(scene, state)
            state.rest = scene.springs.rest.copy()
            return state
        _configure(scene)
        wdofs = tuple(int(x) for x in scene.workpiece_dof)
        if scene.has_workpiece and held:
            if scene.grip in ("I", "II") and warm_start is None and close:
                target = scene.profile
                try:
                    held = _close(scene, run, tol, per)
                except SettleError:
                    set_curvature(scene, target)
                    # the frictionless closing path can fold (large |kappa|): start
                    # instead from the hinge chain's grip equilibrium, tip on the face
                    held = _place_on_chain(scene, run)
            if held:
                held, converged, why = _release(scene, run, tol, per)
        else:
            converged, why = run.solve(tol, per, frozen=wdofs)
        if scene.has_workpiece and not held and not run.spent():
            # dropped: a release without an equilibrium (Newton stalls as the workpiece falls) is a
            # drop too; a spent budget is not
            converged, why = _finger_alone(scene, run, tol, per)
        if not converged and not allow_unconverged:
            raise SettleError(f"settle did not converge ({why} after {run.iterations} Newton iterations)")
        state = _read(scene, run, t0, held, converged)
        # converged means residual <= tolerance: the reported (MuJoCo) residual is checked, not
        # only Newton's own KKT rows; a grip's tolerance is raised to its contact round-off floor
        state.tolerance = max(tol, min(run.noise_floor(), RESIDUAL_FLOOR_MAX)) if held else tol
        if state.converged and not state.residual <= state.tolerance:
            state.converged = False
            if not allow_unconverged:
                raise SettleError(f"settle did not converge (static residual {state.residual:.3g} above the "
                                  f"tolerance {state.tolerance:.3g} after {run.iterations} Newton iterations)")
        _check_tip(scene, state)
        state.rest = scene.springs.rest.copy()
    finally:
        _restore(m, saved)
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return state


settle = functools.wraps(_settle)(settle)
settle.__name__ = settle.__qualname__ = "settle"


def _hold(scene: Scene, on: bool) -> None:
    """Hold the workpiece: its weight cancelled by ``qfrc_applied`` (its dofs are also frozen)."""
    d = scene.data
    weight = scene.workpiece_mass * scene.physical.g
    for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof):
        d.qfrc_applied[dof] = weight if (on and name == "z") else 0.0


def _finger_alone(scene, run, tol, max_steps):
    """The workpiece is gone: park it (held, no contact) and settle the finger."""
    m = scene.model
    _hold(scene, True)
    run.sticks, run.sliding, run.lam = [], {}, np.zeros(0)
    run.normal_active, run.N = [], np.zeros(0)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return run.solve(tol, max_steps, frozen=tuple(int(x) for x in scene.workpiece_dof))


def _release(scene: Scene, run: _Newton, tol: float, max_steps: int) -> tuple[bool, bool, str]:
    """Let go of the workpiece: stick it where it touches, settle, check the friction cone.

    Returns ``(held, converged, reason)``.  Grips I/II: a violated cone drops the
    workpiece.  Grip III: violated sticks slide with friction ``mu N`` until the
    settled state holds, then stick again.
    """
    _hold(scene, False)
    if not scene.free_workpiece:
        conv, why = run.solve(tol, max_steps, frozen=tuple(int(x) for x in scene.workpiece_dof))
        return True, conv, why
    _touch(scene, run)
    if run.stick_now() == 0:
        return False, True, "no contact"
    for _ in range(6):
        conv, why = run.solve(tol, max_steps)
        if not conv:
            if scene.grip == "III" or why != "stalled" or run.spent():
                return False, conv, why
            return False, True, "dropped"
        bad = run.cone_violations()
        if not bad:
            return True, True, "ok"
        if scene.grip in ("I", "II"):
            return False, True, "dropped"
        for i, sign in bad:
            run.sliding[i] = sign
        conv, why = run.solve(tol, max_steps)
        if not conv:
            if run.spent():
                return False, False, why
            return False, True, "dropped"
        run.stick_now()  # stopped sliding: stick at the new contact
    return False, False, "friction did not settle"


def _place_on_chain(scene: Scene, run: _Newton) -> bool:
    """Fallback start for Grips I/II: the hinge chain's equilibrium, workpiece at the tip."""
    from simgrip.reference.discrete import DiscreteError, solve_chain

    try:
        # the tip a hair inside the face so that MuJoCo reports the contact
        ch = solve_chain(scene.grip, scene.params.replace(b=scene.params.b - 2e-6), scene.profile, scene.n)
    except DiscreteError as exc:
        raise SettleError(f"no starting shape for grip {scene.grip}: {exc}") from exc
    d = scene.data
    d.qpos[scene.joint_qpos] = ch.joint_angles[None, :]
    run.N, run.normal_active = np.zeros(0), []
    scene.model.opt.disableflags = run._flags if hasattr(run, "_flags") else scene.model.opt.disableflags
    _place_workpiece(scene, float(ch.tip[1]) * scene.length)
    return True


def _touch(scene: Scene, run: _Newton) -> None:
    """Lower the workpiece onto the finger(s) if it hovers (placement round-off)."""
    d = scene.data
    wz = [qa for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos) if name == "z"]
    if not wz or not run.pairs:
        return
    for _ in range(3):
        gap = float(np.min(run._dists(d.qpos)))
        if gap <= 0.0:
            break
        d.qpos[wz[0]] -= gap + 1e-9 * scene.length
    mujoco.mj_forward(scene.model, d)


def _close(scene: Scene, run: _Newton, tol: float, max_steps: int) -> bool:
    """Grips I/II closing: curl (contact off) to first touch, place and hold the box, ramp.

    Returns False when the finger cannot reach the workpiece (its free tip never
    comes back to ``X = b/2``).
    """
    m = scene.model
    target = scene.profile
    half = 0.5 * scene.params.b
    wdofs = tuple(int(x) for x in scene.workpiece_dof)
    loose = max(tol, 1e-8)
    flags = int(m.opt.disableflags)

    def free_tip(t):
        set_curvature(scene, target.scaled(t))
        conv, why = run.solve(loose, max_steps, frozen=wdofs)
        if not conv:
            raise SettleError(f"free finger did not settle while closing ({why})")
        return _tip(scene)[0]

    _hold(scene, True)
    m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    x1 = free_tip(1.0)
    if x1 > half:
        set_curvature(scene, target)
        m.opt.disableflags = flags
        return False
    x0 = free_tip(0.0)
    lo, hi, xlo, xhi = 0.0, 1.0, x0, x1
    t, x = 1.0, x1
    for _ in range(60):
        t = lo + (hi - lo) * (xlo - half) / (xlo - xhi)
        t = min(max(t, lo + 0.02 * (hi - lo)), hi - 0.02 * (hi - lo))
        x = free_tip(t)
        if x > half:
            lo, xlo = t, x
        else:
            hi, xhi = t, x
        if abs(x - half) < 1e-7 or hi - lo < 1e-10:
            break
    if x < half:  # start just outside the face
        t = lo
        free_tip(t)
    z0 = _tip(scene)[1]
    _place_workpiece(scene, z0 * scene.length)
    m.opt.disableflags = flags
    if _close_predicted(scene, run, target, t, z0, loose, min(max_steps, CLOSE_STAGE_ITERS), wdofs):
        return True
    # continuation in the curvature factor, halving the increment when a stage fails
    s, h = t, (1.0 - t) / CLOSE_STAGES
    while s < 1.0:
        s_next = min(1.0, s + h)
        q_prev, N_prev, act_prev = scene.data.qpos.copy(), run.N.copy(), list(run.normal_active)
        set_curvature(scene, target.scaled(s_next))
        conv, why = run.solve(loose, min(max_steps, CLOSE_STAGE_ITERS), frozen=wdofs)
        if conv:
            s = s_next
            continue
        if h < (1.0 - t) / CLOSE_STAGES / 8:
            raise SettleError(f"closing on the held workpiece did not converge ({why}, curvature factor {s_next:g})")
        scene.data.qpos[:] = q_prev
        run.N, run.normal_active = N_prev, act_prev
        h *= 0.5
    set_curvature(scene, target)
    return True


def _close_predicted(scene: Scene, run: _Newton, target, t: float, z0: float, tol: float, max_steps: int,
                     wdofs) -> bool:
    """Closing in two MuJoCo stages: the ramp's first stages on the hinge chain, its last in MuJoCo.

    The held, frictionless state along the closing (workpiece frozen at its
    placement height ``z0``, tip on the face ``X = b/2``, purely normal tip
    load) is the hinge chain's equilibrium of ``solve_chain`` with ``M = 0``
    (~1 ms), the exact state of the same chain with an ideal contact.  The chain
    runs the continuation's stages from the first-touch shape (each warm-started
    from the previous one, so it follows the ramp's branch) up to the
    penultimate one; MuJoCo's Newton corrects that state to MuJoCo's contact and
    then takes the ramp's last stage exactly as :func:`_close` would.  The last
    stage is the hardest (the normal force grows along the ramp): where it
    fails, the ramp would halve it and might fall back to the chain's grip
    equilibrium, so the full ramp runs instead and the answer stays the ramp's.
    Used only when the prediction is valid -- every chain stage converges to a
    stable state (positive projected Hessian) with the tip pushing on the face
    (``N1 > 0``) within the box's height, and both Newton solves converge with
    every tip pair carrying a positive normal force; otherwise the scene and the
    Newton state are restored and False returned (the MuJoCo ramp then runs).
    """
    from simgrip.reference.discrete import DiscreteError, solve_chain

    m, d = scene.model, scene.data
    margin = 0.5 * BOX_HEIGHT - 0.1
    # the tip a hair inside the face so that MuJoCo reports the contact (as _place_on_chain)
    params = scene.params.replace(b=scene.params.b - 2e-6, M=0.0)
    stages = []
    s, h = t, (1.0 - t) / CLOSE_STAGES
    while s < 1.0:  # the stages of _close's continuation, same arithmetic
        s = min(1.0, s + h)
        stages.append(s)
    # the ramp's last real stage starts at the last stage a good step below 1 (the cumulative sum
    # can leave a last stage of round-off size: that one stays in MuJoCo too)
    k = max((i for i, si in enumerate(stages) if 1.0 - si > 0.5 * h), default=-1)
    if k < 0:
        return False
    phi = np.cumsum(np.array(d.qpos[scene.joint_qpos[0]]))
    ch, step, lam0 = None, None, None
    for s in stages[:k + 1]:
        try:
            ch = solve_chain(scene.grip, params, target.scaled(s), scene.n, guess=phi)
        except (DiscreteError, ValueError):
            return False
        if not (ch.success and ch.N1 > 0.0 and ch.min_eigenvalue > 0.0 and abs(float(ch.tip[1]) - z0) < margin):
            return False
        # a fold of the frictionless path (where the ramp's Newton fails and the closing falls
        # back to the chain's grip equilibrium) shows as a softening stability margin or a kink
        # in the path; the coarse chain stages would jump it to another branch: leave it to the ramp
        lam0 = ch.min_eigenvalue if lam0 is None else lam0
        new_step = ch.link_angles - phi
        if ch.min_eigenvalue < FOLD_MARGIN * lam0 or (
                step is not None and np.max(np.abs(new_step - step)) > FOLD_KINK * np.max(np.abs(step))):
            return False
        phi, step = ch.link_angles, new_step
    q_prev, N_prev, act_prev, kc_prev = d.qpos.copy(), run.N.copy(), list(run.normal_active), run.kc.copy()
    profile = scene.profile
    d.qpos[scene.joint_qpos] = ch.joint_angles[None, :]
    mujoco.mj_forward(m, d)
    ok = True
    try:
        for s in stages[k:]:  # MuJoCo at the penultimate stage, then the ramp's last stage(s)
            set_curvature(scene, target.scaled(s))
            conv, _ = run.solve(tol, max_steps, frozen=wdofs)
            ok = (conv and bool(run.pairs) and sorted(run.normal_active) == list(range(len(run.pairs)))
                  and bool(np.all(run.N > 0.0)) and abs(_tip(scene)[1] - z0) < margin)
            if not ok:
                break
    except SettleError:
        if run.spent():
            raise
        ok = False
    if ok:
        return True
    d.qpos[:] = q_prev
    run.N, run.normal_active, run.kc[:] = N_prev, act_prev, kc_prev
    set_curvature(scene, profile)
    mujoco.mj_forward(m, d)
    return False


def _tip(scene) -> np.ndarray:
    q = np.array(scene.data.qpos[scene.joint_qpos[0]])
    return link_positions(np.cumsum(q), 1.0 / scene.n)[-1]


def _place_workpiece(scene: Scene, z: float) -> None:
    m, d = scene.model, scene.data
    body_z = float(m.body_pos[scene.workpiece_body][2])
    for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos):
        d.qpos[qa] = z - body_z if name == "z" else 0.0
    if not scene.free_workpiece:
        m.body_pos[scene.workpiece_body][2] = z
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)


def settle_sweep(scene: Scene, profiles, **kw) -> list[SettledState]:
    """Settle ``scene`` for each profile in turn, warm-starting from the previous state.

    The first profile is settled from the scene's current state (with the
    closing procedure for Grips I/II); the following ones change only
    ``qpos_spring`` (:func:`simgrip.sim.scene.set_curvature`) and start from the
    previous equilibrium.  A dropped workpiece stays dropped.
    """
    out = []
    prev = None
    for p in profiles:
        set_curvature(scene, p)
        st = settle(scene, warm_start=prev, **kw)
        out.append(st)
        prev = st
    return out


def naive_settle(scene: Scene, reference: SettledState, *, tol: float = 1e-6, max_steps: int = 1_000_000,
                 damping_ratio: float = 0.05, check_every: int = 500, start_qpos=None) -> dict:
    """Baseline: plain MuJoCo dynamics with physical inertia, light damping, largest stable step.

    Damping proportional to stiffness gives the lowest hinge mode
    ``damping_ratio`` of critical; the time step is ``1.8 / omega_max`` of the
    undamped chain (semi-implicit Euler's limit is ``2 / omega_max``; the
    ``implicitfast`` damping does not move it), contacts use MuJoCo's safe
    minimum time constant ``2 dt`` and the model's friction settings (elliptic
    cone, no-slip).  Steps from ``start_qpos`` (default: the scene's state)
    until every link angle is within ``tol`` of ``reference`` (the state
    :func:`settle` found), i.e. the time a plain simulation needs to reach the
    same rest state.  Returns a dict: steps, wall_time_s, error (final max angle
    error), converged, dt, workpiece_drift (over l).
    """
    m, d = scene.model, scene.data
    dt0, damp0, solref0 = float(m.opt.timestep), m.dof_damping.copy(), m.pair_solref.copy()
    t0 = time.perf_counter()
    try:
        if start_qpos is not None:
            d.qpos[:] = start_qpos
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        kd = np.where(m.jnt_stiffness[m.dof_jntid] > 0, m.jnt_stiffness[m.dof_jntid], 0.0)
        sub = np.flatnonzero(kd > 0)
        w2 = np.linalg.eigvals(np.linalg.solve(M[np.ix_(sub, sub)], np.diag(kd[sub]))).real
        wmax, wmin = math.sqrt(w2.max()), math.sqrt(w2.min())
        dt = 1.8 / wmax
        m.opt.timestep = dt
        m.dof_damping[:] = 2 * damping_ratio / wmin * kd
        m.pair_solref[:, 0] = 2 * dt
        wz0 = d.xpos[scene.workpiece_body].copy() if scene.has_workpiece else None
        steps, err = 0, math.inf
        while steps < max_steps:
            mujoco.mj_step(m, d, check_every)
            steps += check_every
            if not np.all(np.isfinite(d.qpos)):
                raise SettleError("naive settle diverged")
            phi = np.cumsum(np.array(d.qpos[scene.joint_qpos]), axis=1)
            err = float(np.max(np.abs(phi - reference.link_angles)))
            if err < tol:
                break
        drift = float(np.linalg.norm(d.xpos[scene.workpiece_body] - wz0)) / scene.length if wz0 is not None else 0.0
        return {"steps": steps, "wall_time_s": time.perf_counter() - t0, "error": err, "converged": err < tol,
                "dt": dt, "workpiece_drift": drift}
    finally:
        m.opt.timestep, m.dof_damping[:], m.pair_solref[:] = dt0, damp0, solref0
