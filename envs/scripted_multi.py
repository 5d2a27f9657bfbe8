"""A scripted K-finger pick that chooses the curvature from the per-finger planar theory.

Each finger of a K-finger grip on a box (``K`` = 2, 4, a finger on each face)
or a vertical cylinder is the paper's planar Grip I problem: the tip on a
vertical surface at ``X = b/2`` carrying ``M`` = its share of the weight (the
workpiece's mass over ``K``) by friction.  On a sphere it is the same problem
with the contact normal inclined by ``beta`` (:mod:`simgrip.reference.inclined`).
The controller (an oracle: it reads the episode's true workpiece,
``env.workpiece``) takes the gentlest uniform curvature whose solution holds
with ``required_mu <= mu_s / safety`` (box, cylinder:
:func:`simgrip.envs.scripted.choose_kappa`, as the ``Pick-v1`` controller;
sphere: :func:`choose_kappa_sphere`), and puts the palm at the height where
that solution's tip meets the workpiece (box, cylinder: mid-height of the
face; sphere: at the elevation ``beta`` below its equator; with two fingers
above the centre of mass, see :class:`ScriptedMultiPolicy`).  Open loop:
move the palm there with the fingers straight, ramp the curvature, wait,
lift by ``target_height`` plus an allowance, hold.  :class:`ObservationMultiPolicy` is
the honest variant: it sees only the observation and the env's configuration,
takes the theory's choice for the randomised ranges' worst case and curls
further when it sees the workpiece slip.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.envs.pick_multi_model import half_height, workpiece_size
from simgrip.envs.scripted import choose_kappa, kappa_action
from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.profiles import Uniform
from simgrip.reference.elastica import ElasticaError
from simgrip.reference.inclined import solve_inclined

__all__ = ["ObservationMultiPolicy", "ScriptedMultiPolicy", "choose_kappa_sphere"]

#: Palm clearance above the workpiece's top while it moves with straight fingers [m].
CLEARANCE = 0.012


def choose_kappa_sphere(params: DimensionlessParams, contact_angle: float, *, safety: float = 2.0,
                        kappas=None) -> tuple[float, dict]:
    """Gentlest uniform ``kappa_bar`` whose inclined-contact solution (:func:`~simgrip.reference.inclined.
    solve_inclined`, Grip I, elevation ``contact_angle`` [rad]) holds with ``required_mu <= mu_s / safety``.

    Returns ``(kappa, details)`` with the solution's ``normal_force``, ``required_mu``, ``tip`` and
    ``centre_height`` (dimensionless; ``centre_height`` is the sphere's centre below the palm, negative).  The
    sweep runs from gentle to strong, warm-started, and stops at the first that qualifies; when none does, the
    one with the least required friction is returned.
    """
    if kappas is None:
        kappas = np.arange(-2.0, -8.01, -0.25)
    best, cands, prev = None, [], None
    for k in kappas:
        try:
            s = solve_inclined("I", params, Uniform(float(k)), contact_angle, guess=prev, tol=1e-6)
        except ElasticaError:
            break
        if prev is not None and abs(s.tip[1] - prev.tip[1]) > 0.15:  # a jump to another branch
            break
        prev = s.rod
        if s.normal_force > 0:
            cands.append((s.required_mu, float(k), s))
        if s.feasible and s.required_mu <= params.mu_s / safety:
            best = (float(k), s)
            break
    if best is None:
        if not cands:
            raise ElasticaError(f"no Grip I solution on the sphere at contact angle {contact_angle:g}")
        _, k, s = min(cands, key=lambda c: c[0])
        best = (k, s)
    k, s = best
    return k, {"normal_force": float(s.normal_force), "required_mu": float(s.required_mu),
               "tip": np.array(s.tip), "centre_height": float(s.centre_height)}


class ScriptedMultiPolicy:
    """Oracle open-loop K-finger pick: place the palm, ramp ``kappa`` to the planar theory's choice, lift, hold.

    Use as ``policy.reset(env, info)`` after ``env.reset`` and ``action = policy(obs)`` each step; works with
    ``shared_curvature`` either way (every finger gets the same command).

    Parameters
    ----------
    safety : float
        Friction safety factor: the chosen grip needs at most ``mu_s / safety``.
    contact_angle : float or None
        Sphere: elevation [rad] of the contact normal the palm height aims at.  Default: ``-0.35`` (below the
        equator: the tips push up as well as in) for ``K >= 3``; ``+0.3`` for ``K = 2``, whose two contacts
        lie on one line: the sphere would turn about it were its centre above it.
    contact_height : float or None
        Box, cylinder: height of the tip on the face, as a fraction of the workpiece's height.  Default: 0.5
        for ``K >= 3``, 0.75 for ``K = 2`` (the centre of mass below the line through the two tips).
    ramp_time, settle_time : float
        Seconds to ramp the curvature command, then to wait before lifting.
    lift_speed : float
        Palm speed while lifting, as a fraction of the env's ``palm_speed``.
    extra_lift : float
        Palm travel beyond ``target_height`` [m] (the soft fingers sag under the load).
    """

    def __init__(self, safety: float = 2.0, contact_angle: float | None = None, contact_height: float | None = None,
                 ramp_time: float = 0.6, settle_time: float = 0.3, lift_speed: float = 0.5, extra_lift: float = 0.02):
        self.safety = float(safety)
        self.contact_angle = contact_angle
        self.contact_height = contact_height
        self.ramp_time = float(ramp_time)
        self.settle_time = float(settle_time)
        self.lift_speed = float(lift_speed)
        self.extra_lift = float(extra_lift)
        self.kappa = None
        self.details = {}

    def _plan(self, env) -> tuple[float, float]:
        """``(kappa, palm height [m])`` for the episode's true workpiece (oracle)."""
        w, L = env.workpiece, env.length
        # the contact sits on the tip sphere: its centre is r_tip outside the workpiece's surface
        b_eff = min((w.width + 2.0 * env.r_tip) / L, 1.9)
        p = env.dimensionless().replace(b=b_eff)
        size = workpiece_size(w.shape, w.width, env.workpiece_height)
        top = 2.0 * half_height(w.shape, size)
        pair = env.K == 2
        if w.shape == "sphere":
            beta = self.contact_angle if self.contact_angle is not None else (0.3 if pair else -0.35)
            kappa, self.details = choose_kappa_sphere(p, beta, safety=self.safety)
            palm = 0.5 * w.width - self.details["centre_height"] * L
        else:
            kappa, self.details = choose_kappa("I", p, safety=self.safety)
            tip_y = self.details["tip"][1] if self.details["tip"] is not None else -0.6
            frac = self.contact_height if self.contact_height is not None else (0.75 if pair else 0.5)
            palm = frac * top - tip_y * L
        lo, hi = env.palm_range
        return kappa, min(max(palm, top + CLEARANCE, lo), hi)

    def reset(self, env, info=None):
        """Plan the episode of ``env`` (just reset); returns the chosen curvature."""
        env = env.unwrapped
        self.env = env
        self.kappa, self.palm_grasp = self._plan(env)
        self.palm_target = None
        self.t_grasp = None  # when the palm reached its grasp height [s]
        self.t = 0.0
        return self.kappa

    def __call__(self, obs):
        env = self.env
        step = env.palm_speed * env.dt
        if self.palm_target is None:
            self.palm_target = float(obs[env.obs_slices["palm_height"]][0]) * env.length
            self.palm0 = self.palm_target
        t = self.t
        self.t += env.dt
        k, vz = 0.0, 0.0
        if self.t_grasp is None:  # move the palm to its grasp height with the fingers straight
            gap = self.palm_grasp - self.palm_target
            vz = max(-1.0, min(1.0, gap / step))
            if abs(gap) <= step:
                self.t_grasp = t + env.dt
        else:
            tau = t - self.t_grasp
            w = min(1.0, tau / self.ramp_time) if self.ramp_time > 0 else 1.0
            k = w * self.kappa
            if tau >= self.ramp_time + self.settle_time:
                remaining = self.palm_grasp + env.target_height + self.extra_lift - self.palm_target
                vz = min(self.lift_speed, remaining / step) if remaining > 0 else 0.0
        lo, hi = env.palm_range
        self.palm_target = min(max(self.palm_target + vz * step, lo), hi)
        ak = kappa_action(k, env.kappa_range)
        nk = env.action_space.shape[0] - 1
        return np.array([ak] * nk + [vz], dtype=np.float32)


class ObservationMultiPolicy(ScriptedMultiPolicy):
    """Honest K-finger pick: sees only the observation and the env's configuration, never the workpiece.

    The plan is made from the first observation.  The workpiece's centre height above the table (``palm_height``
    plus ``workpiece_position``'s ``z``) tells a sphere (centre at half its width) from a box or cylinder (centre
    at half ``workpiece_height``, a configuration value): a centre within ``shape_tol`` [m] of that height is
    taken for a box or cylinder.  Every grip takes the randomisation's worst case per finger: the heaviest
    workpiece (``mass_range[1] / K``) and the lowest friction (``friction_range[0]``).  Box or cylinder: the
    strongest of the planar theory's choices (:func:`~simgrip.envs.scripted.choose_kappa`) over ``widths``
    widths spanning ``size_range``, the palm where those solutions' mean tip height meets the face at the
    oracle's fraction of its height.  Sphere: its width is twice the observed centre height, and the choice is
    :func:`choose_kappa_sphere` for that width.  Then, as the oracle: palm down with straight fingers, ramp,
    wait, lift, hold; while lifting and holding, each time the workpiece sinks relative to the palm faster than
    ``slip_speed`` [m/s] or by more than ``slip_drop`` [m] since the lift began, the fingers curl further by
    ``slip_step`` (at most once per ``slip_wait`` s, never beyond ``kappa_range``).  The configuration it reads
    (finger length and stiffness, tip radius, the randomisation's ranges and shapes, workpiece height, control
    step, palm speed and range, curvature range, target height, observation layout) is set by whoever makes the
    env, not hidden state.  Other parameters as :class:`ScriptedMultiPolicy`; ``safety`` defaults to 1 (the worst
    case is already assumed).
    """

    def __init__(self, safety: float = 1.0, widths: int = 5, shape_tol: float = 2e-4, slip_speed: float = 0.02,
                 slip_drop: float = 0.002, slip_step: float = 0.5, slip_wait: float = 0.1, **kwargs):
        super().__init__(safety=safety, **kwargs)
        if int(widths) < 1:
            raise ValueError(f"widths must be at least 1, got {widths!r}")
        self.widths = int(widths)
        self.shape_tol = float(shape_tol)
        self.slip_speed, self.slip_drop = float(slip_speed), float(slip_drop)
        self.slip_step, self.slip_wait = float(slip_step), float(slip_wait)
        self._prismatic = {}  # configuration -> (kappa, mean tip height) of the box / cylinder plan

    def _worst(self, env, width: float) -> DimensionlessParams:
        """Per-finger groups for a workpiece ``width`` [m] wide, heaviest and least frictional of the ranges."""
        L = env.length
        p = PhysicalParams(length=L, EI=env.EI, rho=env.rho, g=env.g, m=env.mass_range[1] / env.K, b=width,
                           mu_s=env.friction_range[0], gamma=0.8 * L).dimensionless()
        return p.replace(b=min((width + 2.0 * env.r_tip) / L, 1.9))  # tip sphere centres r_tip off the faces

    def _plan_prismatic(self, env) -> tuple[float, float]:
        """``(kappa, tip height over l)``: the strongest worst-case choice over the widths (cached per config)."""
        key = (env.K, env.length, env.EI, env.rho, env.g, env.r_tip, tuple(env.size_range),
               tuple(env.mass_range), tuple(env.friction_range), self.safety, self.widths)
        if key not in self._prismatic:
            kappas, tips = [], []
            for w in np.linspace(env.size_range[0], env.size_range[1], self.widths):
                k, d = choose_kappa("I", self._worst(env, float(w)), safety=self.safety)
                kappas.append(k)
                tips.append(d["tip"][1] if d["tip"] is not None else -0.6)
            self._prismatic[key] = (min(kappas), float(np.mean(tips)))
        return self._prismatic[key]

    def _plan_obs(self, obs) -> tuple[float, float]:
        """``(kappa, palm height [m])`` from the first observation and the configuration."""
        env = self.env
        sl, L = env.obs_slices, env.length
        centre = float(obs[sl["palm_height"]][0]) * L + float(obs[sl["workpiece_position"]][2]) * L
        h = env.workpiece_height
        sphere = "sphere" in env.shapes and (env.shapes == ("sphere",) or abs(centre - 0.5 * h) > self.shape_tol)
        pair = env.K == 2
        if sphere:
            width = min(max(2.0 * centre, 0.5 * env.size_range[0]), 1.9 * L)
            beta = self.contact_angle if self.contact_angle is not None else (0.3 if pair else -0.35)
            kappa, self.details = choose_kappa_sphere(self._worst(env, width), beta, safety=self.safety)
            palm, top = centre - self.details["centre_height"] * L, 2.0 * centre
        else:
            kappa, tip_y = self._plan_prismatic(env)
            self.details = {"tip_height": tip_y}
            frac = self.contact_height if self.contact_height is not None else (0.75 if pair else 0.5)
            palm, top = frac * h - tip_y * L, h
        self.details["shape_guess"] = "sphere" if sphere else "box or cylinder"
        lo, hi = env.palm_range
        return kappa, min(max(palm, top + CLEARANCE, lo), hi)

    def reset(self, env, info=None):
        """Start an episode of ``env`` (just reset); the plan waits for the first observation.  Returns None."""
        self.env = env.unwrapped
        self.kappa = self.palm_grasp = None
        self.palm_target = self.t_grasp = None
        self.t = 0.0
        self.curl = 0.0  # extra curvature added on slip
        self.z_lift = None  # the workpiece's height relative to the palm when the lift began [m]
        self.t_slip = -math.inf
        self.slips = 0
        return None

    def __call__(self, obs):
        if self.kappa is None:
            self.kappa, self.palm_grasp = self._plan_obs(obs)
        env = self.env
        t = self.t
        action = super().__call__(obs)
        if self.t_grasp is None or t - self.t_grasp < self.ramp_time + self.settle_time:
            return action
        # lifting or holding: watch the workpiece relative to the palm and curl further when it slips
        sl, L = env.obs_slices, env.length
        z_rel = float(obs[sl["workpiece_position"]][2]) * L
        vz_rel = float(obs[sl["workpiece_velocity"]][2]) * L
        if self.z_lift is None:
            self.z_lift = z_rel
        lo = env.kappa_range[0]
        slipping = vz_rel < -self.slip_speed or self.z_lift - z_rel > self.slip_drop
        if slipping and t - self.t_slip >= self.slip_wait and self.kappa + self.curl > lo:
            self.curl = max(self.curl - self.slip_step, lo - self.kappa)
            self.t_slip = t
            self.slips += 1
            self.z_lift = z_rel
        ak = kappa_action(self.kappa + self.curl, env.kappa_range)
        action[:-1] = ak
        return action
