"""Measuring helpers of the bench: median wall time of repeats, errors against a reference state."""

from __future__ import annotations

import statistics
import time

import numpy as np

__all__ = ["median_time", "contact_force", "errors"]


def median_time(fn, repeats: int):
    """Run ``fn()`` ``repeats`` times (at least once); return ``(last result, median s, min s)``."""
    times = []
    out = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times), min(times)


def contact_force(obj) -> np.ndarray:
    """``(N1, N2)``, the contact force on the rod over ``rho g l``, of any state or solution that has them."""
    return np.array([float(obj.N1), float(obj.N2)])


def errors(grip: str, tip, force, ref) -> tuple[float, float | None]:
    """``(|tip - ref.tip|, |force - (ref.N1, ref.N2)|)``; no force error for the free rod (``None``)."""
    tip_err = float(np.linalg.norm(np.asarray(tip, float) - ref.tip))
    if grip == "free":
        return tip_err, None
    return tip_err, float(np.linalg.norm(np.asarray(force, float) - contact_force(ref)))
