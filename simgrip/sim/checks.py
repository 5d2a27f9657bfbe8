"""One way to turn MuJoCo's warnings and non-finite states into errors.

MuJoCo does not raise when a simulation goes wrong: it counts warnings in
``data.warning`` (bad accelerations, contact buffer full, NaN in qpos, ...) and
carries on, often after resetting the state.  Everything in simgrip that steps
or evaluates a model checks through :func:`check_invalid_state` (modelled on
dm_control's ``Physics.check_invalid_state``), so a diverged state is never
reported as a result.
"""

from __future__ import annotations

import contextlib
import math
from typing import Iterator

import mujoco
import numpy as np

__all__ = ["PhysicsError", "StateCheck", "active_warnings", "check_invalid_state", "clear_warnings", "invalid_state",
           "stderr_printer", "warnings_to", "warnings_to_stderr"]


class PhysicsError(RuntimeError):
    """MuJoCo warned (instability, buffer overflow, NaN) or the state is not finite."""


def active_warnings(data: mujoco.MjData) -> list[str]:
    """Names of the MuJoCo warnings counted in ``data`` (e.g. ``['mjWARN_BADQACC']``)."""
    return [mujoco.mjtWarning(int(i)).name for i in np.flatnonzero(data.warning.number)]


def clear_warnings(data: mujoco.MjData) -> None:
    """Reset MuJoCo's warning counters of ``data`` (before a new check window)."""
    data.warning.number[:] = 0  # a view of the counters (one call: cheap enough for every env step)


def invalid_state(data: mujoco.MjData) -> str | None:
    """Why ``data`` is not a valid state (warnings or non-finite qpos/qvel), or ``None`` when it is."""
    if data.warning.number.any():
        return f"MuJoCo warnings {', '.join(active_warnings(data))}"
    # a sum is finite only if every entry is (cheap enough for every env step; an overflow counts too)
    if not math.isfinite(float(data.qpos.sum()) + float(data.qvel.sum())):
        return "non-finite qpos or qvel"
    return None


class StateCheck:
    """:func:`clear_warnings` and :func:`invalid_state` of one ``data`` for a hot loop (an env step).

    Binds numpy views of the warning counters, ``qpos`` and ``qvel`` once; the tests are those of
    :func:`invalid_state`.  Views do not survive pickling: make a new ``StateCheck`` for a copied ``data``.
    """

    def __init__(self, data: mujoco.MjData):
        self._data = data
        self._number = data.warning.number
        self._qpos, self._qvel = data.qpos, data.qvel

    def clear(self) -> None:
        """Reset the warning counters."""
        self._number.fill(0)

    def __call__(self, qpos: list | None = None, qvel: list | None = None) -> str | None:
        """Why the state is not valid, or ``None`` when it is (see :func:`invalid_state`).

        ``qpos``, ``qvel``: optionally the state already read as lists (``data.qpos.tolist()``), summed in
        Python instead of read again.
        """
        # count_nonzero and dot are the cheapest numpy reductions; a huge finite state that overflows the dot
        # (or sum) is passed on to invalid_state, which decides
        if qpos is None:
            q, v = self._qpos, self._qvel
            finite = math.isfinite(q.dot(q) + v.dot(v))
        else:
            finite = math.isfinite(sum(qpos) + sum(qvel))
        if any(self._number.tolist()) or not finite:  # (a list of 8 counts: cheaper than a numpy reduction)
            return invalid_state(self._data)
        return None


@contextlib.contextmanager
def check_invalid_state(data: mujoco.MjData, what: str = "simulation", error: type[Exception] = PhysicsError) -> Iterator[None]:
    """Raise ``error`` if MuJoCo warns or the state turns non-finite inside the block.

    The warning counters are cleared on entry, so only what happens inside the
    block counts.  ``what`` names the operation in the message
    (``"settle diverged (MuJoCo warnings mjWARN_BADQACC)"``).
    """
    clear_warnings(data)
    yield
    why = invalid_state(data)
    if why is not None:
        raise error(f"{what} diverged ({why})")


@contextlib.contextmanager
def warnings_to(handler) -> Iterator[None]:
    """MuJoCo's warning printer replaced by ``handler(message)`` for a block, the previous one restored after.

    Without a handler MuJoCo appends each warning to ``MUJOCO_LOG.TXT`` in the working folder (and prints it):
    a file the user did not ask for, written by every process that steps a model (a Dask worker's included).
    The warnings are still counted in ``data.warning`` whatever the handler does.
    """
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(handler)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)


def stderr_printer(prefix: str):
    """A warning handler for MuJoCo (:func:`warnings_to`, ``mujoco.set_mju_user_warning``) that prints
    ``"<prefix>: MuJoCo: <message>"`` as one line on stderr."""
    import sys

    def print_warning(msg: str) -> None:
        print(f"{prefix}: MuJoCo: {msg}", file=sys.stderr, flush=True)

    return print_warning


def warnings_to_stderr(prefix: str):
    """:func:`warnings_to` :func:`stderr_printer`'s one line on stderr."""
    return warnings_to(stderr_printer(prefix))
