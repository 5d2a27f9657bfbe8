"""The sweep's packaging of a reference (simgrip.sweep.reference.Reference): the fields the sweep reads equal
ElasticaSolution.from_bvp's bit for bit, on every grip, on both sides of every feasibility test."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.sweep import reference as sweep_reference
from simgrip.sweep.grid import make_grid

LINKS = 8


@pytest.mark.parametrize("grip, kappa, mu", [
    ("I", (-7.0, -2.0, 6), (0.2, 1.0, 2)),   # across Grip I's hold/drop boundary, friction on both sides
    ("II", (1.0, 6.0, 6), (0.3, 1.0, 2)),    # Grip II from dropped (other shape) to held
    ("III", (-6.0, -1.0, 6), (0.2, 1.0, 2)),  # Grip III: the contact inside the rod, tip clear or not
])
def test_reference_fields_equal_from_bvp(grip, kappa, mu):
    g = make_grid(grip, kappa=kappa, mu=mu, links=LINKS)
    seen = set()
    for i in range(g.size):
        point = g.point(i)
        sol = sweep_reference.cold(point)
        ref = sweep_reference.Reference(point.grip, point.params(), sol._raw)
        for name in ("N1", "normal_force", "required_mu", "feasible"):
            a, b = getattr(ref, name), getattr(sol, name)
            assert type(a) is type(b) and (a == b or (np.isnan(a) and np.isnan(b))), (i, name, a, b)
        seen.add(tuple(sorted(sol.feasibility.items())))
        # any other field: the ElasticaSolution's, built on first access
        assert np.array_equal(ref.theta, sol.theta) and ref.feasibility == sol.feasibility
    assert len(seen) >= 2, seen  # both verdicts met (a field computed wrongly on one side would show)


def test_spline_end_value_is_its_value_at_the_end():
    """Spline.end_value (what Reference reads the tip with) against the spline evaluated at t = 1, eager and
    lazy (a walk's solution on its mesh, simgrip.reference.collocation._LazySpline), bit for bit."""
    from simgrip.reference.collocation import _LazySpline

    g = make_grid("III", kappa=(-6.0, -5.0, 3), links=LINKS)
    seg = sweep_reference._Segment([g.point(i) for i in range(3)])
    mesh, factor = seg.start()
    walked = sweep_reference.warm(g.point(1), seg.sol[0], (), {"mesh": mesh, "factor": factor})
    cold = sweep_reference.cold(g.point(1))
    for sol in (walked._raw.sol, cold._raw.sol):
        lazy = isinstance(sol, _LazySpline)
        first = sol.end_value(1.0)  # a lazy spline's before its coefficients exist
        each = [sol.end_component(1.0, j) for j in range(first.size)]
        assert np.array_equal(first, sol(np.array([1.0]))[:, 0]) and np.array_equal(first, sol.end_value(1.0))
        assert each == [sol.end_component(1.0, j) for j in range(first.size)] == first.tolist()
        assert lazy is (sol is walked._raw.sol)
