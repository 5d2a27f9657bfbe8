"""Checks of the environments' arguments: each bad value raises ``ValueError`` naming the argument."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["check_action", "check_bool", "check_int", "check_number", "check_positive", "check_range"]


def check_range(name, value, lo=-math.inf, hi=math.inf, positive=True, strict=False) -> tuple[float, float]:
    """``value`` as a finite ``(low, high)`` pair within ``[lo, hi]``: ``low <= high`` (``low < high`` when
    ``strict``), ``low > 0`` when ``positive``; ValueError naming ``name`` otherwise."""
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
        raise ValueError(f"{name} must lie within [{lo}, {hi}], got {value!r}")
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
