"""A scripted pick controller that chooses the curvature from the elastica reference.

For the episode's box (width ``b``, half mass ``m`` per finger, friction
``mu_s``) the controller solves the paper's Grip I boundary-value problem along
a sweep of uniform curvatures (:func:`simgrip.reference.elastica.kappa_sweep`) and takes
the gentlest curvature whose required friction ``|F_f|/N`` is at most
``mu_s / safety``: inside the feasible window, with a safety factor on the
friction and no more squeeze than that.  The pick itself is open loop in three
phases: ramp the curvature command to that value, wait for the grip to settle,
lift the palm by the target height plus an allowance for the fingers' sag, and
hold.

Grip III (``PickCradle-v0``, the box on a pedestal): the curvature is the
gentlest whose elastica cradle (contact at ``gamma = 0.8 l``) holds with the
safety factor, and the palm height puts the box's lower edge where that
solution has its contact.  Recipe: open the fingers into a claw
(``kappa_open``), lower the palm around the box, curl the fingers under its
lower edges, lift and hold.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.reference.elastica import ElasticaError, solve
from simgrip.profiles import Uniform
from simgrip.params import DimensionlessParams, PhysicalParams

__all__ = ["ObservationPickPolicy", "ScriptedPickPolicy", "choose_kappa", "kappa_action"]


def kappa_action(kappa: float, kappa_range) -> float:
    """The curvature command's action (in ``[-1, 1]``, clipped) that commands ``kappa_bar = kappa`` within
    the env's ``kappa_range = (low, high)`` (the inverse of the envs' ``low + (a + 1)/2 (high - low)``)."""
    lo, hi = kappa_range
    return float(np.clip(2.0 * (kappa - lo) / (hi - lo) - 1.0, -1.0, 1.0))


def choose_kappa(grip: str, params: DimensionlessParams, *, safety: float = 2.0,
                 kappas=None, fallback: float | None = None) -> tuple[float, dict]:
    """Gentlest uniform ``kappa_bar`` whose elastica grip holds with ``required_mu <= mu_s / safety``.

    Returns ``(kappa, details)``; ``details`` has the solution's ``normal_force``,
    ``required_mu`` and ``tip`` (dimensionless), and ``window`` (the feasible
    curvatures met before stopping).  The sweep runs from gentle to strong
    curvature, each solve warm-started from the previous one, and stops at the
    first curvature that qualifies or at a jump to another solution branch.  When no curvature of the sweep qualifies,
    the one with the smallest required friction is returned (or ``fallback``).
    """
    if kappas is None:
        kappas = np.arange(-2.5, -7.01, -0.25) if grip == "I" else np.arange(-2.5, -6.01, -0.25)
    sols = []
    best = None
    prev = None
    for k in kappas:
        try:
            s = solve(grip, params, Uniform(float(k)), guess=prev, tol=1e-6)
        except ElasticaError:
            break
        # stop at a jump to another branch of solutions (the tip height leaps)
        if prev is not None and abs(s.tip[1] - prev.tip[1]) > 0.15:
            break
        sols.append((float(k), s))
        prev = s
        if s.feasible and s.required_mu <= params.mu_s / safety:
            best = (float(k), s)
            break
    window = [k for k, s in sols if s.feasible]
    if best is None:
        cands = [(s.required_mu, k, s) for k, s in sols if s.feasibility.get("contact", False)]
        if fallback is not None or not cands:
            k = float(fallback if fallback is not None else kappas[len(kappas) // 2])
            return k, {"normal_force": math.nan, "required_mu": math.nan, "tip": None, "contact": None,
                       "window": window}
        _, k, s = min(cands)
        best = (k, s)
    k, s = best
    return k, {"normal_force": float(s.normal_force), "required_mu": float(s.required_mu),
               "tip": np.array(s.tip), "contact": np.array(s.contact), "window": window}


class ScriptedPickPolicy:
    """Oracle open-loop pick: ramp ``kappa`` to the elastica choice, settle, lift, hold.

    The oracle reads the episode's true box (width, mass, friction: ``env.box``) to
    choose its curvature from the elastica; :class:`ObservationPickPolicy` is the
    honest variant that sees only what a learned policy sees.  Use as
    ``policy.reset(env, info)`` after ``env.reset`` and ``action = policy(obs)``
    each step.  Works with ``per_finger`` either way.

    Parameters
    ----------
    safety : float
        Friction safety factor: the chosen grip needs at most ``mu_s / safety``.
    ramp_time, settle_time : float
        Seconds to ramp the curvature command, then to wait before lifting.
    lift_speed : float
        Palm speed while lifting, as a fraction of the env's ``palm_speed``.
    extra_lift : float
        Palm travel beyond ``target_height`` [m] (the soft fingers sag under the box).
    kappa_open, open_time : float
        Grip III: the claw's curvature and the seconds to open it before descending.
    """

    def __init__(self, safety: float = 2.0, ramp_time: float = 0.6, settle_time: float = 0.3,
                 lift_speed: float = 0.5, extra_lift: float = 0.02, kappa_open: float = -1.6,
                 open_time: float = 0.4):
        self.safety = float(safety)
        self.ramp_time = float(ramp_time)
        self.settle_time = float(settle_time)
        self.lift_speed = float(lift_speed)
        self.extra_lift = float(extra_lift)
        self.kappa_open = float(kappa_open)
        self.open_time = float(open_time)
        self.kappa = None
        self.depth = None
        self.details = {}

    def _plan(self, env) -> tuple[float, float | None]:
        """``(kappa, depth)``: the curvature to grip with and, for Grip III, how deep under the palm
        (in finger lengths) the box's lower edge is carried; from the true box (oracle)."""
        p = env.dimensionless()
        # the contact sits on the tip sphere: its centre is r_tip outside the box face
        b_eff = (env.box.width + 2.0 * env.r_tip) / env.length
        if env.grip == "I":
            kappa, self.details = choose_kappa("I", p.replace(b=min(b_eff, 1.9)), safety=self.safety)
            return kappa, None
        # cradle: the box's lower edge rests on the link capsules, r_tip outside the centreline
        kappa, self.details = choose_kappa("III", p.replace(b=min(b_eff, 1.9)), safety=self.safety)
        depth = 0.58 if self.details["contact"] is None else -float(self.details["contact"][1])
        return kappa, depth

    def reset(self, env, info=None):
        """Plan the episode of ``env`` (just reset); returns the chosen curvature."""
        env = env.unwrapped
        self.env = env
        self.kappa, self.depth = self._plan(env)
        self.grasp_height = None
        self.t = 0.0
        self.palm_target = None  # the palm's target height [m], integrated from our own commands
        self.palm0 = None
        self.palm_lift0 = None
        self.t_from, self.k_from = 0.0, 0.0  # Grip I: the curvature ramp starts here
        return self.kappa

    def _first(self, obs):
        """Read the palm's start height and (Grip III) the grasp height off the first observation."""
        env = self.env
        sl, L = env.obs_slices, env.length
        self.palm_target = self.palm0 = float(obs[sl["palm_height"]][0]) * L
        if self.depth is not None:
            # box centre relative to the palm -> its lower edge above the table
            bottom = self.palm0 + float(obs[sl["box_position"]][-1]) * L - 0.5 * env.box_height  # (x,) z
            self.grasp_height = bottom + self.depth * L + env.r_tip

    def _probe(self, t, obs):
        """Grip I hook: a curvature command while still probing, or None once the plan is made."""
        return None

    def __call__(self, obs):
        env = self.env
        if self.palm_target is None:
            self._first(obs)
        t = self.t
        self.t += env.dt
        vz = 0.0
        if self.grasp_height is None:  # Grip I: ramp, settle, lift
            k = self._probe(t, obs)
            if k is not None:
                t_lift = math.inf
            else:
                t_lift = self.t_from + self.ramp_time + self.settle_time
                w = min(1.0, (t - self.t_from) / self.ramp_time) if self.ramp_time > 0 else 1.0
                k = self.k_from + w * (self.kappa - self.k_from)
        else:  # Grip III: open the claw, descend around the box, curl under it, lift
            t_down = self.open_time + max(0.0, self.palm0 - self.grasp_height) / (env.palm_speed * self.lift_speed * 2)
            if t < self.open_time:
                k = self.kappa_open * t / self.open_time
            elif t < t_down:
                k = self.kappa_open
            else:
                w = min(1.0, (t - t_down) / self.ramp_time) if self.ramp_time > 0 else 1.0
                k = self.kappa_open + w * (self.kappa - self.kappa_open)
            if self.open_time <= t and self.palm_target > self.grasp_height:
                vz = -min(1.0, (self.palm_target - self.grasp_height) / (env.palm_speed * env.dt))
            t_lift = t_down + self.ramp_time + self.settle_time
            if t >= t_lift and self.palm_lift0 is None:
                self.palm_lift0 = self.palm_target
        if t >= t_lift:
            base = self.palm0 if self.grasp_height is None else self.palm_lift0
            goal = base + env.target_height + self.extra_lift
            remaining = goal - self.palm_target
            vz = min(self.lift_speed, remaining / (env.palm_speed * env.dt)) if remaining > 0 else 0.0
        lo, hi = env.palm_range
        self.palm_target = min(max(self.palm_target + vz * env.palm_speed * env.dt, lo), hi)
        ak = kappa_action(k, env.kappa_range)
        a = [ak, ak, vz] if env.per_finger else [ak, vz]
        return np.array(a, dtype=np.float32)


class ObservationPickPolicy(ScriptedPickPolicy):
    """Honest scripted pick: sees only the observation and the env's configuration.

    Unlike the oracle :class:`ScriptedPickPolicy` it does not know the episode's
    box.  Grip I: it curls the fingers slowly (``probe_rate`` per second) until
    the observation shows both fingers touching the box, reads the box width
    off the observed fingertip positions, and takes the elastica's gentlest
    holding curvature for that width and the randomisation's heaviest box and
    lowest friction (``box_mass_range``, ``friction_range``: the env's
    configuration, what a learner's training distribution also holds), with
    ``safety`` on the friction; then it ramps there, lifts and holds like the
    oracle.  Grip III: one curvature ``kappa`` and carrying depth ``depth`` for
    the whole range.  The configuration it reads (finger length and stiffness,
    control step, palm speed and range, curvature range, target height, box
    height, tip radius, observation layout) is set by whoever makes the env,
    not hidden state.
    """

    def __init__(self, kappa: float = -4.5, depth: float = 0.58, probe_rate: float = 5.0, safety: float = 1.0,
                 **kwargs):
        super().__init__(safety=safety, **kwargs)
        self.kappa_fixed = float(kappa)
        self.depth_fixed = float(depth)
        self.probe_rate = float(probe_rate)

    def _plan(self, env):
        self.details = {}
        self.probing = env.grip == "I"
        if env.grip == "I":
            return math.nan, None  # chosen once the fingers touch the box
        return self.kappa_fixed, self.depth_fixed

    def _probe(self, t, obs):
        if not self.probing:
            return None
        env = self.env
        sl, L = env.obs_slices, env.length
        lo, hi = env.kappa_range
        k_now = lo + 0.5 * (float(obs[sl["kappa_command"]][0]) + 1.0) * (hi - lo)
        normals = obs[sl["contact_force"]][0::2]  # per finger: normal, friction (finger 1 only if per_finger)
        if t > 0 and np.all(normals > 0) or k_now <= lo:
            tip_x = np.abs(obs[sl["tip_position"]][0::2])
            width = 2.0 * float(np.mean(tip_x)) * L - 2.0 * env.r_tip
            width = min(max(width, 0.2 * L), 1.9 * L)
            p = PhysicalParams(length=L, EI=env.EI, rho=env.rho, g=env.g, m=0.5 * env.box_mass_range[1],
                               b=width, mu_s=env.friction_range[0], gamma=0.8 * L).dimensionless()
            b_eff = (width + 2.0 * env.r_tip) / L
            self.kappa, self.details = choose_kappa("I", p.replace(b=min(b_eff, 1.9)), safety=self.safety)
            self.details["width"] = width
            self.kappa = min(self.kappa, k_now)  # never open again
            self.probing = False
            self.t_from, self.k_from = t, k_now
            return None
        return max(k_now - self.probe_rate * env.dt, lo) if t > 0 else 0.0
