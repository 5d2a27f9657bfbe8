r"""The least a Gymnasium step of a pick environment's interface does in Python, to time against bare ``mj_step``.

Issue 18, item 5 asks for an environment whose overhead over bare ``mj_step`` is at most 10 %.  Part of any
Python environment's step is not the task's work but the interface itself: the rest angles and the controls
written into MuJoCo's arrays, the ``frame_skip`` physics steps called, the state read back, an observation array
made and an ``info`` dictionary of the environment's keys returned.  :func:`floor_step` builds that step, and
nothing else, for one environment: :func:`simgrip.envs.throughput.measure_throughput` replays the environment's
own control steps through it (``floor_overhead_percent``), so what is left between that floor and the target is
what the task's own Python (curvature lag, contact forces, crush and drop rules, validity screen, observation
and reward) may cost.

The floor's step writes the rest angles' block (``model.qpos_spring``; one NumPy copy, as the environment's one
multiply into it) and all of ``data.ctrl``, calls ``mujoco.mj_step(model, data, frame_skip)``, reads ``qpos``
and ``qvel`` as lists (the environment's one ``tolist`` each), makes the observation (``np.array`` of as many
floats as the environment observes) and a dictionary literal with the environment's ``info`` keys, an array of
the same length where the environment's value is an array, a float or a bool otherwise.  Its values are
meaningless; it is written out as one compiled function (no loops, no comprehensions) so that it is the floor,
not an estimate above it.
"""

from __future__ import annotations

import numbers

import mujoco
import numpy as np

__all__ = ["floor_step"]


def floor_step(model, data, *, frame_skip: int, obs_size: int, info: dict, spring_index):
    """``step(spring, ctrl) -> (obs, reward, terminated, truncated, info)``: the interface's least Python step.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The environment's model and data (the step writes and steps these).
    frame_skip : int
        Physics steps per control step.
    obs_size : int
        Length of the environment's observation.
    info : dict
        One ``info`` of the environment's ``step``: its keys, and for each whether its value is an array (and its
        length) or a bool; the step returns a dictionary of the same keys.
    spring_index : slice or array of int
        Where the fingers' rest angles live in ``model.qpos_spring``.

    Returns
    -------
    callable
        ``step(spring, ctrl)``: writes ``spring`` (rest angles [rad]) and ``ctrl`` (all of ``data.ctrl``), steps
        ``frame_skip`` times and returns the tuple ``env.step`` returns, its values meaningless.
    """
    fs, n_obs = int(frame_skip), int(obs_size)
    if fs < 1 or n_obs < 1:
        raise ValueError(f"frame_skip and obs_size must be positive integers, got {frame_skip!r}, {obs_size!r}")
    state = model.nq + model.nv
    reps = -(-n_obs // state)  # the state read back, repeated until it is as long as the observation
    whole = "s" if n_obs == state else (f"s[:{n_obs}]" if reps == 1 else f"(s * {reps})[:{n_obs}]")
    items = []
    for i, (key, value) in enumerate(info.items()):
        if not isinstance(key, str):
            raise ValueError(f"info keys must be strings, got {key!r}")
        j = i % state
        if isinstance(value, np.ndarray):  # a slice of the value's length (the state is longer than any)
            j = i % max(state - value.size + 1, 1)
            items.append(f"{key!r}: array(s[{j}:{j + value.size}])")
        elif isinstance(value, (bool, np.bool_)):
            items.append(f"{key!r}: s[{j}] > 0.0")
        elif isinstance(value, numbers.Real):
            items.append(f"{key!r}: s[{j}]")
        else:  # a message list or the like: the environment makes it only where it has something to say
            items.append(f"{key!r}: None")
    source = (
        "def step(spring, ctrl):\n"
        "    springs[index] = spring\n"
        "    controls[:] = ctrl\n"
        "    mj_step(model, data, fs)\n"
        "    s = qpos.tolist() + qvel.tolist()\n"
        f"    obs = array({whole})\n"
        f"    return obs, 0.0, False, False, {{{', '.join(items)}}}\n"
    )
    scope = {"springs": model.qpos_spring, "index": spring_index, "controls": data.ctrl, "mj_step": mujoco.mj_step,
             "model": model, "data": data, "fs": fs, "qpos": data.qpos, "qvel": data.qvel, "array": np.array}
    exec(compile(source, "<step_floor>", "exec"), scope)  # noqa: S102 - our own source
    return scope["step"]
