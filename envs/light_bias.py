r"""Training episodes weighted towards the lightest workpieces (issue 18, the K fingers).

``LightBias(env, probability, share)`` wraps a fragile task (every ``simgrip/*Fragile-*`` id: their mass is
drawn log-uniform over ``mass_range``).  On each ``reset``, with probability ``probability``, it draws the
episode's mass itself, log-uniform over the lightest ``share`` of that range in log mass,

    m  in  [m_lo, m_lo (m_hi / m_lo)^share],

and hands it to the env as the reset's mass option; everything else of the episode (size, friction, crush
ratio, pre-grasp gap, placement) is the env's own draw from the same seed, and the hidden crush limit follows
from the drawn mass as always (``hold_force x crush ratio``).  The other resets are the env's own.  A training
aid only: evaluation runs the registered task (:func:`simgrip.envs.env_options.make_env` builds evaluation envs
without it), whose draw it leaves unchanged.  ``reset``'s info gains ``light_bias`` (True when the wrapper drew
the mass).

Why (measured on ``PickMultiFragile-v6``; the Gymnasium environments page, "Which workpieces the K fingers lose"
and "Light pieces more often in training"): PPO's K-finger policies plateau at 46-72 % held-out success (one seed
of six at 88 %), and what they lose is the lightest third of the pieces (5-18 g: 5 of 21 held by each of two
policies measured, against 20 of 21 for the careful scripted controller), crushed within 3-20 steps of the
pre-grasp by a closing too fast for a piece that holds at 15-120 mN, while the heavier ones are finished ~30 steps
sooner than the controller does. Under the task's draw a third of the pieces are that light, and a policy careless
with them is worth nearly as much in the learner's discounted return as the controller: little gradient towards
care. Drawn at ``probability = 0.5`` (two thirds of the training pieces light), PPO with SB3 defaults behind the
probe offset reached 72 / 90 / 80 % at 15 CPU-minutes (seeds 0-2) and 80 / 82 / 84 % (seeds 3-5), against 66 / 68 /
88 % and 72 / 64 / 46 % without it; every policy is worth more than the controller in its own discounted return.

The draws use the wrapper's own generator, seeded from ``reset``'s ``seed`` (the same seeds give the same
episodes); the env's generator draws exactly what it draws unwrapped (its own mass draw is made and replaced).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

__all__ = ["LightBias", "LIGHT_SHARE", "episode_mass", "mass_bins"]

#: default ``share``: the lightest third of the log mass range (5-18 g of the pinch's and K fingers' 5-250 g)
LIGHT_SHARE = 1.0 / 3.0


def episode_mass(env) -> float | None:
    """The workpiece mass [kg] of ``env``'s current episode (a fragile task's hidden draw), ``None`` when ``env``
    is not a fragile task."""
    u = env.unwrapped
    if not hasattr(u, "_mass_range"):
        return None
    return float(u._episode()[0])


def mass_bins(env, bins: int = 3) -> list[float] | None:
    """The edges [kg] of ``bins`` equal parts of ``env``'s log mass range (``bins + 1`` increasing masses: the
    first part is :class:`LightBias`'s light end at ``share = 1 / bins``), ``None`` when ``env`` is not a
    fragile task."""
    u = env.unwrapped
    if not hasattr(u, "_mass_range"):
        return None
    lo, hi = (float(m) for m in u._mass_range)
    return [lo * (hi / lo) ** (i / bins) for i in range(bins)] + [hi]


class LightBias(gym.Wrapper):
    """Draw a share of the training episodes' workpieces from the light end of the mass range
    (see :mod:`simgrip.envs.light_bias`).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task as ``gym.make`` builds it (its mass drawn log-uniform, taken as a reset option).
    probability : float
        The share of resets whose mass the wrapper draws, in [0, 1].
    share : float
        The light end's width as a share of the log mass range, in (0, 1].

    Raises ValueError naming ``probability`` or ``share`` when out of range, ``env`` when it is not a fragile
    task.
    """

    def __init__(self, env: gym.Env, probability: float = 0.5, share: float = LIGHT_SHARE):
        for name, value, low_open in (("probability", probability, False), ("share", share, True)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or not (0.0 < value <= 1.0 if low_open else 0.0 <= value <= 1.0):
                raise ValueError(f"{name} must be a number in {'(0, 1]' if low_open else '[0, 1]'}, got {value!r}")
        u = env.unwrapped
        if not (hasattr(u, "_mass_range") and hasattr(u, "_MASS_KEY")):
            raise ValueError(f"env: {type(u).__name__} is not a fragile task (no log-uniform mass draw to bias)")
        super().__init__(env)
        self.probability, self.share = float(probability), float(share)
        lo, hi = (float(m) for m in u._mass_range)
        self.light_range = (lo, lo * (hi / lo) ** self.share)
        self._rng = np.random.default_rng(0)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self._rng = np.random.default_rng([int(seed), 0x11B])
        light = bool(self._rng.random() < self.probability)
        if light:
            lo, hi = self.light_range
            mass = float(math.exp(self._rng.uniform(math.log(lo), math.log(hi))))
            options = {**(options or {}), self.env.unwrapped._MASS_KEY: mass}
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, {**info, "light_bias": light}
