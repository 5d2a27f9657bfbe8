"""The K-finger dynamic settle (simgrip.gripper.settle, ``method="dynamics"``) against the planar settle and the BVP.

(The default, ``method="auto"``, settles an exactly symmetric scene by the symmetry skip instead:
tests/test_gripper_symmetry.)

A cylinder (any K) and a box (K = 4) put every finger in the paper's planar
problem: tip on a vertical surface at radius b/2, friction vertical, the
workpiece's weight K M shared equally.  So every finger must read like the
planar one-finger dynamic settle and the BVP.

Tolerances:

* the stop test bounds every row of the static residual at rest by ``tol``
  (``tolerance``: ``max(DYN_TOL, 2e-6 K M)``, MuJoCo's friction creep; hinges over rho g l^2, the workpiece's translation over
  rho g l).  A settled finger is therefore the hinge chain's equilibrium
  (:func:`simgrip.reference.solve_chain`, the MuJoCo finger's own statics) at
  the finger's own tip ``X`` and tip couple, up to the response of the chain
  to a generalised force ``tol`` on every row: ``tol`` times the l1 norm of
  the chain's sensitivities (fixture ``sensitivity``, finite differences; a
  hinge force is a rest-angle shift, the workpiece's vertical row the
  friction).  Two settled states of the same scene (rotated, or another
  finger) differ by at most twice that.  The vertical row bounds
  ``|sum N2 + K M|`` by ``tol``.
* against the BVP, the planar settle is second order in ds, documented at
  n = 32 as ``N1`` within 0.5 % and tip height within 1e-3 l, hence at
  n = 16: 2 % and 4e-3 l (the BVP with the tip couple the settle measured).
* the workpiece's force balance is the residual's translation rows, its
  moment balance the rotation rows: each within ``tol`` (per component).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.chain import ChainSprings, chain_springs
from simgrip.reference import elastica, solve_chain
from simgrip.scenes import build_scene
from simgrip.settle import SettleError, settle
from simgrip.settle.dynamics import DYN_PEN_LIMIT
from simgrip.gripper.settle import GripperState, contact_rest_depth, settle_gripper, straight_frequency
from simgrip.reference.inclined import solve_inclined
from simgrip.gripper.scene import build_gripper

KAPPA = {"I": -6.0, "II": 5.0}
N = 16
PLANAR = [(3, "cylinder"), (4, "cylinder"), (4, "box"), (2, "box")]
#: n = 16 against the BVP: the documented n = 32 bounds times (32/16)^2 (second order).
BVP_N_REL, BVP_TIP = 0.005 * 4, 1e-3 * 4


@pytest.fixture(scope="module")
def planar():
    return {g: settle(build_scene(g, STANDARD, Uniform(KAPPA[g]), N), method="dynamics") for g in KAPPA}


@pytest.fixture(scope="module")
def grippers():
    return {(g, K, w): settle_gripper(build_gripper(g, STANDARD, Uniform(KAPPA[g]), N, fingers=K, workpiece=w),
                                      method="dynamics")
            for g in KAPPA for K, w in PLANAR}


def _chain_at(grip, tip_x, moment, springs=None, M=STANDARD.M, guess=None):
    """The hinge chain (the MuJoCo finger's own statics) with its tip at ``X = tip_x`` and the tip couple ``moment``."""
    return solve_chain(grip, STANDARD.replace(b=2 * tip_x, M=M), Uniform(KAPPA[grip]), N, springs=springs,
                       contact_moment=moment, guess=guess)


def _sensitivity(grip, b=STANDARD.b):
    """How far a static residual of 1 on any row may move ``N1`` and the tip height: ``(s_n, s_y)``.

    A generalised force ``tau`` on hinge ``i`` is a shift ``tau / k_i`` of its rest angle; a vertical
    force ``tau`` on the workpiece changes the friction a finger carries by at most ``tau``.  The bound
    is the l1 norm of the chain's response to a unit force on every row (finite differences), with
    the tip at ``X = b/2``.
    """
    sp = chain_springs(Uniform(KAPPA[grip]), N)
    base = _chain_at(grip, 0.5 * b, 0.0)
    eps = 1e-6
    dn, dy = [], []
    for i in range(N):
        rest = sp.rest.copy()
        rest[i] += eps / (STANDARD.D * sp.stiffness[i])
        ch = _chain_at(grip, 0.5 * b, 0.0, springs=ChainSprings(n=N, ds=sp.ds, stiffness=sp.stiffness, rest=rest,
                                                               nodes=sp.nodes), guess=base.link_angles)
        dn.append((ch.N1 - base.N1) / eps)
        dy.append((ch.tip[1] - base.tip[1]) / eps)
    ch = _chain_at(grip, 0.5 * b, 0.0, M=STANDARD.M + eps, guess=base.link_angles)
    dn.append((ch.N1 - base.N1) / eps)
    dy.append((ch.tip[1] - base.tip[1]) / eps)
    return float(np.sum(np.abs(dn))), float(np.sum(np.abs(dy)))


@pytest.fixture(scope="module")
def sensitivity():
    """Per grip: :func:`_sensitivity` of the planar problem (tip at ``X = b/2``)."""
    return {grip: _sensitivity(grip) for grip in KAPPA}


@pytest.mark.parametrize("grip", ["I", "II"])
@pytest.mark.parametrize("K, shape", PLANAR)
def test_every_finger_is_the_planar_finger(planar, grippers, sensitivity, grip, K, shape):
    """Every finger, and the planar one-finger settle, is the hinge chain at its own tip and tip couple.

    MuJoCo's soft contact gives the K-finger state a slightly different penetration (its impedance
    depends on the contact's effective mass, which includes the free workpiece) and so a slightly
    different tip ``X`` and couple: each state is compared with the chain solved at its own ones,
    within the stop test's residual times the chain's sensitivity.
    """
    st, pl = grippers[grip, K, shape], planar[grip]
    assert isinstance(st, GripperState) and st.held and st.converged and st.residual <= st.tolerance
    assert len(st.records) == K and st.velocity < 1e-6 and st.penetration < DYN_PEN_LIMIT
    s_n, s_y = sensitivity[grip]
    ch = _chain_at(grip, pl.tip[0, 0], pl.contact.moment)
    assert abs(pl.N1 - ch.N1) <= pl.tolerance * s_n and abs(pl.tip[0, 1] - ch.tip[1]) <= pl.tolerance * s_y
    for rec in st.records:
        ch = _chain_at(grip, rec.tip[0], rec.moment)
        assert abs(rec.N1 - ch.N1) <= st.tolerance * s_n
        assert abs(rec.tip[1] - ch.tip[1]) <= st.tolerance * s_y
        assert abs(rec.N2 - pl.N2) <= st.tolerance + pl.tolerance
        assert abs(rec.N3) <= st.tolerance  # nothing out of the finger's plane
        # the tip's centre sits the penetration inside X = b/2
        assert rec.tip[0] == pytest.approx(0.5 * STANDARD.b - rec.penetration, abs=1e-3 * rec.penetration)
        # on a vertical surface the contact normal is E1 and the friction E2
        assert abs(rec.contact_angle) < 1e-6
        turn = abs(rec.contact_angle) * (abs(rec.N1) + abs(rec.N2)) + 1e-12  # the in-plane rotation by that angle
        assert abs(rec.normal - rec.N1) <= turn and abs(rec.friction - rec.N2) <= turn
    # the weight is shared: sum of the vertical forces on the rods is -K M
    assert abs(sum(r.N2 for r in st.records) + K * STANDARD.M) <= st.tolerance


@pytest.mark.parametrize("grip", ["I", "II"])
@pytest.mark.parametrize("K, shape", PLANAR)
def test_every_finger_matches_the_bvp(grippers, grip, K, shape):
    st = grippers[grip, K, shape]
    for rec in st.records:
        ref = elastica.solve(grip, STANDARD, Uniform(KAPPA[grip]), contact_moment=rec.moment)
        assert abs(rec.N1 / ref.N1 - 1) < BVP_N_REL
        assert abs(rec.friction - ref.friction_force) <= st.tolerance
        assert abs(rec.tip[1] - ref.tip[1]) < BVP_TIP
        assert abs(rec.tip[0] - 0.5 * STANDARD.b) <= 2 * rec.penetration  # on the surface, up to MuJoCo's softness
        assert abs(rec.required_mu / ref.required_mu - 1) < BVP_N_REL


@pytest.mark.parametrize("grip", ["I", "II"])
@pytest.mark.parametrize("K, shape", PLANAR + [(3, "sphere"), (5, "sphere")])
def test_workpiece_force_and_moment_balance(grippers, sensitivity, grip, K, shape):
    st = grippers.get((grip, K, shape))
    if st is None:
        st = settle_gripper(build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape),
                            method="dynamics")
    assert st.held and st.converged
    # the reader's contact forces plus the weight are the residual's translation rows
    assert np.max(np.abs(st.force_balance)) <= st.residual + 1e-12 * (1 + st.fingers * STANDARD.M)  # round-off
    assert np.linalg.norm(st.moment_balance) <= math.sqrt(3) * st.tolerance
    # centred and level: every finger pushes alike
    assert np.max(np.abs(st.workpiece_position[:2])) <= st.penetration
    spread = max(r.N1 for r in st.records) - min(r.N1 for r in st.records)
    assert spread <= 2 * st.tolerance * sensitivity[grip][0]


@pytest.mark.parametrize("grip", ["I", "II"])
def test_held_iff_mu_n_reaches_m_per_finger(planar, grip):
    # per finger the criterion is the planar one (mu_s N >= M); the BVP's required mu with the
    # settle's own tip couple, +-2 % around it (MuJoCo's elliptic cone is sharp to +-0.5 %: test_settle_dynamics)
    need = elastica.solve(grip, STANDARD, Uniform(KAPPA[grip]), contact_moment=planar[grip].contact.moment).required_mu
    free = solve_chain("free", STANDARD, Uniform(KAPPA[grip]), N)
    for K, shape in ((3, "cylinder"), (4, "box")):
        for factor, held in ((1.02, True), (0.98, False)):
            st = settle_gripper(build_gripper(grip, STANDARD.replace(mu_s=need * factor), Uniform(KAPPA[grip]), N,
                                              fingers=K, workpiece=shape), method="dynamics")
            assert st.held is held and st.converged, (K, shape, factor)
            if not held:
                assert st.records == []
                for f in range(K):  # the fingers settle alone
                    np.testing.assert_allclose(st.link_angles[f], free.link_angles, atol=1e-5)


def test_out_of_reach_is_not_held():
    # kappa = -1: the free finger's tip stays beyond X = b/2, nothing to hold
    p = STANDARD
    st = settle_gripper(build_gripper("I", p, Uniform(-1.0), N, fingers=3, workpiece="cylinder"), method="dynamics")
    assert not st.held and st.converged and st.records == []
    free = solve_chain("free", p, Uniform(-1.0), N)
    np.testing.assert_allclose(st.link_angles, np.vstack([free.link_angles] * 3), atol=1e-5)


def test_a_finger_that_would_pull_does_not_hold():
    # soft fingers, narrow heavy box: the hinge chain with its tip at X = b/2 under the weight pulls on
    # the face (N1 < 0, as the BVP: infeasible); the planar dynamic settle drops it too
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=0.17, M=9.51, b=0.135, mu_s=1.27)
    assert solve_chain("I", p, Uniform(-2.73), 10).N1 < 0
    assert not settle(build_scene("I", p, Uniform(-2.73), 10), method="dynamics").held
    for K, shape in ((4, "box"), (3, "cylinder")):
        st = settle_gripper(build_gripper("I", p, Uniform(-2.73), 10, fingers=K, workpiece=shape), method="dynamics")
        assert not st.held and st.converged and st.records == []
        free = solve_chain("free", p, Uniform(-2.73), 10)
        np.testing.assert_allclose(st.link_angles, np.vstack([free.link_angles] * K), atol=1e-5)


@pytest.mark.parametrize("K, shape", [(3, "cylinder"), (4, "box"), (3, "sphere")])
def test_invariant_under_rotation_about_the_palm_axis(grippers, sensitivity, K, shape):
    grip = "I"
    a = grippers.get((grip, K, shape)) or settle_gripper(
        build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape), method="dynamics")
    b = settle_gripper(build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape, yaw=0.7),
                       method="dynamics")
    assert b.held and b.converged
    s_n, s_y = sensitivity[grip]
    assert len(a.records) == len(b.records) == K
    for ra, rb in zip(a.records, b.records):
        assert abs(ra.N1 - rb.N1) <= (a.tolerance + b.tolerance) * s_n and abs(ra.N2 - rb.N2) <= a.tolerance + b.tolerance
        assert abs(ra.tip[1] - rb.tip[1]) <= (a.tolerance + b.tolerance) * s_y
        assert abs(ra.contact_angle - rb.contact_angle) <= 1e-6
    # the workpiece turned with the scene: same height, orientation yawed by 0.7
    assert a.workpiece_position[2] == pytest.approx(b.workpiece_position[2], abs=(a.tolerance + b.tolerance) * s_y)
    turn = 2 * math.atan2(b.workpiece_quat[3], b.workpiece_quat[0]) - 2 * math.atan2(a.workpiece_quat[3],
                                                                                    a.workpiece_quat[0])
    assert turn == pytest.approx(0.7, abs=1e-6)


def test_deterministic():
    def run():
        return settle_gripper(build_gripper("II", STANDARD, Uniform(5.0), N, fingers=3, workpiece="sphere"),
                              method="dynamics")

    a, b = run(), run()
    assert np.array_equal(a.qpos, b.qpos) and a.steps == b.steps
    assert [r.N1 for r in a.records] == [r.N1 for r in b.records]


def test_settle_restores_the_model_and_checks_its_arguments():
    sc = build_gripper("I", STANDARD, Uniform(-6.0), 8, fingers=3, workpiece="cylinder")
    m = sc.model
    before = (float(m.opt.timestep), int(m.opt.integrator), int(m.opt.jacobian), m.dof_damping.copy(),
              m.pair_solref.copy())
    st = settle_gripper(sc, method="dynamics")
    assert st.held
    assert (float(m.opt.timestep), int(m.opt.integrator), int(m.opt.jacobian)) == before[:3]
    assert np.array_equal(m.dof_damping, before[3]) and np.array_equal(m.pair_solref, before[4])
    for kw, name in [(dict(tol=0), "tol"), (dict(tol="x"), "tol"), (dict(max_steps=0), "max_steps"),
                     (dict(max_steps=True), "max_steps")]:
        with pytest.raises(ValueError, match=name):
            settle_gripper(sc, **kw, method="dynamics")
    with pytest.raises(ValueError, match="scene"):
        settle_gripper(build_scene("I", STANDARD, Uniform(-6.0), 8), method="dynamics")
    with pytest.raises(SettleError, match="did not converge"):
        settle_gripper(sc, max_steps=5, method="dynamics")
    st = settle_gripper(sc, max_steps=5, allow_unconverged=True, method="dynamics")
    assert not st.converged


@pytest.mark.parametrize("grip, beta", [("I", -0.3), ("I", 0.2), ("II", -0.2)])
def test_sphere_fingers_match_the_inclined_contact_elastica(grip, beta):
    """A sphere held off its equator (simgrip.reference.inclined) at the simulation's own contact angle.

    Each finger is the hinge chain with its tip at its own ``X`` (the rod's problem is Grip I/II at
    width ``b cos beta``, the friction carrying ``M``) to the stop test's residual; against the
    elastica to the second-order bound at n = 16, the normal and friction forces included.
    """
    st = settle_gripper(build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=3, workpiece="sphere",
                                      contact_angle=beta), method="dynamics")
    assert st.held and st.converged and len(st.records) == 3
    s_n, s_y = _sensitivity(grip, 2 * st.records[0].tip[0])
    for rec in st.records:
        b_sim = rec.contact_angle
        # the contact sticks where it started: the sphere sinks by about the penetration
        assert abs(b_sim - beta) <= 2 * rec.penetration / (0.5 * STANDARD.b)
        ch = _chain_at(grip, rec.tip[0], rec.moment)
        assert abs(rec.N1 - ch.N1) <= st.tolerance * s_n and abs(rec.tip[1] - ch.tip[1]) <= st.tolerance * s_y
        assert abs(rec.N2 + STANDARD.M) <= st.tolerance and abs(rec.N3) <= st.tolerance
        # the reader's normal and friction are (N1, N2) in the contact frame
        c, s = math.cos(b_sim), math.sin(b_sim)
        assert rec.normal == pytest.approx(rec.N1 * c + rec.N2 * s, abs=1e-12)
        assert rec.friction == pytest.approx(-rec.N1 * s + rec.N2 * c, abs=1e-12)
        ref = solve_inclined(grip, STANDARD, Uniform(KAPPA[grip]), b_sim, contact_moment=rec.moment)
        assert abs(rec.normal / ref.normal_force - 1) < BVP_N_REL
        assert abs(rec.friction / ref.friction_force - 1) < BVP_N_REL
        assert abs(rec.required_mu / ref.required_mu - 1) < 2 * BVP_N_REL  # a ratio of two such forces
        assert abs(rec.tip[1] - ref.tip[1]) < BVP_TIP
        # the tip centre on the sphere (radius b/2 through the tip centres), up to the penetration
        assert abs(rec.tip[0] - ref.tip[0]) <= 2 * rec.penetration + BVP_TIP * abs(math.tan(b_sim))
    assert abs(st.workpiece_position[2] - ref.centre_height) < BVP_TIP
    assert np.max(np.abs(st.force_balance)) <= st.residual + 1e-12 * (1 + st.fingers * STANDARD.M)  # round-off


@pytest.mark.parametrize("grip, beta", [("I", -0.1), ("II", -0.2)])
def test_sphere_held_iff_the_inclined_cone_holds(grip, beta):
    probe = settle_gripper(build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=3, workpiece="sphere",
                                         contact_angle=beta), method="dynamics")
    rec = probe.records[0]
    need = solve_inclined(grip, STANDARD, Uniform(KAPPA[grip]), rec.contact_angle,
                          contact_moment=rec.moment).required_mu
    for factor, held in ((1.02, True), (0.98, False)):
        st = settle_gripper(build_gripper(grip, STANDARD.replace(mu_s=need * factor), Uniform(KAPPA[grip]), N,
                                          fingers=3, workpiece="sphere", contact_angle=beta), method="dynamics")
        assert st.held is held and st.converged, factor


@pytest.mark.parametrize("grip", ["I", "II"])
def test_every_finger_converges_at_second_order_to_the_bvp(grip):
    """N1, tip height and required mu of every finger fall by 4 per halving of ds (n = 8, 16, 32).

    The reference is the BVP at the finger's own tip ``X`` (``b/2`` less MuJoCo's penetration) and
    tip couple, as ``compare`` does for Grip III; the stop test's share of the error (``tol`` times
    the chain's sensitivity, ~3e-6 relative) is ~1 % of the error at n = 32, so the observed order
    is 2 within the planar test's band (0.15).
    """
    errs = []
    for n in (8, 16, 32):
        st = settle_gripper(build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), n, fingers=3, workpiece="cylinder"),
                            method="dynamics")
        assert st.held and st.converged
        row = []
        for rec in st.records:
            ref = elastica.solve(grip, STANDARD.replace(b=2 * rec.tip[0]), Uniform(KAPPA[grip]),
                                 contact_moment=rec.moment)
            row.append([abs(rec.N1 / ref.N1 - 1), abs(rec.tip[1] - ref.tip[1]),
                        abs(rec.required_mu / ref.required_mu - 1)])
        errs.append(row)
    errs = np.array(errs)  # (resolution, finger, quantity)
    orders = np.log2(errs[:-1] / errs[1:])
    np.testing.assert_allclose(orders, 2.0, atol=0.15)


def test_si_parameters_give_the_dimensionless_state():
    # built in SI (l = 0.1 m, rho = 0.05 kg/m, g = 9.81): every step scales with the model, so the
    # dimensionless state is the one built with l = rho = g = 1, to round-off
    si = settle_gripper(build_gripper("I", STANDARD.to_physical(length=0.1, rho=0.05, g=9.81), Uniform(-6.0), N,
                                      fingers=3, workpiece="cylinder"), method="dynamics")
    one = settle_gripper(build_gripper("I", STANDARD, Uniform(-6.0), N, fingers=3, workpiece="cylinder"),
                         method="dynamics")
    assert si.held and si.steps == one.steps
    for a, b in zip(si.records, one.records):
        assert a.N1 == pytest.approx(b.N1, rel=1e-9) and a.N2 == pytest.approx(b.N2, rel=1e-9)
        np.testing.assert_allclose(a.tip, b.tip, atol=1e-12)
    np.testing.assert_allclose(si.workpiece_position, one.workpiece_position, atol=1e-12)


def test_a_state_in_the_other_grips_shape_is_not_held():
    # soft Grip II fingers that settle with their tips below the palm (Grip I's shape): not held,
    # as the planar settle reports it (simgrip.validity.check_grip_shape)
    from simgrip.params import DimensionlessParams

    p = DimensionlessParams(D=0.142, M=3.3, b=0.762, mu_s=0.894)
    pl = settle(build_scene("II", p, Uniform(9.83), 6), method="dynamics")
    assert not pl.held and not pl.grip_matched
    st = settle_gripper(build_gripper("II", p, Uniform(9.83), 6, fingers=3, workpiece="cylinder"), method="dynamics")
    assert not st.held and not st.grip_matched and st.converged
    assert any("wrong grip" in w for w in st.warnings)
    assert np.all(st.tip[:, 1] < 0)


@pytest.mark.parametrize("grip, K, shape", [("I", 3, "cylinder"), ("II", 4, "box"), ("I", 2, "box")])
def test_the_step_is_the_straight_chains_as_the_planar_settles(planar, grippers, grip, K, shape):
    """``h = 1/omega_min`` of the straight chains: the planar dynamic settle's (from its built, straight
    scene), whatever the start's shape; the same per-finger problem then takes the same number of steps."""
    st, pl = grippers[grip, K, shape], planar[grip]
    sc = build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape)
    assert st.timestep == pytest.approx(pl.timestep, rel=1e-9)
    assert st.timestep == pytest.approx(1.0 / straight_frequency(sc, mujoco.MjData(sc.model),
                                                                 sc.model.jnt_stiffness[sc.model.dof_jntid]), rel=1e-12)
    assert st.steps == pl.steps


@pytest.mark.parametrize("grip, K, shape, beta", [("I", 3, "cylinder", 0.0), ("II", 4, "box", 0.0),
                                                  ("II", 3, "sphere", -0.2)])
def test_contact_rest_depth_is_the_settled_penetration(grip, K, shape, beta):
    """MuJoCo's contact rests at ``N tc^2 A_nn`` (the contact's mobility through the step's metric); measured
    1.020 times that in every case (n = 16, 32; K = 2 to 5; both grips; off-centre, turned, sphere), so
    within 3 %."""
    sc = build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape, contact_angle=beta)
    st = settle_gripper(sc, method="dynamics")
    depth = contact_rest_depth(sc, [r.normal for r in st.records], st.timestep)  # at the settled state
    assert depth.shape == (K,)
    for rec, dep in zip(st.records, depth):
        assert 1.0 <= rec.penetration / dep <= 1.03
