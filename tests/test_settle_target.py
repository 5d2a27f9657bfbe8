"""settle(target_error=E): Richardson extrapolation and an honest error estimate.

Derivation (``simgrip/settle/target.py``): the chain is second order with an even
expansion, ``Q(h) = Q* + a h^2 + b h^4``; the extrapolated ``R(h/2)`` has error
``-b h^4/64`` and the Romberg estimate is ``|R(h/2) - R(h)|/15``.  In the
asymptotic range (coarsest level >= 8 links) the estimate must bound the true
error within a factor of 3 either way; the true error is measured against the
converged point-contact BVP (tol 1e-10).
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.compare import settled_record
from simgrip.reference import elastica
from simgrip.scenes import build_scene
from simgrip.settle import settle

CASES = [("free", -3.0), ("free", 2.0), ("I", -6.0), ("I", -8.0), ("II", 5.0), ("II", 6.0)]


def _true_errors(st, grip, kappa):
    ref = elastica.solve(grip, STANDARD, Uniform(kappa), tol=1e-10)
    tip = float(np.max(np.abs(st.tip[0] - ref.tip)))
    if grip == "free":
        return tip, None
    return tip, float(max(abs(st.N1 - ref.N1), abs(st.N2 - ref.N2)) / max(abs(ref.N1), abs(ref.N2)))


@pytest.mark.parametrize("grip,kappa", CASES)
@pytest.mark.parametrize("n0", [8, 16])
def test_the_estimate_bounds_the_true_error_within_a_factor_3(monkeypatch, grip, kappa, n0):
    import simgrip.settle.target as T

    monkeypatch.setattr(T, "TARGET_N0", n0)
    st = settle(build_scene(grip, STANDARD, Uniform(kappa), 16), target_error=0.5)  # first round accepted
    assert st.extrapolated and st.links == 4 * n0
    tip, force = _true_errors(st, grip, kappa)
    est = st.error_estimate
    assert tip / 3 <= est["tip"] <= 3 * tip
    if force is not None:
        assert force / 3 <= est["force"] <= 3 * force


@pytest.mark.parametrize("grip,kappa", [("free", -3.0), ("I", -6.0), ("II", 5.0)])
def test_a_target_of_1e_5_is_met(grip, kappa):
    st = settle(build_scene(grip, STANDARD, Uniform(kappa), 16), target_error=1e-5)
    tip, force = _true_errors(st, grip, kappa)
    assert max(st.error_estimate.values()) <= 1e-5
    assert tip <= 1e-5 and (force is None or force <= 1e-5)
    rec = settled_record(st, STANDARD)
    assert rec["extrapolated"] is True and rec["links"] == st.links and rec["error_estimate"] == st.error_estimate


def test_a_tighter_target_takes_more_links():
    a = settle(build_scene("I", STANDARD, Uniform(-6.0), 16), target_error=1e-4)
    b = settle(build_scene("I", STANDARD, Uniform(-6.0), 16), target_error=1e-7)
    assert b.links > a.links and max(b.error_estimate.values()) <= 1e-7


@pytest.mark.parametrize("value", [0.0, -1e-3, float("nan"), 1e-9, 2.0, "x"])
def test_bad_targets_name_the_parameter(value):
    with pytest.raises(ValueError, match="target_error"):
        settle(build_scene("I", STANDARD, Uniform(-6.0), 8), target_error=value)


def test_grip_iii_is_refused():
    with pytest.raises(ValueError, match="target_error: Grip III"):
        settle(build_scene("III", STANDARD, Uniform(-6.0), 8), target_error=1e-4)
