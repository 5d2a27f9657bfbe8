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


# --- issue 16 section 6: the audit's planar groups (unreached face, wrong branch, cone, fallback, tip contact) ---


@pytest.mark.parametrize("grip,kappa,D,M", [("I", -1.0, 1.0, 1e4), ("I", 5.0, 1e-2, 5.0)])
def test_a_finger_that_does_not_reach_the_face_says_so(grip, kappa, D, M):
    """Both settles drop, the BVP (tip prescribed on the face) holds: the dropped state names why -- its
    unloaded tip lies outside the face, X(l) > b/2, so closing from it the finger never presses on it."""
    p = STANDARD.replace(D=D, M=M, mu_s=100.0)
    for method in ("newton", "dynamics"):
        st = settle(build_scene(grip, p, Uniform(kappa), N), method=method)
        assert not st.held and st.grip_matched and st.tip[0, 0] > 0.5 * p.b
        assert any(w.startswith("not held: the unloaded finger's tip") for w in st.warnings), st.warnings
    assert elastica.solve(grip, p, Uniform(kappa)).feasible  # the BVP holds: the disagreement is the named one


def test_a_reached_face_is_not_warned():
    st = settle(build_scene("I", STANDARD.replace(mu_s=0.1), Uniform(-6.0), N))  # dropped by friction
    assert not st.held and st.tip[0, 0] < 0.5 * STANDARD.b
    assert not any("unloaded finger" in w for w in st.warnings)


def test_grip_ii_bvp_in_grip_is_shape_is_not_feasible():
    """Grip II at D = 1e-2, kappa = 3.5, mu_s = 100: the BVP's 'held' solution hangs below the palm (Grip I's
    shape, Y(l) = -0.94), which the settle calls 'wrong grip'; the BVP says not feasible too."""
    p = STANDARD.replace(D=1e-2, mu_s=100.0)
    sol = elastica.solve("II", p, Uniform(3.5))
    assert sol.tip[1] < 0 and sol.feasibility["contact"] and sol.feasibility["friction"]
    assert sol.feasibility["grip_shape"] is False and not sol.feasible
    res = compare("II", p, Uniform(3.5), N)
    assert not res["simulation"]["feasible"] and not res["reference"]["feasible"] and res["warnings"] == []


def test_the_reference_follows_the_settled_branch():
    """Grip I, kappa = -6, D = 1e4, b = 0.02: the settle holds (tip Y = -2e-4, N = 14385); the cold BVP landed on
    another branch (tip Y = +0.85, n = -1.5e5: 'dropped').  Started from the settled chain it is the same
    equilibrium (tips within the chain's O(1/n^2) error) and holds."""
    from simgrip.compare import branch_warnings

    p = STIFF.replace(b=0.02)
    res = compare("I", p, Uniform(-6.0), N)
    sim, ref = res["simulation"], res["reference"]
    # issue 17: this stiff loop (a circle of radius 1/6 pinned on a face 0.01 l from the palm) runs through the
    # workpiece and its tip through the finger's own base: both the state and its reference are impossible
    assert not sim["valid"] and not sim["feasible"] and not ref["valid"] and not ref["feasible"]
    assert res["warnings"] and all(w.startswith("the reference itself crosses itself") for w in res["warnings"])
    assert abs(sim["tip"][1] - ref["tip"][1]) < 1.0 / N**2  # within the chain's O(1/n^2) error: the same branch
    assert ref["normal_force"] == pytest.approx(sim["normal_force"], rel=5e-3)
    cold = elastica.solve("I", p, Uniform(-6.0), contact_moment=sim["contact_moment"])
    assert cold.tip[1] > 0.5 and not cold.feasible  # the other branch, which the check names
    (w,) = branch_warnings(sim["tip"], N, cold)
    assert w.startswith("the reference converged to another equilibrium branch")


def test_the_grip_iii_reference_follows_the_settled_branch():
    """Grip III, kappa = -10, D = 1e-2, M = 5, mu_s = 100: Newton holds; at its gamma the cold BVP found another
    shape with n < 0 (dropped); from the settled chain the reference holds too."""
    res = compare("III", STANDARD.replace(D=1e-2, mu_s=100.0), Uniform(-10.0), N)
    assert res["simulation"]["feasible"] and res["reference"]["feasible"]
    assert not any("another equilibrium branch" in w for w in res["warnings"])


def test_grip_iii_at_the_friction_cone_says_so():
    """Grip III, kappa = -4, D = 1, M = 0, mu_s = 1: Newton's corner contact saturates in MuJoCo's frame (the
    carrying link's) while the rod's frame needs 1.108: held, with the cone's edge named (the BVP drops)."""
    st = settle(build_scene("III", STANDARD.replace(M=0.0), Uniform(-4.0), N))
    assert st.held and st.contact.required_mu > 1.0
    assert any(w.startswith("held at the friction cone's edge") for w in st.warnings), st.warnings


def test_weightless_frictionless_planar_state_says_so():
    st = settle(build_scene("I", STANDARD.replace(D=1e-2, M=0.0, mu_s=0.0), Uniform(-1.0), N))
    assert any("M = 0 with mu_s = 0" in w for w in st.warnings)


def test_the_default_falls_back_to_the_dynamics_where_newton_fails():
    """Grip III, kappa = -7, D = 1e-2, M = 1e4: Newton stops at max_iter.  The default (no method) answers with
    the dynamics and says so; an explicit method='newton' stays strict."""
    from simgrip.compare import simulate

    p = STANDARD.replace(D=1e-2, M=1e4)
    with pytest.raises(SettleError, match="max_iter"):
        simulate("III", p, Uniform(-7.0), N, method="newton")
    st = simulate("III", p, Uniform(-7.0), N)
    assert st.method == "dynamics" and st.converged
    assert st.warnings[0].startswith("the default settle (Newton) failed (settle did not converge (max_iter")
    with pytest.raises(SettleError, match="max_iter"):  # the point contact is Newton's only: no fallback
        simulate("III", p, Uniform(-7.0), N, contact="point")


def test_a_grip_iii_contact_at_the_tip_has_no_reference(capsys):
    """``simgrip compare III --kappa -7 --gamma 0.97`` exited 2 ('gamma must lie in (0, 1), got 1.0'): the
    settled contact is at the tip.  Now the state and the comparison say so, and there is no reference."""
    from simgrip.cli import main
    from simgrip.compare import reference_for
    from simgrip.reference.bvp import ElasticaError

    p = STANDARD.replace(gamma=0.97)
    res = compare("III", p, Uniform(-7.0), N)
    sim, ref = res["simulation"], res["reference"]
    assert sim["held"] and sim["gamma"] == 1.0
    assert any("contact is at the tip" in w for w in sim["warnings"])
    assert ref["available"] is False and res["difference"] == {}
    assert res["warnings"][0].startswith("no reference: the simulation's contact is at the tip")
    st = settle(build_scene("III", p, Uniform(-7.0), N))
    with pytest.raises(ElasticaError, match="no reference"):
        reference_for(st, p, Uniform(-7.0))
    assert main(["compare", "III", "--kappa", "-7", "--gamma", "0.97"]) == 0
    out = capsys.readouterr().out
    assert "WARNING: no reference" in out and "Traceback" not in out


def test_compare_fingers_reference_is_on_the_settled_branch_and_warns_as_the_planar():
    """The K-finger compare had the planar one's wrong branch (I, kappa = -6, D = 1e4, b = 0.02: the BVP
    'dropped' with n = -1.5e5) and no warnings; it now follows finger 0's settled shape and carries the
    planar compare's verdict warnings."""
    from simgrip.gripper.compare import compare_gripper

    res = compare_gripper("I", STIFF.replace(b=0.02), Uniform(-6.0), N, fingers=2, workpiece="box")
    sim, ref = res["simulation"], res["reference"]
    # issue 17: the stiff loop runs through the box and its own base (see the planar test above): both impossible
    assert not sim["valid"] and not sim["feasible"] and not ref["valid"] and not ref["feasible"]
    assert res["warnings"] and all(w.startswith("the reference itself crosses itself") for w in res["warnings"])
    assert ref["normal_force"] == pytest.approx(sim["normal_force"], rel=5e-3)
    low = compare_gripper("I", STANDARD.replace(mu_s=0.1), Uniform(-6.0), 8, fingers=2, workpiece="box")
    assert not low["simulation"]["feasible"] and not low["reference"]["feasible"] and low["warnings"] == []


@pytest.mark.parametrize("kappa,D,mu", [(-10.0, 1e4, 1.0), (-2.0, 1e-2, 100.0)])
def test_a_grip_iii_finger_that_does_not_reach_the_corner_says_so(kappa, D, mu):
    """Both settles drop, the BVP holds with the rod pressed out to the corner at X(gamma) = b/2 (kappa = -10,
    D = 1e4: a curl of radius 0.1 l, n = 5e5): the dropped state says its unloaded rod ends short of the corner."""
    p = STANDARD.replace(D=D, mu_s=mu)
    for method in ("newton", "dynamics"):
        st = settle(build_scene("III", p, Uniform(kappa), N), method=method)
        assert not st.held and st.nodes[0][:, 0].max() < 0.5 * p.b
        assert any(w.startswith("not held: the unloaded finger reaches at most") for w in st.warnings), st.warnings
    assert elastica.solve("III", p, Uniform(kappa)).feasible
