"""Tests of simgrip.reference.capacity: feasibility margin, least friction coefficient, largest load.

The largest load is checked against what defines it: at the returned ``M`` the
condition it names is exactly marginal (friction: ``mu_s N = M``), and a fold is
where the stability eigenvalue of the branch vanishes like ``sqrt(M_fold - M)``.
"""

from __future__ import annotations

import functools
import math

import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import (
    ElasticaError,
    LoadCapacity,
    elastica,
    largest_load,
    least_mu,
    margin,
    margin_terms,
    max_load,
    solve,
    stability_eigenvalue,
    sweep,
    track_largest_load,
)


@pytest.fixture(scope="module")
def loads():
    """``max_load(grip, STANDARD, Uniform(kappa))``, each (grip, kappa) searched once in this module: four tests
    ask for the same Grip I loads (kappa = -5 in four, -6 in two); each is still compared with its own solve."""
    return functools.cache(lambda grip, kappa: max_load(grip, STANDARD, Uniform(kappa)))


def test_grip_III_carries_the_most_load(loads):
    ks = {"I": [-5.0, -6.0], "II": [4.5, 5.0, 5.5, 6.0], "III": [-4.0, -5.0]}
    best = {g: max(loads(g, k) for k in kk) for g, kk in ks.items()}
    assert best["III"] > best["I"] and best["III"] > best["II"]
    assert math.isfinite(best["III"])


def test_max_load_is_the_feasibility_boundary(loads):
    """At the returned M the grip is marginal: mu_s N = M (Grip I)."""
    M = loads("I", -5.0)
    sol = solve("I", STANDARD.replace(M=M), Uniform(-5.0))
    assert STANDARD.mu_s * sol.N1 == pytest.approx(M, abs=1e-6)
    assert least_mu("I", STANDARD, Uniform(-5.0)) == pytest.approx(STANDARD.M / solve("I", STANDARD, Uniform(-5.0)).N1)
    assert least_mu("I", STANDARD, Uniform(-1.0)) == math.inf


def test_margin_is_non_negative_exactly_where_the_grip_holds():
    for grip, kappas in (("I", (-3.0, -5.0, -6.0)), ("III", (-2.0, -4.0, -6.5))):
        for sol in sweep(grip, STANDARD, [Uniform(k) for k in kappas]):
            terms = margin_terms(sol)
            assert margin(sol) == min(terms.values())
            assert (margin(sol) >= 0) == sol.feasible
            assert terms["friction"] == pytest.approx(STANDARD.mu_s * sol.normal_force - abs(sol.friction_force))
            assert ("tip_clear" in terms) == (grip == "III")


def test_largest_load_names_its_reason(loads):
    friction = largest_load("I", STANDARD, Uniform(-5.0))
    assert friction.reason == "friction" and friction.M == pytest.approx(loads("I", -5.0))
    held = friction.solution
    assert held.feasible and 0 <= friction.M - held.params.M <= 1e-6
    none = largest_load("I", STANDARD, Uniform(-1.0))  # the finger pulls on the workpiece: nothing held
    assert none == LoadCapacity(0.0, "none", None)
    limit = largest_load("III", STANDARD, Uniform(-5.0), M_max=10.0)
    assert limit.M == math.inf and limit.reason == "limit" and limit.solution.params.M == 10.0
    with pytest.raises(ValueError, match="M_max"):
        largest_load("I", STANDARD, Uniform(-5.0), M_max=0.0)
    with pytest.raises(ValueError, match="grip"):
        largest_load("free", STANDARD, Uniform(-5.0))


def test_a_fold_is_where_the_branch_loses_stability():
    """Grip II at kappa = 6 snaps through before friction runs out: along the branch the
    stability eigenvalue (nodal scheme, K = 256) vanishes like sqrt(M_fold - M), so from
    4 % to 1 % below the fold it halves (sqrt(1/4)); the O(1/K^2) shift of the discrete
    fold is ~1e-5 M, far below those distances."""
    cap = largest_load("II", STANDARD, Uniform(6.0))
    assert cap.reason == "fold" and margin(cap.solution) > 1.0  # friction is far from its limit
    lam = {}
    prev = solve("II", STANDARD.replace(M=0.0), Uniform(6.0))
    for f in (0.5, 0.9, 0.96, 0.99):
        prev = solve("II", STANDARD.replace(M=f * cap.M), Uniform(6.0), guess=prev, fallback=False)
        lam[f] = stability_eigenvalue(prev, 256)
    assert lam[0.5] > lam[0.9] > lam[0.96] > lam[0.99] > 0
    # abs 0.06: the ratio tells a square-root fold (0.5) from a linear zero (0.25) and a regular point (1); the
    # normal form's next order moves it: lam / sqrt(1 - f) is 17.66 at 4 % and 16.60 at 1 % (measured), so 0.470
    assert lam[0.99] / lam[0.96] == pytest.approx(0.5, abs=0.06)


def test_tracking_a_sweep_matches_independent_searches(loads):
    kappas = (-4.5, -5.0, -5.5, -6.0)
    profiles = [Uniform(k) for k in kappas]
    tracked = track_largest_load("I", STANDARD, profiles, sweep("I", STANDARD, profiles))
    for cap, prof in zip(tracked, profiles):
        assert cap.reason == "friction"
        assert cap.M == pytest.approx(loads("I", prof.kappa), abs=1e-7)
    assert track_largest_load("I", STANDARD, []) == []
    with pytest.raises(ValueError, match="guesses"):
        track_largest_load("I", STANDARD, profiles, [None])


def test_sweeps_can_skip_failed_points(monkeypatch):
    """``failures="skip"``: a point that cannot be solved is None / NaN, the rest go on."""
    real = elastica.solve_problem

    def fails_at_5(P, *a, **k):
        return None if P.profile == Uniform(-5.0) else real(P, *a, **k)

    monkeypatch.setattr(elastica, "solve_problem", fails_at_5)
    profiles = [Uniform(k) for k in (-4.5, -5.0, -5.5)]
    with pytest.raises(ElasticaError):
        sweep("I", STANDARD, profiles)
    sols = sweep("I", STANDARD, profiles, failures="skip")
    assert sols[1] is None and sols[0].success and sols[2].success
    with pytest.raises(ValueError, match="failures"):
        sweep("I", STANDARD, profiles, failures="ignore")
