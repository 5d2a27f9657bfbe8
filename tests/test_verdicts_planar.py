"""Hold/drop verdicts of the planar finger against the BVP (issue 16, section 6, first two items).

Tolerances, derived rather than tuned:

* the settled state is the hinge chain's equilibrium up to the contact depth
  ``p <= PEN_STIFFEN = 1e-5 l`` (the centreline meets the face at ``b/2 - p``):
  its normal force differs from the chain's by at most the chain's own change
  when the face moves by ``p`` -- measured here by solving the chain at
  ``b - 2 PEN_STIFFEN`` (the settle's error bound);
* the chain differs from the BVP by its discretisation error (second order,
  ``~7e-4`` relative at ``n = 32`` for these cases), so the simulation's force
  is within that error plus the settle's bound of the BVP's.
"""

from __future__ import annotations

import pytest

from simgrip import STANDARD, Uniform
from simgrip.compare import compare, verdict_warnings
from simgrip.reference import elastica, solve_chain
from simgrip.scenes import build_scene
from simgrip.settle import SettleError, settle
from simgrip.settle.newton import PEN_STIFFEN, Newton

N = 32
STIFF = STANDARD.replace(D=1e4)


def _settle_bound(grip, params, kappa, n):
    """Relative change of the chain's normal force when the face moves by the largest settle depth."""
    a = solve_chain(grip, params, Uniform(kappa), n)
    b = solve_chain(grip, params.replace(b=params.b - 2 * PEN_STIFFEN), Uniform(kappa), n)
    return a, abs(b.N1 / a.N1 - 1.0)


@pytest.mark.parametrize("grip,kappa", [("I", -5.5), ("II", 5.0)])
def test_stiff_finger_holds_with_the_bvps_force(grip, kappa):
    """``compare I --kappa -5.5 --D 1e4 --links 32`` said not held (tip at x = -0.128: the release ran out of
    iterations with the tip pressed 4e-3 l deep, past its radius, and was reported as a drop)."""
    res = compare(grip, STIFF, Uniform(kappa), N)
    sim, ref = res["simulation"], res["reference"]
    assert sim["held"] and sim["converged"] and sim["feasible"] and ref["feasible"]
    assert sim["warnings"] == [] and res["warnings"] == []
    assert sim["penetration"] <= PEN_STIFFEN
    assert sim["tip"][0] == pytest.approx(0.5 * STIFF.b, abs=PEN_STIFFEN)  # the tip on the face, not past it
    chain, bound = _settle_bound(grip, STIFF, kappa, N)
    assert abs(sim["normal_force"] / chain.N1 - 1.0) <= bound
    disc = abs(chain.N1 / ref["normal_force"] - 1.0)  # the n = 32 chain's discretisation error
    assert disc < 1e-3
    assert abs(sim["normal_force"] / ref["normal_force"] - 1.0) <= disc + bound


def test_moderately_stiff_finger_touches_the_face_where_the_bvp_does():
    """D = 3000 agreed on the verdict, but its contact was 1.1e-3 l deep (the tip 1.1e-3 l inside b/2)."""
    st = settle(build_scene("I", STANDARD.replace(D=3000.0), Uniform(-5.5), N))
    assert st.held and st.contact_ok and st.penetration <= PEN_STIFFEN
    assert st.tip[0, 0] == pytest.approx(0.5 * STANDARD.b, abs=PEN_STIFFEN)


def test_three_stiff_fingers_hold():
    """``simulate I --kappa -5.5 --D 1e4 --fingers 3`` (the K-finger settle replicates the planar one)."""
    from simgrip.gripper import simulate_gripper

    st = simulate_gripper("I", STIFF, Uniform(-5.5), N, fingers=3, workpiece="cylinder")  # the CLI's default
    assert st.held and st.converged
    chain, bound = _settle_bound("I", STIFF, -5.5, N)
    for r in st.records:
        assert abs(r.N1 / chain.N1 - 1.0) <= bound


def test_a_release_that_fails_is_not_reported_as_a_drop(monkeypatch):
    """Without the stiffening the D = 1e4 release runs out of iterations: that is a failed solve (an error, or
    ``converged=False``), never 'not held' with the finger through the box."""
    monkeypatch.setattr(Newton, "stiffen", lambda self, N, **k: False)
    sc = build_scene("I", STIFF, Uniform(-5.5), N)
    with pytest.raises(SettleError, match="did not converge"):
        settle(sc)
    st = settle(build_scene("I", STIFF, Uniform(-5.5), N), allow_unconverged=True)
    assert not st.converged


def test_a_contact_pressed_past_half_its_radius_is_flagged(monkeypatch):
    """Without the stiffening, D = 3000 settles 1.1e-3 l deep (more than half of r_tip = 2e-3 l): the state
    says so and the comparison does not call it feasible."""
    monkeypatch.setattr(Newton, "stiffen", lambda self, N, **k: False)
    res = compare("I", STANDARD.replace(D=3000.0), Uniform(-5.5), N)
    sim = res["simulation"]
    assert sim["held"] and sim["contact_ok"] is False and not sim["feasible"]
    assert any("deep" in w and "not a surface contact" in w for w in sim["warnings"])
    assert any("verdicts disagree" in w for w in res["warnings"])  # the reference holds: flagged, not silent


def test_a_tip_past_the_face_is_flagged():
    """The geometric check (whether or not MuJoCo reports the contact): a tip centre inside the face."""
    from simgrip.validity import check_contact_depth

    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    st = settle(sc)
    assert st.held and st.contact_ok
    st.tip[0, 0] = float(sc.box_half[0]) / sc.length - 1e-6
    check_contact_depth(sc, st)
    assert not st.contact_ok and any("passed the workpiece's face" in w for w in st.warnings)


@pytest.mark.parametrize("b", [0.1, 0.05, 0.0201])
def test_grip_iii_tip_above_the_contact_is_not_feasible(b):
    """``compare III --kappa -4 --b 0.1``: the tip curls up beyond the box (x = -0.144, half-width 0.05) above
    the contact; the BVP's condition (23) says not feasible, and so must the simulation (it said feasible)."""
    p = STANDARD.replace(b=b)
    res = compare("III", p, Uniform(-4.0), N)
    sim, ref = res["simulation"], res["reference"]
    assert sim["held"] and not sim["tip_clear"] and not sim["feasible"]
    assert not ref["tip_clear"] and not ref["feasible"]
    assert sim["tip"][0] < -0.5 * b and sim["tip"][1] > sim["contact"][1]
    assert any("condition (23) violated" in w and "palm axis" in w for w in sim["warnings"])
    assert res["warnings"] == []  # the verdicts agree


def test_grip_iii_tip_above_the_contact_dynamics():
    res = compare("III", STANDARD.replace(b=0.1), Uniform(-4.0), N, method="dynamics")
    assert res["simulation"]["held"] and not res["simulation"]["feasible"] and not res["reference"]["feasible"]
    assert res["warnings"] == []


def test_grip_iii_tip_below_the_contact_stays_feasible():
    res = compare("III", STANDARD, Uniform(-4.0), N)
    sim = res["simulation"]
    assert sim["tip_clear"] and sim["feasible"] and res["reference"]["feasible"] and sim["warnings"] == []


def test_a_verdict_at_the_edge_is_flagged_not_silent():
    """mu_s between the n = 16 chain's required mu and the BVP's: the simulation holds, the BVP does not (the
    chain's discretisation error decides); the comparison says so."""
    need = compare("I", STANDARD, Uniform(-6.0), 16)
    mu_sim, mu_ref = need["simulation"]["required_mu"], need["reference"]["required_mu"]
    assert mu_sim != pytest.approx(mu_ref, rel=1e-4)
    res = compare("I", STANDARD.replace(mu_s=0.5 * (mu_sim + mu_ref)), Uniform(-6.0), 16)
    assert res["simulation"]["feasible"] != res["reference"]["feasible"]
    (w,) = res["warnings"]
    assert w.startswith("verdicts disagree") and "required mu" in w


def test_verdict_warnings_on_records():
    sim = {"grip": "III", "feasible": True, "held": True, "tip_clear": True, "tip": [-0.1, -0.55],
           "contact": [0.05, -0.57], "required_mu": 0.4, "params": {"mu_s": 1.0}}
    ref = {**sim, "feasible": False, "tip_clear": False}
    out = verdict_warnings(sim, ref)
    assert len(out) == 2 and out[0].startswith("condition (23) disagrees") and "verdicts disagree" in out[1]
    assert verdict_warnings(sim, dict(sim)) == []
    assert verdict_warnings({"grip": "free"}, {"grip": "free", "feasible": False}) == []


def test_weightless_cradle_on_a_stiff_finger_answers():
    """Grip III, D = 1e4, M = 0: MuJoCo weighs the contact by the near-massless workpiece's inverse mass, so it
    is ~1e-10 as stiff as configured and needs a factor ~1e14, beyond the time-constant form's clamp (the
    factor ran away: 'contact set did not settle'; then, clamped, 1e-3 l deep: 'max_iter').  The direct
    (stiffness, damping) form reaches it: the verdicts are the BVP's, the contacts <= PEN_STIFFEN deep."""
    for mu, kappa, feasible in ((0.0, -4.0, False), (100.0, -4.0, True), (100.0, -6.0, False)):
        res = compare("III", STIFF.replace(M=0.0, mu_s=mu), Uniform(kappa), 16)
        sim = res["simulation"]
        assert sim["converged"] and sim["penetration"] <= PEN_STIFFEN
        assert sim["feasible"] is feasible and res["reference"]["feasible"] is feasible and res["warnings"] == []
