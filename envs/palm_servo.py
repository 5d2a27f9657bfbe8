"""The palm's slide servos and the commands a palm action gives them: held over the control step, or ramped.

A palm action ``a`` in ``[-1, 1]`` moves the slide's target by ``a * speed * dt`` [m] per control step of ``dt``
[s], clamped to the slide's range.  How the servo sees the new target within the step:

* **held** (``ramp=False``: ``Pick-v1``, ``PickCradle-v1``, ``PickMulti-v0`` and the fragile ids before
  :mod:`simgrip.envs.pick_fragile_v7`): a position servo whose ``ctrl`` is the target; the
  target jumps at the start of the control step and is held over its ``frame_skip`` physics steps (a
  zero-order hold).  Each jump is a jerk: lifting at full speed (0.1 m/s, 2 mm a step at 50 Hz) yanks
  the palm every control step, and a finger's normal force on a held workpiece peaks within the step
  1.4-1.8 times above its value at the step's end, where the crush rule and the tactile sensor read it
  (``docs/environments.md``, "Forces within a control step");
* **ramped** (``ramp=True``): MuJoCo's ``intvelocity`` actuator, whose activation integrates ``ctrl`` (a
  velocity [m/s]) over the physics steps and is the position servo's target, clamped to the range by its
  ``actrange``; the command is the velocity that brings the target from where it was to the new clamped
  target by the step's end: the same targets at the control steps, reached along a line, as a palm driven
  at a steady speed moves.

:func:`add_palm_servo` adds either kind to a model spec (same gains, critically damped for the moving mass);
:class:`PalmCommand` turns actions into ``ctrl`` for one slide.
"""

from __future__ import annotations

import math

import mujoco

__all__ = ["PALM_KP", "PalmCommand", "add_palm_servo", "palm_command"]

#: the palm servos' stiffness [N/m]
PALM_KP = 4000.0


def add_palm_servo(spec, name: str, joint: str, moving_mass: float, *, ramp: bool = False, lo: float = -math.inf,
                   hi: float = math.inf):
    """Add the servo ``name`` on the slide ``joint`` to ``spec`` (critically damped for ``moving_mass`` [kg]):
    a position servo (``ctrl``: target [m]) or, ``ramp``, an ``intvelocity`` one (``ctrl``: the target's
    velocity [m/s], its activation the target, kept in ``[lo, hi]`` [m]); returns it."""
    servo = spec.add_actuator(name=name, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    kv = 2.0 * math.sqrt(PALM_KP * moving_mass)
    if ramp:
        servo.set_to_intvelocity(kp=PALM_KP, kv=kv)
        servo.actlimited = mujoco.mjtLimited.mjLIMITED_TRUE
        servo.actrange = [lo, hi]
        servo.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    else:
        servo.set_to_position(kp=PALM_KP, kv=kv)
    return servo


class PalmCommand:
    """One palm slide's commands: ``target`` [m], moved by ``reset`` and ``command`` (module docstring).

    ``index``: the servo's actuator (its ``ctrl`` entry); ``act``: its activation's index (``ramp`` only);
    ``lo``, ``hi``: the slide's range [m]; ``speed``: the target's speed at ``a = 1`` [m/s]; ``dt``: the control
    step [s].
    """

    __slots__ = ("target", "ramp", "_i", "_act", "_lo", "_hi", "_speed", "_dt", "_inv_dt")

    def __init__(self, index: int, *, lo: float, hi: float, speed: float, dt: float, ramp: bool = False,
                 act: int = -1):
        if ramp and act < 0:
            raise ValueError("act: a ramped servo needs its activation's index")
        self._i, self._act, self.ramp = int(index), int(act), bool(ramp)
        self._lo, self._hi, self._speed, self._dt = float(lo), float(hi), float(speed), float(dt)
        self._inv_dt = 1.0 / self._dt
        self.target = 0.0

    def reset(self, data, z: float) -> None:
        """Hold the slide at ``z`` [m] from now (the episode's start): the target, and the servo's ``ctrl``
        (held) or activation with a zero velocity (ramped)."""
        self.target = z = float(z)
        if self.ramp:
            data.act[self._act] = z
            data.ctrl[self._i] = 0.0
        else:
            data.ctrl[self._i] = z

    def command(self, ctrl, a: float) -> float:
        """Write the command of palm action ``a`` into ``ctrl`` (``data.ctrl``); the new target [m]."""
        prev = self.target
        z = prev + a * self._speed * self._dt  # (this order: the envs' arithmetic before the ramp, bit for bit)
        lo, hi = self._lo, self._hi
        self.target = z = lo if lo > z else (hi if hi < z else z)  # min(max(z, lo), hi), written out
        ctrl[self._i] = (z - prev) * self._inv_dt if self.ramp else z
        return z


def palm_command(env, model, index: int = 0, lo: float | None = None, hi: float | None = None) -> PalmCommand:
    """The :class:`PalmCommand` of an environment's palm servo ``index`` in ``model`` (0: the vertical slide, over
    ``env.palm_range``; else ``[lo, hi]`` [m]), at ``env.palm_speed`` [m/s] per control step ``env.dt`` [s], held
    or ramped as ``env.palm_ramp`` says."""
    lo = env.palm_range[0] if lo is None else lo
    hi = env.palm_range[1] if hi is None else hi
    return PalmCommand(index, lo=lo, hi=hi, speed=env.palm_speed, dt=env.dt, ramp=env.palm_ramp,
                       act=int(model.actuator_actadr[index]))
