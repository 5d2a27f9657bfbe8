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
lift by ``target_height`` plus an allowance, hold.
"""

from __future__ import annotations

import numpy as np

from simgrip.envs.pick_multi_model import half_height, workpiece_size
from simgrip.envs.scripted import choose_kappa, kappa_action
from simgrip.params import DimensionlessParams
from simgrip.profiles import Uniform
from simgrip.reference.elastica import ElasticaError
from simgrip.reference.inclined import solve_inclined

__all__ = ["ScriptedMultiPolicy", "choose_kappa_sphere"]

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
