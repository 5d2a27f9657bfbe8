"""Tests of how the elastica solves are brought to converge (simgrip.reference.continuation).

The hostile inputs below once took 26-62 s (a final-tolerance polish that
refined a coarse mesh up to the node limit, retried at every halved step) or
1-5 s a point (folds met by the first cold-start strategy, approached in a
dozen halvings).  The tests are not timings (speed is ``simgrip bench``'s): the
work is counted (``solve_bvp`` runs), a ``SIGALRM`` of 300 s only guards against
a hang (the slowest case takes ~1 s alone, so a machine loaded 100-fold still
passes), and each must end in a verified solution (residual within ``tol``,
contact at ``b/2``, moments agreeing with an independent global balance): a
solver that gives up on them fails (issue 22, item 2).
"""

from __future__ import annotations

import signal

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference.bvp import ElasticaError
from simgrip.reference.continuation import MAX_BVP_RUNS, Budget, cold_start
from simgrip.reference.elastica import checked_problem, solve

from test_elastica import _balance_moment

_GUARD_S = 300  # a hang guard only (see the module docstring)
#: ``solve_bvp`` runs one hostile solve may spend: measured 5 (the first three) to 62 (Grip I, kappa -9); half of
#: MAX_BVP_RUNS, so a solve that wanders towards the budget (the old fold halvings) fails here, not in a timing.
HOSTILE_RUNS = MAX_BVP_RUNS // 2


class _Hang(Exception):
    pass


@pytest.fixture
def guard():
    """Fail a test that runs past ``_GUARD_S`` seconds (a hang, not a slow run)."""

    def alarm(signum, frame):
        raise _Hang(f"still running after {_GUARD_S} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(_GUARD_S)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


HOSTILE = [
    ("III", dict(D=6148, M=0.0, b=0.6898, mu_s=1e-15, gamma=0.6898), 0.0807),
    ("III", dict(D=1e4, M=0.2414, b=0.00549, gamma=0.2122), 0.8),
    ("II", dict(D=1e4, M=8.37e-5, b=0.8093, mu_s=4.84), 11.905),
    ("I", {}, -7.5),
    ("I", {}, -8.0),
    ("I", {}, -9.0),
    ("I", {}, -10.0),
]


@pytest.mark.parametrize("grip, changes, kappa", HOSTILE)
def test_hostile_solves_end_verified(guard, monkeypatch, grip, changes, kappa):
    """Every hostile case has a solution, and the solver must find it (the first three are infeasible as
    grips, which is the solution's verdict, not a failure); an ElasticaError fails the test."""
    import simgrip.reference.continuation as C

    runs = []
    real = C.run_bvp
    monkeypatch.setattr(C, "run_bvp", lambda *a, **k: runs.append(1) or real(*a, **k))
    p = STANDARD.replace(**changes)
    sol = solve(grip, p, Uniform(kappa))
    assert 0 < len(runs) <= HOSTILE_RUNS
    assert sol.success and sol.residual <= 1e-8
    assert sol.contact[0] == pytest.approx(p.b / 2, abs=1e-9)
    scale = max(1.0, float(np.max(np.abs(sol.moment))))
    for s0 in (0.0, 0.3, 0.9):
        assert sol.moment_at(s0) == pytest.approx(_balance_moment(sol, s0), abs=1e-7 * scale)


def test_the_work_of_a_solve_is_bounded():
    _, _, P = checked_problem("I", STANDARD, Uniform(-9.0))
    budget = Budget(3)
    with pytest.raises(ElasticaError, match="MAX_BVP_RUNS"):
        cold_start(P, 1e-8, budget)
    assert budget.used == 3
    assert Budget().limit == MAX_BVP_RUNS


def test_a_cold_start_spends_few_runs_at_the_standard_case():
    # The exact arc, the profile, the loads and a polish: a handful of runs, far below the bound.
    _, _, P = checked_problem("I", STANDARD, Uniform(-5.5))
    budget = Budget()
    raw = cold_start(P, 1e-8, budget)
    assert raw is not None and raw.rms <= 1e-8
    assert budget.used < 20
