"""Each finger's largest normal force within a control step, summed by MuJoCo's contact sensors in C.

The fragile envs' crush rule reads each finger's normal force after the control step's ``frame_skip``
physics steps (``crush_at="end"``: every fragile id before :mod:`simgrip.envs.pick_fragile_v7`, whose registered
versions read the peak); within the step the force can be higher
(``docs/environments.md``, "Forces within a control step": the first touch's impact, and the held palm's jerk).
``crush_at="peak"`` reads the largest value within the step instead, at no Python cost per physics step:

* :func:`add_touch_sensors` adds, per finger, a MuJoCo contact sensor (``subtree1`` the finger's first link,
  ``geom2`` the workpiece, each contact's force in its contact frame, the normal first; no reduction, room for
  ``2 (n + 1)`` contacts: a capsule or sphere on a box face makes up to two) whose history keeps its last
  ``frame_skip`` samples (``nsample``): MuJoCo computes them in each physics step's forward pass, the pass whose
  constraint forces the env's own end-of-step reader reads, so the history is the step's physics steps' forces;
* :class:`TouchPeaks` reads those histories once per control step: per finger the largest, over the samples,
  of the summed normal forces [N].  Equal to a physics-step-by-physics-step replay's peaks
  (:func:`simgrip.envs.substep_forces.step_with_peaks`) to rounding: NumPy sums a finger's contacts pairwise, the
  env's reader one by one, 1-2 units in the last place apart where a finger has several (``tests/test_touch_history.py``).

The history's layout (MuJoCo 4): per sensor, two bookkeeping entries, ``nsample`` sample times, then
``nsample`` samples of the sensor's ``dim`` values, a ring buffer: the order of the samples does not matter to
a maximum.
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["TouchPeaks", "add_touch_sensors", "read_forces", "touch_contacts"]

#: the sensors' names, one per finger
SENSOR_NAME = "touch_f{}"


def read_forces(info: dict):
    """Each finger's normal force [N] as a fragile task's crush rule read it in the step whose ``info`` this is:
    ``info["peak_normal_force"]`` where the rule reads the peak within the step (``crush_at="peak"``), else
    ``info["normal_force"]`` (the step's end).  What the training wrappers that judge a grip against the hidden limit
    read (:mod:`simgrip.envs.crush_margin`, :mod:`simgrip.envs.privileged_critic`)."""
    return info.get("peak_normal_force", info["normal_force"])


def touch_contacts(n_links: int) -> int:
    """The contacts each finger's sensor has room for: two per link and tip (a capsule or a sphere on a box's face
    makes up to two)."""
    return 2 * (int(n_links) + 1)


def add_touch_sensors(spec, *, fingers: int, n_links: int, frame_skip: int, workpiece: str,
                      prefix: str = "hand_") -> None:
    """Add each finger's contact sensor on ``workpiece`` (a geom's name) to ``spec``, with a history of
    ``frame_skip`` samples (module docstring)."""
    for f in range(int(fingers)):
        s = spec.add_sensor(name=SENSOR_NAME.format(f), type=mujoco.mjtSensor.mjSENS_CONTACT)
        s.objtype = mujoco.mjtObj.mjOBJ_XBODY  # the subtree of the finger's first link: every link and its tip
        s.objname = f"{prefix}f{f}_link0"
        s.reftype = mujoco.mjtObj.mjOBJ_GEOM
        s.refname = workpiece
        s.intprm = [1 << int(mujoco.mjtConDataField.mjCONDATA_FORCE), 0, touch_contacts(n_links)]
        s.nsample = int(frame_skip)


class TouchPeaks:
    """Reads each finger's largest summed normal force [N] over the last control step from a model with
    :func:`add_touch_sensors`' sensors (``fingers`` of them, ``frame_skip`` samples each)."""

    def __init__(self, model, *, fingers: int, frame_skip: int):
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, SENSOR_NAME.format(f)) for f in range(fingers)]
        if min(ids) < 0:
            raise ValueError("model: it has no touch sensors (add_touch_sensors before compiling)")
        fs = int(frame_skip)
        if any(int(model.sensor_history[i][0]) != fs for i in ids):
            raise ValueError(f"frame_skip: the touch sensors keep {model.sensor_history[ids[0]][0]} samples, not {fs}")
        self._fs, self._ids = fs, ids
        adr = [int(model.sensor_historyadr[i]) + 2 + fs for i in ids]  # each sensor's first value
        dims = {int(model.sensor_dim[i]) for i in ids}
        steps = {b - a for a, b in zip(adr, adr[1:])}
        if len(dims) != 1 or len(steps) > 1:
            raise ValueError("model: the touch sensors' histories are not evenly laid out")
        self._first, self._dim = adr[0], dims.pop()
        self._gap = steps.pop() if steps else 0
        self._views = (None, None)  # (data, the normal components' view of its history): _bind
        self._sums = np.empty((len(ids), fs))  # each finger's summed normal force at each physics step [N]
        self._peaks = np.empty(len(ids))

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_views"] = (None, None)  # a view of one MjData: bound again on the next read
        return state

    def _bind(self, data):
        """A strided view ``(fingers, frame_skip, contacts)`` of the normal components in ``data.history``."""
        h = data.history
        item = h.itemsize
        view = np.lib.stride_tricks.as_strided(
            h[self._first:], shape=(len(self._ids), self._fs, self._dim // 3),
            strides=(self._gap * item, self._dim * item, 3 * item), writeable=False)
        self._views = (data, view)
        return view

    def read(self, data) -> list:
        """Each finger's largest summed normal force over the last ``frame_skip`` physics steps [N]."""
        d, view = self._views
        if d is not data:
            view = self._bind(data)
        return np.maximum.reduce(np.add.reduce(view, axis=2, out=self._sums), axis=1, out=self._peaks).tolist()
