"""The sweep's references at the cost of a continuation (simgrip.sweep.reference): what is solved, and how.

The equality of every warm reference with the point's cold solve on lines that cross the hold/drop boundary
is tests/test_sweep_stream.py's; here the work: a line whose BVP does not change (the friction axis) costs
one cold solve, and a walk along kappa takes no cold solve but its two ends.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.sweep import point as sweep_point
from simgrip.sweep import reference as sweep_reference
from simgrip.sweep.grid import make_grid
from simgrip.sweep.point import evaluate_point, evaluate_segment

LINKS = 8


def _no_simulation(point):
    return {**{c: None for c in sweep_point.SIM_COLUMNS}, "wall_time_s": None, "message": ""}


def _counted(monkeypatch, tols=None):
    calls = {"cold": 0, "warm": 0}
    for name in calls:
        real = getattr(sweep_reference, name)

        def counted(*args, _real=real, _name=name):
            calls[_name] += 1
            if _name == "cold" and tols is not None:
                tols.append(args[1] if len(args) > 1 else sweep_reference.TOL)
            return _real(*args)

        monkeypatch.setattr(sweep_reference, name, counted)
    return calls


def test_a_friction_line_is_one_cold_solve(monkeypatch):
    """mu enters the verdict only: a Grip II segment along mu (5 points, the sweep's default cut) is one BVP,
    solved cold once; every point's columns equal its own cold solve's, the verdict with its own mu (the line
    crosses the friction limit: required mu ~0.78 here)."""
    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    grid = make_grid("II", kappa=4.5, mu=(0.5, 1.5, 5), links=LINKS)
    assert list(grid.segments()) == [(0, 5)]
    points = [grid.point(i) for i in range(5)]
    calls = _counted(monkeypatch)
    rows = evaluate_segment(points)
    assert calls == {"cold": 1, "warm": 0}
    cold = [evaluate_point(p) for p in points]
    assert [r["bvp_feasible"] for r in rows] == [r["bvp_feasible"] for r in cold]
    assert len({r["bvp_feasible"] for r in rows}) == 2
    for r, c in zip(rows, cold):
        assert (r["bvp_normal_force"], r["bvp_required_mu"]) == (c["bvp_normal_force"], c["bvp_required_mu"])


def test_a_kappa_walk_is_cold_at_its_ends_only(monkeypatch):
    """The first point solved by its cold path without the final polish (TOL_MID) and finished on a sized mesh,
    the others walked, the last checked by its cold path without the final polish and kept from the walk: both
    ends equal to their full cold solves to the solver's tolerance."""
    from simgrip.reference.bvp import TOL_MID

    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    grid = make_grid("I", kappa=(-7, -6, 12), links=LINKS)
    tols = []
    calls = _counted(monkeypatch, tols)
    rows = evaluate_segment([grid.point(i) for i in range(grid.size)])
    assert calls == {"cold": 2, "warm": 11} and tols == [TOL_MID, TOL_MID]
    assert all(r["bvp_warning"] == "" and r["bvp_message"] == "" for r in rows)
    for k in (0, grid.size - 1):
        full = evaluate_point(grid.point(k))
        # two 1e-8 solutions of one equilibrium (see tests/test_sweep_stream.py's FORCE_RTOL)
        assert rows[k]["bvp_normal_force"] == pytest.approx(full["bvp_normal_force"], rel=1e-6)
        assert rows[k]["bvp_feasible"] is full["bvp_feasible"]


@pytest.mark.parametrize("grip, kappa, D", [("I", -7.0, 1.0), ("I", -3.0, 1.0), ("II", 4.5, 1.0),
                                            ("II", 4.0, 0.5), ("III", -4.0, 1.0)])
def test_a_sized_mesh_is_as_accurate_as_its_estimate_says(grip, kappa, D):
    """The walk's meshes (sweep.reference.on_sized_mesh) against the full 1e-8 cold solve: the sized start's N1
    (over max(|N1|, 1)) and theta within 10 x its Richardson estimate (fourth order assumed: the estimate is within ~1.5x of the
    error measured on Grip I, 10x leaves room for the other grips) and that estimate within TOL; the cold mesh
    thinned to every 8th node is refused where its estimate exceeds TOL and otherwise also within 10x."""
    g = make_grid(grip, kappa=kappa, D=D, links=LINKS)
    point = g.point(0)
    full = sweep_reference.cold(point)
    sol, factor = sweep_reference.sized_start(point)
    assert sol is not None and factor is not None
    est = sweep_reference.walk_error(sol)
    assert est <= sweep_reference.TOL
    idx = np.searchsorted(full._raw.x, sol._raw.x)
    assert sol._raw.x.size < full._raw.x.size  # coarser than solve_bvp's (else nothing is gained)
    s = np.linspace(0.0, 1.0, 41)
    err = max(abs(sol.N1 - full.N1) / max(abs(full.N1), 1.0),  # as sweep.reference._gap measures it
              float(np.max(np.abs(sol._raw.states(s)[0] - full._raw.states(s)[0]))))
    assert err <= 10 * max(est, 1e-12), (err, est, idx.size)
    coarse = full._raw.x[sweep_reference._thinned(full._raw.x, 8)]
    r, _ = sweep_reference.on_sized_mesh(full, [coarse])
    if r is not None:
        e8 = sweep_reference.walk_error(r)
        assert e8 <= sweep_reference.TOL
        assert abs(float(r.p[0]) - full.N1) / max(abs(full.N1), 1.0) <= 10 * max(e8, 1e-12)


def test_problem_key_ignores_only_friction():
    g = make_grid("III", kappa=-4, mu=(0.5, 1, 2), gamma=(0.7, 0.8, 2), links=LINKS)
    keys = [sweep_reference.problem_key(g.point(i)) for i in range(g.size)]
    # grid order: mu slower than gamma; equal keys exactly where only mu differs
    assert keys[0] == keys[2] and keys[1] == keys[3] and keys[0] != keys[1]
    g1 = make_grid("I", kappa=-4, gamma=(0.7, 0.8, 2), links=LINKS)
    assert sweep_reference.problem_key(g1.point(0)) == sweep_reference.problem_key(g1.point(1))  # gamma: III only
