"""Measuring helpers of the bench: median wall time of repeats, the fastest CPU times of functions run in
turn, a settle repeatable from the same start, errors against a reference state."""

from __future__ import annotations

import statistics
import time

import numpy as np

__all__ = ["median_time", "fastest_cpu_times", "interleaved_cpu_times", "settle_from_start", "contact_force", "errors"]


def median_time(fn, repeats: int):
    """Run ``fn()`` ``repeats`` times (at least once); return ``(last result, median s, min s)``."""
    times = []
    out = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times), min(times)


def interleaved_cpu_times(fns: dict, repeats: int) -> dict:
    """Every CPU time [s] (``time.process_time``) of each ``fn()`` of ``fns``, ``{key: [seconds, ...]}``, the
    functions run in turn ``repeats`` times (at least once): interleaved, so their ratios hold on a busy
    machine."""
    times = {k: [] for k in fns}
    for _ in range(max(1, repeats)):
        for k, fn in fns.items():
            t0 = time.process_time()
            fn()
            times[k].append(time.process_time() - t0)
    return times


def fastest_cpu_times(fns: dict, repeats: int) -> dict:
    """Fastest CPU seconds of each ``fn()`` of ``fns`` over :func:`interleaved_cpu_times`' runs."""
    return {k: min(v) for k, v in interleaved_cpu_times(fns, repeats).items()}


def settle_from_start(grip: str, kappa: float, n: int, **kw):
    """A function running the planar settle (:func:`simgrip.settle.settle`, keywords ``kw``) of the standard
    case of ``grip`` at uniform ``kappa_bar = kappa`` with ``n`` links, from the same start on every call: the
    scene is built once, outside the timed region, and its start state put back before each settle."""
    from simgrip.params import STANDARD
    from simgrip.profiles import Uniform
    from simgrip.scenes import build_scene
    from simgrip.settle import settle

    sc = build_scene(grip, STANDARD, Uniform(kappa), n)
    q0, bp = sc.data.qpos.copy(), sc.model.body_pos.copy()

    def run():
        sc.data.qpos[:] = q0
        sc.model.body_pos[:] = bp
        return settle(sc, **kw)

    return run


def contact_force(obj) -> np.ndarray:
    """``(N1, N2)``, the contact force on the rod over ``rho g l``, of any state or solution that has them."""
    return np.array([float(obj.N1), float(obj.N2)])


def errors(grip: str, tip, force, ref) -> tuple[float, float | None]:
    """``(|tip - ref.tip|, |force - (ref.N1, ref.N2)|)``; no force error for the free rod (``None``)."""
    tip_err = float(np.linalg.norm(np.asarray(tip, float) - ref.tip))
    if grip == "free":
        return tip_err, None
    return tip_err, float(np.linalg.norm(np.asarray(force, float) - contact_force(ref)))
