"""simgrip.harness.agreement: hold/drop of Newton and dynamics compared per stress case, with the friction margin."""

from __future__ import annotations

import pytest

from simgrip.harness.agreement import MARGIN, agreement_case, method_agreement
from simgrip.reference import elastica
from simgrip import STANDARD, Uniform


def _case(i, grip, kappa, mu_s, **kw):
    return {"id": i, "grip": grip, "D": STANDARD.D, "kappa": kappa, "M": STANDARD.M, "mu_s": mu_s, "b": STANDARD.b,
            "n": 16, "profile": "uniform", "alpha": 0.0, "outcome": "settled", **kw}


def test_margin_is_that_of_the_held_state():
    need = elastica.solve("I", STANDARD, Uniform(-6.0)).required_mu
    rec = agreement_case(_case(0, "I", -6.0, 1.1 * need))
    assert rec["agree"] and rec["newton"] == rec["dynamics"] == "held"
    # 1 - mu_req / mu_s of the held state: 1 - 1/1.1 up to the chain's O(ds^2) and the tip couple
    assert rec["margin_newton"] == pytest.approx(1.0 - 1.0 / 1.1, abs=0.01)


def test_counts_and_lists():
    need = elastica.solve("I", STANDARD, Uniform(-6.0)).required_mu
    cases = [_case(0, "I", -6.0, 1.1 * need), _case(1, "I", -6.0, 0.9 * need),
             _case(2, "free", -3.0, 1.0), _case(3, "I", -6.0, 1.0, outcome="rejected")]
    res = method_agreement(cases)
    assert res["cases"] == 2 and res["agree"] == 2 and res["disagree"] == 0
    assert res["disagree_above_margin"] == [] and res["unsettled"] == []
    assert [r["newton"] for r in res["records"]] == ["held", "dropped"]
    assert 0 < MARGIN < 1
