"""A settled state is the grip asked for, or says loudly that it is not (issue 12, item 1)."""

from __future__ import annotations

import pytest

from simgrip import STANDARD, Uniform
from simgrip.compare import compare
from simgrip.scenes import build_scene
from simgrip.settle import settle


@pytest.mark.parametrize("method", ["newton", "dynamics"])
@pytest.mark.parametrize("grip,kappa,other", [("I", 5.0, "II"), ("II", -5.5, "I")])
def test_a_state_in_the_other_grips_shape_is_not_held(grip, kappa, other, method):
    """``simgrip compare I --kappa 5 --links 32`` settled a Grip II shape and said ``held: true``."""
    st = settle(build_scene(grip, STANDARD, Uniform(kappa), 32), method=method)
    assert not st.held and not st.grip_matched
    assert any(w.startswith(f"wrong grip: finger 0 settled in Grip {other}'s shape") for w in st.warnings)


def test_compare_reports_the_wrong_grip():
    res = compare("I", STANDARD, Uniform(5.0), 32)
    sim = res["simulation"]
    assert sim["held"] is False and sim["feasible"] is False
    assert any("wrong grip" in w for w in sim["warnings"])


@pytest.mark.parametrize("grip,kappa", [("I", -6.0), ("II", 5.0)])
def test_the_grip_asked_for_is_held(grip, kappa):
    st = settle(build_scene(grip, STANDARD, Uniform(kappa), 16))
    assert st.held and st.grip_matched and not st.warnings
