"""The sweep's references at the cost of a continuation (simgrip.sweep.reference): what is solved, and how.

The equality of every warm reference with the point's cold solve on lines that cross the hold/drop boundary
is tests/test_sweep_stream.py's; here the work: a line whose BVP does not change (the friction axis) costs
one cold solve, and a walk along kappa takes no cold solve but its two ends.
"""

from __future__ import annotations

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
    """The first point solved cold, the others walked, the last checked by its cold path without the final
    polish (TOL_MID) and kept from the walk: equal to its full cold solve to the solver's tolerance."""
    from simgrip.reference.bvp import TOL_MID

    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    grid = make_grid("I", kappa=(-7, -6, 12), links=LINKS)
    tols = []
    calls = _counted(monkeypatch, tols)
    rows = evaluate_segment([grid.point(i) for i in range(grid.size)])
    assert calls == {"cold": 2, "warm": 11} and tols == [sweep_reference.TOL, TOL_MID]
    assert all(r["bvp_warning"] == "" and r["bvp_message"] == "" for r in rows)
    full = evaluate_point(grid.point(grid.size - 1))
    # two 1e-8 solutions of one equilibrium (see tests/test_sweep_stream.py's FORCE_RTOL)
    assert rows[-1]["bvp_normal_force"] == pytest.approx(full["bvp_normal_force"], rel=1e-6)
    assert rows[-1]["bvp_feasible"] is full["bvp_feasible"]


def test_problem_key_ignores_only_friction():
    g = make_grid("III", kappa=-4, mu=(0.5, 1, 2), gamma=(0.7, 0.8, 2), links=LINKS)
    keys = [sweep_reference.problem_key(g.point(i)) for i in range(g.size)]
    # grid order: mu slower than gamma; equal keys exactly where only mu differs
    assert keys[0] == keys[2] and keys[1] == keys[3] and keys[0] != keys[1]
    g1 = make_grid("I", kappa=-4, gamma=(0.7, 0.8, 2), links=LINKS)
    assert sweep_reference.problem_key(g1.point(0)) == sweep_reference.problem_key(g1.point(1))  # gamma: III only
