"""Checks of the environments' arguments: each bad value raises ``ValueError`` naming the argument.

The scalar checks (:func:`check_number`, :func:`check_range`, ...) serve every
argument; :func:`set_finger_arguments`, :func:`set_task_arguments` and
:func:`check_camera` check the arguments that ``simgrip/Pick-v1``
(:class:`~simgrip.envs.pick.PickEnv`) and ``simgrip/PickMulti-v0``
(:class:`~simgrip.envs.pick_multi.PickMultiEnv`) share (same names, same
checks, same messages) and set them on the environment.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from simgrip.chain import check_links
from simgrip.params import MAX_LINKS

__all__ = ["check_action", "check_bool", "check_camera", "check_int", "check_number", "check_positive", "check_range",
           "check_charge", "check_size", "check_within",
           "check_reset", "set_finger_arguments", "set_task_arguments"]


#: the largest rendered image side [pixels]: 8192, within every GL driver's framebuffer limit (OSMesa: 16384)
MAX_PIXELS = 8192
#: the longest control step ``timestep * frame_skip`` [s]: a pick lasts a few seconds (300 steps of 20 ms)
MAX_CONTROL_STEP = 1.0
#: the tip and link radius ``r_tip`` over the finger length, least and most: 1e-4 (0.01 mm on the default 10 cm
#: finger; at 1e-8 MuJoCo refuses the links' inertia) to 0.5 (a tip as wide as the finger is long)
MIN_TIP_RADIUS, MAX_TIP_RADIUS = 1e-4, 0.5
#: a workpiece's height or depth at most this many finger lengths (:func:`check_size`)
MAX_WORKPIECE_SIZE = 10.0
#: the longest settle at reset [s]: the default fingers settle within 2 % in 0.18 s (simgrip.envs.pick)
MAX_SETTLE_TIME = 10.0


def check_range(name, value, lo=-math.inf, hi=math.inf, positive=True, strict=False, why: str = "") -> tuple[float, float]:
    """``value`` as a finite ``(low, high)`` pair within ``[lo, hi]``: ``low <= high`` (``low < high`` when
    ``strict``), ``low > 0`` when ``positive``; ValueError naming ``name`` (and ``why``, what sets the bounds)
    otherwise."""
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (low, high) pair of numbers, got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a > b or (strict and a == b):
        rel = "<" if strict else "<="
        raise ValueError(f"{name} must be a finite (low, high) pair with low {rel} high, got {value!r}")
    if positive and a <= 0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    if a < lo or b > hi:
        raise ValueError(f"{name} must lie within [{lo:g}, {hi:g}]{' (' + why + ')' if why else ''}, got {value!r}")
    return (a, b)


def check_number(name, value, *, positive=True) -> float:
    """``value`` as a finite float, > 0 (``positive``) or >= 0; ValueError naming ``name`` otherwise."""
    what = "a positive number" if positive else "a number >= 0"
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {what}, got {value!r}") from None
    if not (math.isfinite(v) and (v > 0 if positive else v >= 0)):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    return v


def check_within(name, value, lo: float, hi: float, why: str = "") -> float:
    """``value`` as a float in ``[lo, hi]`` (bools, NaN refused); ValueError naming ``name`` (and ``why``, the
    range's own name) otherwise: a value out of range is refused, never clipped into it."""
    try:
        v = math.nan if isinstance(value, (bool, np.bool_)) else float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not lo <= v <= hi:  # (NaN fails)
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}]{' (' + why + ')' if why else ''}, got {value!r}")
    return v


def check_size(name, value, length: float) -> float:
    """``value`` as a workpiece dimension [m] in ``(0, MAX_WORKPIECE_SIZE * length]`` (``length``: the fingers');
    ValueError naming ``name`` otherwise (a box 1e9 m deep was knocked over by its first step, unnamed)."""
    v = check_positive(name, value)
    if v > MAX_WORKPIECE_SIZE * length:
        raise ValueError(f"{name} must be at most {MAX_WORKPIECE_SIZE:g} times length = {length:g} m (fingers "
                         f"that long pick nothing so big), got {value!r}")
    return v


def check_charge(name, value) -> float:
    """``value`` as a charge in reward units: an int or float, finite and >= 0 (bools and strings refused, unlike
    :func:`check_number`); ValueError naming ``name`` otherwise (the training aids' charges,
    :mod:`simgrip.envs.crush_charge` and :mod:`simgrip.envs.step_charge`)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (0.0 <= value < math.inf):
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def check_positive(name, value) -> float:
    """``value`` as a finite float > 0; ValueError naming ``name`` otherwise."""
    return check_number(name, value, positive=True)


def check_int(name, value, low: int) -> int:
    """``value`` as an int >= ``low`` (integral floats accepted, bools refused); ValueError naming ``name``."""
    ok = not isinstance(value, (bool, np.bool_))
    try:
        v = int(value)
        ok = ok and v == value
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok or v < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return v


def check_bool(name, value) -> bool:
    """``value`` if it is a bool (numbers and strings are refused); ValueError naming ``name`` otherwise."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def check_reset(seed, options, known) -> tuple[int | None, dict]:
    """``reset``'s ``(seed, options)`` checked: ``seed`` None or an integer >= 0 (Python's or NumPy's, returned
    as a Python ``int``: Gymnasium refuses ``np.int64``), ``options`` None or a mapping whose keys are in
    ``known`` (returned as a new dict).  ValueError naming ``seed`` or ``options`` otherwise."""
    if seed is not None:
        if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be None or an integer >= 0 (int or NumPy integer), got {seed!r}")
        seed = int(seed)
    if options is None:
        return seed, {}
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be None or a dict of reset options ({', '.join(sorted(known))}), "
                         f"got {type(options).__name__} {options!r}")
    unknown = set(options) - set(known)
    if unknown:
        raise ValueError(f"unknown reset options {sorted(map(str, unknown))}; use {', '.join(sorted(known))}")
    return seed, dict(options)


def check_action(action, shape: tuple) -> list:
    """``action`` as a list of floats clipped to ``[-1, 1]``; ValueError on a wrong shape or non-finite values."""
    if type(action) is np.ndarray and action.shape == shape and action.dtype.kind == "f":
        vals = action.tolist()  # the usual case: a float array of the right shape (float32 values are exact)
    else:
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"action must be an array of {shape[0]} numbers, got {action!r}") from None
        if a.shape != shape:
            raise ValueError(f"action must have shape {shape}, got {a.shape}")
        vals = a.tolist()
    for v in vals:
        if not math.isfinite(v):
            raise ValueError(f"action must be finite (no NaN or inf), got {action!r}")
    return [-1.0 if v < -1.0 else (1.0 if v > 1.0 else v) for v in vals]


def set_finger_arguments(env, *, render_mode, n_links, length, EI, rho, g, r_tip) -> None:
    """Check the render mode and the fingers' arguments and set them on ``env`` (SI units).

    Sets ``env.render_mode`` (None or one of ``env.metadata["render_modes"]``), ``env.n`` (``n_links``, an
    integer >= 2), ``env.length`` [m], ``env.EI`` [N m^2], ``env.rho`` [kg/m], ``env.g`` [m/s^2] and
    ``env.r_tip`` [m] (all > 0); ValueError naming the first bad argument.
    """
    if render_mode is not None and render_mode not in env.metadata["render_modes"]:
        raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
    env.render_mode = render_mode
    env.n = check_links(n_links, "n_links")
    env.length = check_positive("length", length)
    env.EI = check_positive("EI", EI)
    env.rho = check_positive("rho", rho)
    env.g = check_positive("g", g)
    lo, hi = MIN_TIP_RADIUS * env.length, MAX_TIP_RADIUS * env.length
    env.r_tip = check_within("r_tip", r_tip, lo, hi, f"{MIN_TIP_RADIUS:g} to {MAX_TIP_RADIUS:g} times length = "
                             f"{env.length:g} m")


def set_task_arguments(env, *, kappa_range, kappa_tau, palm_speed, palm_range, palm_start, target_height,
                       hold_time, w_lift, w_success, w_squeeze, w_drop, squeeze_margin, drop_distance, timestep,
                       frame_skip, settle_time, finger_damping_time, shape_points, spin_friction, impratio,
                       finger_armature, width, height, camera, palm_ramp=False) -> None:
    """Check the control, task, reward, physics and rendering arguments and set them on ``env``.

    Each argument is set under its own name (SI units: ``kappa_range`` is the curvature command's range of
    ``kappa_bar``, a ``(low, high)`` pair with ``low < high``; ``kappa_tau`` [s]; ``palm_speed`` [m/s];
    ``palm_range``, ``palm_start`` [m], ``palm_start`` within ``palm_range``; ``target_height`` [m];
    ``hold_time``, ``timestep``, ``settle_time``, ``finger_damping_time`` [s]; ``finger_armature`` [kg m^2];
    ``width``, ``height`` [pixels]; ``camera`` a non-empty name, checked against the model by
    :func:`check_camera`; ``palm_ramp`` a bool: the palm's target ramped within a control step,
    :mod:`simgrip.envs.palm_servo`).  Derived: ``env.settle_steps`` (physics steps of ``settle_time``), ``env.dt``
    (``timestep * frame_skip``, the control step [s]), ``env._lag_alpha`` (the pneumatic lag's exact
    first-order factor over one control step) and ``env.metadata["render_fps"]``.  ValueError naming the first
    bad argument.
    """
    env.kappa_range = check_range("kappa_range", kappa_range, positive=False, strict=True)
    env.kappa_tau = check_number("kappa_tau", kappa_tau, positive=False)
    env.palm_speed = check_positive("palm_speed", palm_speed)
    env.palm_range = check_range("palm_range", palm_range)
    env.palm_start = check_range("palm_start", palm_start, lo=env.palm_range[0], hi=env.palm_range[1])
    env.target_height = check_positive("target_height", target_height)
    env.hold_time = check_number("hold_time", hold_time, positive=False)
    env.w_lift = check_number("w_lift", w_lift, positive=False)
    env.w_success = check_number("w_success", w_success, positive=False)
    env.w_squeeze = check_number("w_squeeze", w_squeeze, positive=False)
    env.w_drop = check_number("w_drop", w_drop, positive=False)
    env.squeeze_margin = check_positive("squeeze_margin", squeeze_margin)
    env.drop_distance = check_positive("drop_distance", drop_distance)
    env.timestep = check_positive("timestep", timestep)
    env.frame_skip = check_int("frame_skip", frame_skip, 1)
    if env.timestep * env.frame_skip > MAX_CONTROL_STEP:
        raise ValueError(f"frame_skip: the control step timestep * frame_skip must be at most {MAX_CONTROL_STEP:g} s "
                         f"(a pick lasts a few seconds), got {frame_skip!r} steps of {env.timestep:g} s")
    env.settle_time = check_number("settle_time", settle_time, positive=False)
    if env.settle_time > MAX_SETTLE_TIME:
        raise ValueError(f"settle_time must be at most {MAX_SETTLE_TIME:g} s (the fingers settle within 0.2 s), "
                         f"got {settle_time!r}")
    env.settle_steps = int(round(env.settle_time / env.timestep))
    env.finger_damping_time = check_number("finger_damping_time", finger_damping_time, positive=False)
    if env.finger_damping_time > 0 and env.timestep >= 2.0 * env.finger_damping_time:
        raise ValueError(f"timestep must be below 2 finger_damping_time = {2.0 * env.finger_damping_time:g} s (the "
                         f"hinges' step is stable below it, their damping implicit), got {timestep!r}")
    env.shape_points = check_int("shape_points", shape_points, 2)
    if env.shape_points > MAX_LINKS:
        raise ValueError(f"shape_points must be at most {MAX_LINKS} (the finest chain simgrip builds; a sample "
                         f"between two links' midpoints is interpolated), got {shape_points!r}")
    env.spin_friction = check_positive("spin_friction", spin_friction)
    env.impratio = check_positive("impratio", impratio)
    env.finger_armature = check_number("finger_armature", finger_armature, positive=False)
    env.width = check_int("width", width, 1)
    env.height = check_int("height", height, 1)
    for name in ("width", "height"):
        if getattr(env, name) > MAX_PIXELS:
            raise ValueError(f"{name} must be at most {MAX_PIXELS} pixels (an offscreen framebuffer GL drivers "
                             f"allocate), got {getattr(env, name)!r}")
    if not isinstance(camera, str) or not camera:
        raise ValueError(f"camera must be the name of a camera of the model, got {camera!r}")
    env.camera = camera
    env.palm_ramp = check_bool("palm_ramp", palm_ramp)
    env.dt = env.timestep * env.frame_skip
    env._lag_alpha = 1.0 if env.kappa_tau == 0 else 1.0 - math.exp(-env.dt / env.kappa_tau)
    env.metadata = dict(env.metadata, render_fps=int(round(1.0 / env.dt)))


def check_camera(model, camera: str) -> None:
    """ValueError naming ``camera`` unless ``model`` (an ``MjModel``) has a camera of that name."""
    if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
        cams = [model.camera(i).name for i in range(model.ncam)]
        raise ValueError(f"camera must be one of {cams}, got {camera!r}")
