"""settle(method="dynamics"): over-damped MuJoCo dynamics against the static settle and the BVP."""

from __future__ import annotations


import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import elastica, solve_chain
from simgrip.scenes import build_scene
from simgrip.settle import SettleError, settle, settle_sweep
from settle_cases import GRIP_III_SLIDE_OFF, KAPPA, PEN_LIMIT, stress_scene


# ---------------------------------------------------------------------------
# method="dynamics": over-damped MuJoCo dynamics with MuJoCo's own contact and friction
#
# Tolerances:
# * free rod: no contact, so the dynamic settle is limited only by its stopping
#   tolerance (tol = 1e-10 -> angles to ~1e-10 of the chain minimiser);
# * grips: MuJoCo's soft contact at rest penetrates p ~ 3e-5 - 6e-5 l with the
#   automatic step (the Newton path: 7e-7 l); the centreline meets the face at
#   b/2 - p, so the shape differs from the Newton settle by O(p) (measured
#   ~3 p in angle) and N1 by ~p; the friction creep floor (impratio 1e4)
#   leaves ~1e-5 of the weight unbalanced, which is the residual tolerance.


@pytest.fixture(scope="module")
def dyn_states():
    out = {}
    for grip in ("I", "II", "III"):
        for n in (16, 32):
            out[grip, n] = settle(build_scene(grip, STANDARD, Uniform(KAPPA[grip]), n), method="dynamics")
    return out


@pytest.mark.parametrize("kappa", [-4.0, 3.0])
def test_dynamics_free_rod_equals_chain_minimiser(kappa):
    steps = []
    for n in (8, 32):
        st = settle(build_scene("free", STANDARD, Uniform(kappa), n), method="dynamics", tol=1e-10)
        ch = solve_chain("free", STANDARD, Uniform(kappa), n)
        assert st.converged and st.method == "dynamics" and st.residual < 1e-10
        np.testing.assert_allclose(st.link_angles[0], ch.link_angles, rtol=0, atol=1e-9)
        np.testing.assert_allclose(st.tip[0], ch.tip, rtol=0, atol=1e-9)
        steps.append(st.steps)
    # the damping is proportional to the hinge stiffness: the over-damped flow is
    # preconditioned by it, so the step count does not grow with n
    assert max(steps) < 60 and abs(steps[0] - steps[1]) <= 3


@pytest.mark.parametrize("grip", ["I", "II"])
def test_dynamics_grip_matches_newton_settle_and_bvp(surface_states, dyn_states, grip):
    for n in (16, 32):
        st, nw = dyn_states[grip, n], surface_states[grip, n]
        assert st.held and st.converged and st.method == "dynamics"
        assert st.penetration < PEN_LIMIT
        assert st.residual < 1e-5 and st.velocity < 1e-6
        c = st.contact
        assert c.N2 == pytest.approx(-STANDARD.M, rel=1e-5)  # MuJoCo's friction carries the weight
        np.testing.assert_allclose(st.link_angles, nw.link_angles, atol=5 * st.penetration)  # penetration-limited
        assert c.N1 == pytest.approx(nw.N1, rel=5 * st.penetration)
    # against the BVP the dynamic settle is as good as the Newton one (discretisation-limited)
    c32 = dyn_states[grip, 32].contact
    ref = elastica.solve(grip, STANDARD, Uniform(KAPPA[grip]), contact_moment=c32.moment)
    st = dyn_states[grip, 32]
    assert abs(st.N1 / ref.N1 - 1) < 5e-3 and abs(st.tip[0, 1] - ref.tip[1]) < 1e-3
    assert abs(st.required_mu / ref.required_mu - 1) < 5e-3


def test_dynamics_grip_iii_matches_newton_settle(surface_states, dyn_states):
    for n in (16, 32):
        st, nw = dyn_states["III", n], surface_states["III", n]
        assert st.held and st.converged and st.penetration < PEN_LIMIT
        assert st.contact.gamma == pytest.approx(nw.contact.gamma, abs=1e-5)
        np.testing.assert_allclose(st.link_angles, nw.link_angles, atol=5 * st.penetration)
        assert st.contact.normal == pytest.approx(nw.contact.normal, rel=1e-4)
        assert st.contact.friction == pytest.approx(nw.contact.friction, rel=1e-4)


@pytest.mark.parametrize("grip", ["I", "II"])
def test_dynamics_hold_and_drop_follow_the_friction_criterion(dyn_states, grip):
    """Held just above, dropped just below the required mu of the chain the MuJoCo finger is, solved at
    the dynamics' own tip X and couple: MuJoCo's elliptic cone (impratio 1e4) creeps and leaves at most
    the residual tolerance (1e-5, i.e. 2e-6 of the weight M = 5) unbalanced, so its threshold is the
    chain's to ~2e-6 (measured 2e-7 - 6e-7; asserted < 1e-5); below it the tip must also slide
    DYN_DROP_SLIP within the step budget, which takes ~eps^-1/2 (2,800-4,600 steps at eps = 1e-3 and
    3e-4): tested at +-1e-3 (derivation: tests/test_hold_band.py), so a cone 1 % too generous fails.
    The BVP's mg/N is 0.3 % (I) / 0.1 % (II) off the n = 16 chain (second order)."""
    st = dyn_states[grip, 16]
    moment = st.contact_moment
    chain = solve_chain(grip, STANDARD.replace(b=2 * st.tip[0, 0]), Uniform(KAPPA[grip]), 16, contact_moment=moment)
    need = -chain.N2 / chain.N1
    assert abs(st.required_mu / need - 1) < 1e-5
    bvp = elastica.solve(grip, STANDARD, Uniform(KAPPA[grip]), contact_moment=moment).required_mu
    assert abs(need / bvp - 1) < 5e-3  # second order in ds
    for factor, held in ((1 + 1e-3, True), (1 - 1e-3, False)):
        st = settle(build_scene(grip, STANDARD.replace(mu_s=need * factor), Uniform(KAPPA[grip]), 16),
                    method="dynamics")
        assert st.held is held and st.converged
        if not held:
            free = solve_chain("free", STANDARD, Uniform(KAPPA[grip]), 16)
            np.testing.assert_allclose(st.link_angles[0], free.link_angles, atol=1e-5)


def test_dynamics_two_fingers_agree_with_the_symmetric_reduction(dyn_states):
    for grip in ("I", "III"):
        one = dyn_states[grip, 16]
        two = settle(build_scene(grip, STANDARD, Uniform(KAPPA[grip]), 16, fingers=2), method="dynamics")
        assert two.held and two.converged
        np.testing.assert_allclose(two.link_angles, np.vstack([one.link_angles] * 2), atol=5 * one.penetration)
        for c in two.contacts:
            assert c.N1 == pytest.approx(one.N1, rel=1e-4)
        assert two.workpiece_pose[0] == pytest.approx(0.0, abs=1e-9)  # centred
        assert two.workpiece_pose[2] == pytest.approx(0.0, abs=1e-9)  # level


def test_dynamics_is_fast_at_n32_grip_i(dyn_states):
    # physics steps, not wall time (the machine is shared): closing ramp ~120, release ~80
    assert dyn_states["I", 32].steps < 600
    assert dyn_states["I", 32].timestep > 0


@pytest.mark.parametrize("grip,kappa", [("II", 5.5), ("II", 6.0), ("I", -8.0)])
def test_dynamics_holds_where_newton_holds_far_inside_the_cone(grip, kappa):
    """Stress run: Grip II at kappa 5.5-6 (standard parameters, margin ~0.6) was dropped by the dynamics.
    The chain start already carries the weight by friction; fading a holding force out on top of it
    pushed the workpiece up off the tip.  Same tolerances as above (penetration-limited)."""
    st = settle(build_scene(grip, STANDARD, Uniform(kappa), 16), method="dynamics")
    nw = settle(build_scene(grip, STANDARD, Uniform(kappa), 16), contact="surface")
    assert st.held and nw.held and st.converged
    assert st.penetration < PEN_LIMIT  # bounds the penetration-limited tolerance below (5e-4 at most)
    assert st.N1 == pytest.approx(nw.N1, rel=5 * st.penetration)


def test_dynamics_drop_is_confirmed_at_half_the_step():
    """Stress case 301: a heavy workpiece on a soft finger starts a growing two-step oscillation of the
    contact at h = 1/omega_min and is thrown off the tip; at h/2 it holds, as Newton says (margin 0.4)."""
    from simgrip.harness.stress_cases import stress_profile
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=0.047019033657647105, M=3.520487155765295, b=0.9036905963160098,
                            mu_s=3.0996078049733544)
    prof = stress_profile("wiggle", -5.4611229076981544, 0.3391074314713478)
    st = settle(build_scene("I", p, prof, 59), method="dynamics")
    nw = settle(build_scene("I", p, prof, 59), contact="surface")
    assert st.held and nw.held and st.converged
    assert st.penetration < PEN_LIMIT  # bounds the penetration-limited tolerance below (5e-4 at most)
    assert st.N1 == pytest.approx(nw.N1, rel=5 * st.penetration)


def test_dynamics_drop_stands_when_half_the_step_finds_no_rest():
    """Stress case 185 (Newton: dropped): dropped at h; at h/2 the workpiece creeps without coming to
    rest, so the drop found at h stands (it ran into SettleError after 20,000 steps)."""
    from simgrip.harness.stress_cases import stress_profile
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=23.007131811614286, M=32.70052154548466, b=0.235918826200068,
                            mu_s=0.12503840796246268)
    prof = stress_profile("step", 8.980936512351036, 6.964660443365574)
    st = settle(build_scene("II", p, prof, 14), method="dynamics")
    assert st.converged and not st.held and not settle(build_scene("II", p, prof, 14)).held
    np.testing.assert_allclose(st.link_angles[0], solve_chain("free", p, prof, 14).link_angles, atol=1e-5)


def test_dynamics_grip_iii_settles_in_few_steps(dyn_states):
    # the fall guard's extra damping (~20 x h K at the standard case) is lifted near rest: the
    # over-damped flow D = h K contracts every mode by about 1/2 per step (320 steps with the guard)
    for n in (16, 32):
        assert dyn_states["III", n].steps < 100


@pytest.mark.parametrize("grip,D,kappa", [("III", 0.06, -6.0), ("II", 0.06, 5.0)])
def test_dynamics_soft_drops_come_to_rest_as_newton_says(grip, D, kappa):
    """Issue 9: these two ran into SettleError after 20,000 steps (the workpiece crept down the soft
    rod); both methods now agree: dropped, the finger at the chain's free equilibrium."""
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=D)
    st = settle(build_scene(grip, p, Uniform(kappa), 32), method="dynamics")
    nw = settle(build_scene(grip, p, Uniform(kappa), 32))
    assert st.converged and not st.held and not nw.held
    free = solve_chain("free", p, Uniform(kappa), 32)
    np.testing.assert_allclose(st.link_angles[0], free.link_angles, atol=1e-5)


def test_dynamics_warm_started_sweep_matches_cold():
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    sweep = settle_sweep(sc, [Uniform(k) for k in (-6.0, -7.0)], method="dynamics")
    cold = settle(build_scene("I", STANDARD, Uniform(-7.0), 16), method="dynamics")
    assert all(s.held for s in sweep)
    assert sweep[-1].N1 == pytest.approx(cold.N1, rel=1e-4)
    np.testing.assert_allclose(sweep[-1].link_angles, cold.link_angles, atol=1e-4)


def test_dynamics_restores_the_scene_and_is_deterministic():
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    m = sc.model
    before = (int(m.opt.integrator), float(m.opt.timestep), float(m.opt.impratio), m.dof_damping.copy(),
              m.pair_dim.copy(), m.pair_solref.copy(), int(m.opt.disableflags))
    a = settle(sc, method="dynamics")
    after = (int(m.opt.integrator), float(m.opt.timestep), float(m.opt.impratio), m.dof_damping, m.pair_dim,
             m.pair_solref, int(m.opt.disableflags))
    assert before[:3] == after[:3] and before[6] == after[6]
    for x, y in zip(before[3:6], after[3:6]):
        np.testing.assert_array_equal(x, y)
    b = settle(build_scene("I", STANDARD, Uniform(-6.0), 16), method="dynamics")
    np.testing.assert_array_equal(a.qpos, b.qpos)


def test_dynamics_non_convergence_and_bad_method():
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    with pytest.raises(SettleError):
        settle(sc, method="dynamics", max_steps=3)
    st = settle(sc, method="dynamics", max_steps=3, allow_unconverged=True)
    assert not st.converged and st.steps <= 3
    with pytest.raises(ValueError, match="method"):
        settle(sc, method="verlet")


def test_dynamics_settle_is_bounded_by_max_steps():
    # stress id 458 (Grip III, n = 21): a budget below what the settle needs stops it, with a clear error
    sc = stress_scene("III", **GRIP_III_SLIDE_OFF[1])
    need = settle(sc, method="dynamics", allow_unconverged=True).steps
    budget = max(1, need // 2)
    with pytest.raises(SettleError, match="max_steps"):
        settle(sc, method="dynamics", max_steps=budget)
    st = settle(sc, method="dynamics", max_steps=budget, allow_unconverged=True)
    assert not st.converged and st.steps <= budget


def test_every_dynamic_state_is_within_tolerance(dyn_states):
    for st in dyn_states.values():
        assert st.converged and st.residual <= st.tolerance, (st.grip, st.links, st.method)

