"""Grips I/II closing (chain start, predicted closing, staged ramp) and Grip III hold/slip."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import elastica
from simgrip.scenes import build_scene
from simgrip.settle import settle
from settle_cases import stress_scene


# ---------------------------------------------------------------------------
# Grip III: hold / slip and condition (23)
#
# MuJoCo's friction cone (and the Newton path's, which uses MuJoCo's contact
# frame) is built on the carrying link's normal; the true normal at gamma is
# rotated from it by d = theta'(gamma) (u - 1/2) ds, u in [0, 1) the position
# of gamma within the link (link angles are midpoint samples).  In the link's
# frame (angle theta - d) the force reads f' = f cos d - n sin d, n' = n cos d
# + f sin d, so mu' = |f'|/n' = mu - sgn(f) (1 + mu^2) d + O(d^2): the hold/slip
# threshold the simulation sees is the BVP's required mu shifted by
#     delta = -sgn(f) (1 + mu^2) theta'(gamma) (u - 1/2) ds,   |delta| <= (1 + mu^2) |theta'| ds / 2,
# first order in ds (0.1 at n = 32, kappa = -5.5: a +-25 % band on mu = 0.40).
# With delta applied the remaining error is O(ds^2): tested at +-2 %.

KAPPA_III_CLEAR = -5.5  # tip clear of the workpiece (condition (23) holds); kappa = -6 violates it


def _iii_threshold(n):
    """BVP's required mu at the simulation's own gamma, and the first-order frame shift ``delta``."""
    st = settle(build_scene("III", STANDARD, Uniform(KAPPA_III_CLEAR), n))
    c = st.contact
    ref = elastica.solve("III", STANDARD.replace(b=2 * c.point[0]), Uniform(KAPPA_III_CLEAR), gamma=c.gamma,
                         contact_moment=c.moment)
    i = min(int(c.gamma * n), n - 1)
    u = c.gamma * n - i
    dtheta = float(np.gradient(st.link_angles[0])[i] * n)  # theta' at the contact link
    mu = ref.required_mu
    sign = -math.copysign(1.0, ref.f)
    delta = sign * (1 + mu**2) * dtheta * (u - 0.5) / n
    bound = (1 + mu**2) * abs(dtheta) / (2 * n)
    return st, mu, delta, bound


def test_grip_iii_contact_frame_threshold_is_the_bvp_shifted_at_first_order():
    errs = []
    for n in (16, 32):
        st, mu, delta, bound = _iii_threshold(n)
        assert st.tip_clear
        shift = st.contact.required_mu_contact - mu
        assert abs(shift) <= bound  # first-order band
        errs.append(abs(shift - delta) / mu)
    assert max(errs) < 0.02  # what is left is second order


@pytest.mark.parametrize("method", ["newton", "dynamics"])
def test_grip_iii_holds_and_slips_around_the_shifted_threshold(method):
    n = 32
    st0, mu, delta, bound = _iii_threshold(n)
    gamma0 = st0.contact.gamma

    def run(mu_s):
        st = settle(build_scene("III", STANDARD.replace(mu_s=mu_s), Uniform(KAPPA_III_CLEAR), n), method=method)
        slipped = (not st.held) or abs(st.contact.gamma - gamma0) > 1e-4
        return st, slipped

    # the first-order band: held above it, slips below it, whatever gamma's place in its link
    assert not run(mu + bound + 0.02 * mu)[1]
    assert run(mu - bound - 0.02 * mu)[1]
    # with the frame shift applied, +-2 %
    st, slipped = run((mu + delta) * 1.02)
    assert not slipped and st.tip_clear
    assert run((mu + delta) * 0.98)[1]


@pytest.mark.parametrize("method", ["newton", "dynamics"])
def test_grip_iii_flags_a_tip_that_reaches_the_workpiece(method):
    # past condition (23)'s onset the rod beyond the corner comes back up through the box's bottom face
    # (the scene has no contact pair there): flagged, and an impossible state is not a grip (issue 17)
    bad = settle(build_scene("III", STANDARD, Uniform(-6.0), 32), method=method)
    assert not bad.tip_clear and not bad.valid and not bad.held
    assert any("condition (23)" in w for w in bad.warnings)
    assert any("invalid state" in w and "inside the workpiece" in w for w in bad.warnings)
    good = settle(build_scene("III", STANDARD, Uniform(KAPPA_III_CLEAR), 32), method=method)
    assert good.tip_clear and not good.warnings


def _same_grip_state(a, b, tol=1e-9):
    """Same hold/drop, finger shape and contact forces (the workpiece's height on its face is
    where the closing path put it: the ramp slides the tip along the face, the chain start
    places the workpiece at the tip)."""
    assert a.held == b.held
    assert np.max(np.abs(a.joint_angles - b.joint_angles)) < tol
    assert abs(a.N1 - b.N1) < 1e-7 and abs(a.N2 - b.N2) < 1e-7


@pytest.mark.parametrize("grip,kappa,n", [("I", -6.0, 16), ("I", -4.0, 32), ("II", 5.0, 32)])
def test_chain_start_equals_the_ramped_closing(monkeypatch, grip, kappa, n):
    """Grips I/II from the hinge chain's equilibrium reach the staged ramp's state in a few iterations."""
    import simgrip.settle.closing as S

    fast = settle(build_scene(grip, STANDARD, Uniform(kappa), n))
    monkeypatch.setattr(S, "CHAIN_START", False)
    monkeypatch.setattr(S, "_close_predicted", lambda *a, **k: False)
    ramp = settle(build_scene(grip, STANDARD, Uniform(kappa), n))
    _same_grip_state(fast, ramp)
    assert fast.newton_iterations < 0.3 * ramp.newton_iterations


@pytest.mark.parametrize("grip,kappa,n", [("I", -6.0, 16), ("I", -4.0, 32), ("II", 5.0, 32)])
def test_predicted_closing_equals_the_ramped_closing(monkeypatch, grip, kappa, n):
    """The predicted closing (chain stages + MuJoCo's last stage) reaches the ramp's state.

    The settled state -- the workpiece's height on its face included -- and the hold/drop
    decision are those of the staged MuJoCo ramp, in ~half the Newton iterations.
    """
    import simgrip.settle.closing as S

    monkeypatch.setattr(S, "CHAIN_START", False)
    fast = settle(build_scene(grip, STANDARD, Uniform(kappa), n))
    monkeypatch.setattr(S, "_close_predicted", lambda *a, **k: False)
    ramp = settle(build_scene(grip, STANDARD, Uniform(kappa), n))
    assert fast.held == ramp.held
    assert np.max(np.abs(fast.qpos - ramp.qpos)) < 1e-9
    assert abs(fast.N1 - ramp.N1) < 1e-7 and abs(fast.N2 - ramp.N2) < 1e-7
    assert fast.newton_iterations < 0.6 * ramp.newton_iterations


def test_closing_falls_back_to_the_ramp(monkeypatch):
    """An unusable chain start and prediction (here: the chain solver fails) leave the staged ramp in charge."""
    import simgrip.reference.chain_start as chain_start
    import simgrip.reference.hinge_chain as D

    ref = settle(build_scene("I", STANDARD, Uniform(-6.0), 16))

    def boom(*a, **k):
        raise D.DiscreteError("no")

    monkeypatch.setattr(D, "solve_chain", boom)
    monkeypatch.setattr(chain_start, "grip_start", boom)  # (the chain start's own solve)
    st = settle(build_scene("I", STANDARD, Uniform(-6.0), 16))
    assert st.held and st.newton_iterations > ref.newton_iterations
    _same_grip_state(st, ref)


def test_closing_hands_a_folding_path_to_the_chain(monkeypatch):
    """Stress case whose ramp fails at its last stage (the closing falls back to the chain's grip
    equilibrium): chain start, predictor and ramp all end at the same state."""
    import simgrip.settle.closing as S

    sc = stress_scene("I", 20.04, -8.05, 18.76, 0.215, 0.688, 7)
    fast = settle(sc)
    monkeypatch.setattr(S, "CHAIN_START", False)
    pred = settle(sc)
    monkeypatch.setattr(S, "_close_predicted", lambda *a, **k: False)
    ramp = settle(sc)
    assert pred.held == ramp.held and np.max(np.abs(pred.qpos - ramp.qpos)) < 1e-9
    _same_grip_state(fast, ramp)
