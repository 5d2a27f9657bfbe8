"""What the two-finger and the K-finger pick environments share around ``step``.

:class:`CheckedStep` splits ``step`` in two: ``step(action)`` checks the episode and the action
(:func:`simgrip.envs.arguments.check_action`: a list of floats clipped to ``[-1, 1]``; a float array of the
action's shape already inside ``[-1, 1]`` is read as its list here, what ``check_action`` returns for it) and
hands the list to
``_step_checked(a)``, which every layer of an environment (the fragile tasks' crush rule and reward, the place
task, the valve of :mod:`simgrip.envs.valve`, the env itself) overrides and chains with
``super()._step_checked(a)``, so the episode and the action are checked once per step however many layers
there are (issue 18: the env layer's Python time per control step), before any layer changes its state.  It
also holds the curvature properties both environments had.
"""

from __future__ import annotations

import numpy as np
from gymnasium.error import ResetNeeded

from simgrip.envs.arguments import check_action

__all__ = ["CheckedStep"]


class CheckedStep:
    """``step`` = check, then ``_step_checked`` (a mixin placed before ``gym.Env``; module docstring).

    ``_kcmd``, ``_kact``: the commanded and actual curvatures (sequences of floats) the environment keeps.
    """

    _needs_reset = True

    def step(self, action):
        if self._needs_reset:
            raise ResetNeeded("step() called before reset() or after the episode terminated; call reset()")
        # the usual action: a float array of the right shape, every entry in [-1, 1] (so finite), which
        # check_action returns as its list unchanged; anything else goes through check_action
        if type(action) is np.ndarray and action.shape == self._action_shape and action.dtype.kind == "f":
            a = action.tolist()
            for v in a:
                if not -1.0 <= v <= 1.0:  # (NaN too: every comparison with it is False)
                    break
            else:
                return self._step_checked(a)
        return self._step_checked(check_action(action, self._action_shape))

    def _step_checked(self, a: list):  # pragma: no cover - defined by each environment
        """One control step for the checked action ``a`` (list of floats in ``[-1, 1]``): ``step``'s result."""
        raise NotImplementedError

    @property
    def _kappa_cmd(self) -> np.ndarray:
        """Commanded curvatures (both fingers, or 1 shared / K; a copy)."""
        return np.array(self._kcmd)

    @property
    def _kappa(self) -> np.ndarray:
        """Actual curvatures after the lag (both fingers, or 1 shared / K; a copy)."""
        return np.array(self._kact)
