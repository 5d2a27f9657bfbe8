"""A segment's walk checked ahead, at the next segment's first point (simgrip.sweep.reference, issue 19).

A segment that ends before its line checks its walk by one more warm step to the point after it, against that
point's cold path at TOL_MID, the next segment's start: run next in the same process, that segment takes it
from there instead of solving it again.  What is tested: the cold solves saved (counted), the references
bit-identical to a run of each segment alone in a fresh cache (a cold path is a deterministic function of its
problem), equal to the cold solves, and a check ahead that fails falls back to the segment's own last point
(every warning as without the check ahead).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from simgrip.sweep import point as sweep_point
from simgrip.sweep import reference as sweep_reference
from simgrip.sweep.grid import make_grid
from simgrip.sweep.point import evaluate_point, evaluate_segment

sys.path.insert(0, str(Path(__file__).parent))
# the grid size, the force tolerance (two 1e-8 solves of one equilibrium, 100x the tolerance), the simulation
# left out, and the walk forced astray with what must follow it
from test_sweep_stream import (FORCE_RTOL, LINKS, _no_simulation, assert_astray_solved_cold,  # noqa: E402
                               walk_astray)

BVP = ("bvp_normal_force", "bvp_feasible", "bvp_required_mu", "bvp_message", "bvp_warning")


@pytest.fixture
def counted(monkeypatch):
    """The simulation off, the checks ahead forgotten; returns the TOL of every ``cold`` call, in order."""
    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    monkeypatch.setattr(sweep_reference, "_AHEAD", {})
    tols, real = [], sweep_reference.cold

    def cold(point, tol=sweep_reference.TOL):
        tols.append((point.index, tol))
        return real(point, tol)

    monkeypatch.setattr(sweep_reference, "cold", cold)
    return tols


def test_points_know_the_next_point_on_their_line():
    g = make_grid("I", kappa=(-7, -6, 3), M=(2, 8, 3), links=LINKS)  # lines along M, the last swept axis
    assert [p.after for p in g.points()] == [("M", 5.0), ("M", 8.0), None] * 3
    assert all(g.point(i) == p for i, p in enumerate(g.points()))
    assert make_grid("I", kappa=-5, links=LINKS).point(0).after is None


def test_a_line_costs_one_cold_path_a_segment(counted):
    """Three segments of a 20-point line run in order in one process: the first solves its start and its
    check ahead, the second only its check ahead (its start is the first's), the last only its end check;
    every reference bit-identical to the segment run alone (nothing kept from before) and equal to its
    point's cold solve."""
    from simgrip.reference.bvp import TOL_MID

    grid = make_grid("I", kappa=(-7, -5, 20), links=LINKS)  # crosses nothing: one branch, walks kept
    cuts = list(grid.segments(8))
    assert cuts == [(0, 8), (8, 16), (16, 20)]
    rows, calls = [], []
    for a, b in cuts:
        counted.clear()
        rows += evaluate_segment([grid.point(i) for i in range(a, b)])
        calls.append(list(counted))
    assert calls == [[(0, TOL_MID), (8, TOL_MID)], [(16, TOL_MID)], [(19, TOL_MID)]]
    for a, b in cuts:  # alone, in a fresh cache: the start solved again, the same bits
        sweep_reference._AHEAD.clear()
        alone = evaluate_segment([grid.point(i) for i in range(a, b)])
        assert [[r[c] for c in BVP] for r in alone] == [[r[c] for c in BVP] for r in rows[a:b]]
    for r in rows:
        c = evaluate_point(grid.point(r["index"]))
        assert r["bvp_normal_force"] == pytest.approx(c["bvp_normal_force"], rel=FORCE_RTOL)
        assert (r["bvp_feasible"], r["bvp_message"], r["bvp_warning"]) == (c["bvp_feasible"], "", "")


def test_a_check_ahead_that_fails_checks_the_last_point(counted, monkeypatch):
    """The step ahead forced onto another equilibrium (the solution at kappa + 3): the check ahead fails, the
    segment's last point is checked as without it (its cold path at TOL_MID) and the walk, on the cold branch,
    is kept; no warning (the walk itself did not leave)."""
    from simgrip.reference.bvp import TOL_MID

    real = sweep_reference.warm

    def astray(point, guess, *walk):
        if point.index == 8:  # the point ahead of segment 0..7
            from dataclasses import replace

            return real(replace(point, kappa=point.kappa + 3.0), guess, *walk)
        return real(point, guess, *walk)

    monkeypatch.setattr(sweep_reference, "warm", astray)
    grid = make_grid("I", kappa=(-7, -5, 20), links=LINKS)
    rows = evaluate_segment([grid.point(i) for i in range(8)])
    assert counted == [(0, TOL_MID), (8, TOL_MID), (7, TOL_MID)]
    monkeypatch.setattr(sweep_reference, "warm", real)
    sweep_reference._AHEAD.clear()
    counted.clear()
    ahead = evaluate_segment([grid.point(i) for i in range(8)])
    assert counted == [(0, TOL_MID), (8, TOL_MID)]
    assert [[r[c] for c in BVP] for r in rows] == [[r[c] for c in BVP] for r in ahead]


def test_a_walk_astray_is_solved_cold_and_says_so_with_a_check_ahead(counted, monkeypatch):
    """A walk that leaves the cold branch inside a segment that ends before its line (points 4-6 forced onto
    the solution at kappa + 3): the check ahead fails, the last point's check fails, and the bisection solves
    the points cold and says so, as in a segment that ends its line (tests/test_sweep_stream.py)."""
    walk_astray(monkeypatch)
    grid = make_grid("I", kappa=(-7, -5, 12), links=LINKS)
    points = [grid.point(i) for i in range(7)]  # segment 0..6 of a 12-point line: checked ahead at 7
    assert points[-1].after is not None
    assert_astray_solved_cold(points)
