"""What a repeated :func:`simgrip.compare.simulate` call costs beyond its settle (issue 19, "compile once").

:func:`call_settle_ratio` calls ``simulate`` ``calls + 1`` times on one structure (grip, links) with
different uniform ``kappa_bar0``, the first compiling the scene (:mod:`simgrip.sim.reuse`), the others
setting it in place, and reports the median call's wall time over the median settle's (``wall_time_s``).
Before the cache every call rebuilt and recompiled the model: 16.9x at ``n = 256`` (the free rod).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

__all__ = ["call_settle_ratio"]


def call_settle_ratio(grip: str = "free", links: int = 256, *, calls: int = 12, params=None,
                      kappas=(-1.0, -6.0)) -> dict:
    """Median wall time of a repeated ``simulate(grip, params, Uniform(k), links)`` over its settle's.

    ``calls`` calls after a first one (which compiles and is reported apart), ``k`` evenly spaced over
    ``kappas``; ``params`` default :data:`simgrip.params.STANDARD`.  The calling thread's scene cache is
    emptied first (:func:`simgrip.sim.reuse.clear`).  Returns ``{"grip", "links", "calls", "first_call_s",
    "call_s", "settle_s", "ratio"}`` (seconds; medians, ``ratio = call_s / settle_s``) and, for a shared
    machine, ``"overhead_min_s"`` (the least call-minus-settle), ``"settle_min_s"`` (the fastest settle) and
    ``"ratio_min" = (overhead_min_s + settle_min_s) / settle_min_s``.
    """
    from simgrip.compare import simulate
    from simgrip.params import STANDARD
    from simgrip.profiles import Uniform
    from simgrip.sim import reuse

    if isinstance(calls, bool) or not isinstance(calls, (int, np.integer)) or calls < 1:
        raise ValueError(f"calls must be an integer >= 1, got {calls!r}")
    p = STANDARD if params is None else params
    reuse.clear()
    wall, settle = [], []
    for k in np.linspace(float(kappas[0]), float(kappas[1]), int(calls) + 1):
        t0 = time.perf_counter()
        st = simulate(grip, p, Uniform(float(k)), links)
        wall.append(time.perf_counter() - t0)
        settle.append(float(st.wall_time_s))
    call_s, settle_s = statistics.median(wall[1:]), statistics.median(settle[1:])
    fastest = min(range(1, len(wall)), key=lambda i: wall[i] - settle[i])  # the call least disturbed by the machine
    return {"grip": grip, "links": int(links), "calls": int(calls), "first_call_s": wall[0], "call_s": call_s,
            "settle_s": settle_s, "ratio": call_s / settle_s,
            "overhead_min_s": wall[fastest] - settle[fastest], "settle_min_s": min(settle[1:]),
            "ratio_min": (wall[fastest] - settle[fastest] + min(settle[1:])) / min(settle[1:])}
