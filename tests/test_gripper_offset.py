"""K-finger grasps beyond the planar theory: off-centre, turned workpieces and unequal fingers.

There is no closed form for these grasps, so the tests check what must hold:

* **balance**: the workpiece's net force within the settle's residual (to
  round-off) and its net moment within ``sqrt(3)`` tolerances (its rotation
  rows are in its body frame), recomputed here from the published per-finger
  records (forces and contact points in each finger's frame);
* **convergence at second order in n**: every finger is a hinge chain whose
  springs approximate the elastica with an ``O(ds^2)`` error
  (:mod:`simgrip.chain`), and the workpiece's balance is a smooth function of
  each chain's ``N1`` and tip height, so every finger's forces and tip carry an
  error ``C ds^2 (1 + O(ds))``: the observed order ``log2(|F16 - F32| / |F32 - F64|)``
  is 2.  The stop test adds at most a few ``tol`` (settled at ``tol = 4e-6``
  here) to any force; only differences ``|F32 - F64|`` of at least
  ``100 tol`` are judged, so that it moves the observed order by at most
  ~0.06, inside the +-0.3 band (which leaves room for the ``O(ds)`` term).  Every
  finger's ``N1`` is always among them.  (Two fingers, ``K = 2``, are left
  out: the Grip II box with unequal fingers, settled on to ``tol = 4e-6``,
  turns a few degrees after its first balanced rest until a tip slides off
  and the settle reports a drop, at n = 16, 32 and 64 alike; the state the
  default tolerance stops at is balanced but apparently not stable.  Grip I's
  two-finger box converges at order 2 at the default tolerance, outside this test);
* **invariance** under turning the whole scene about the palm axis (``yaw``):
  the same per-finger forces and tips to the tolerance;
* **determinism**: the same inputs give bit-identical numbers;
* **reduction**: no offset, no turn and equal fingers is the symmetric grasp
  (bit-identical through the same path; through the balanced start, within
  the tolerance);
* **hold iff the friction suffices**: the settled forces do not depend on
  ``mu_s`` while the contacts stick, so a probe at a generous ``mu_s`` gives
  each finger's required ``mu``; the workpiece is held at 1.02 times the
  largest and dropped at 0.98 times it (MuJoCo's elliptic cone is sharp to
  +-0.5 %, test_settle_dynamics).

With ``K >= 4`` fingers statics does not fix every finger's forces (a squeeze
of the vertical shares, a twist of the out-of-plane forces); the settle keeps
the balanced start's least-norm choice (:mod:`simgrip.gripper.start`),
which is what the convergence test of the four-finger box follows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD
from simgrip.params import DimensionlessParams
from simgrip.reference import solve_chain
from simgrip.gripper.settle import settle_gripper
from simgrip.gripper.scene import build_gripper

N = 16
#: name -> (grip, profile, build keywords): off-centre, turned, unequal fingers, both grips.
SCENES = {
    "cyl3-offset-kappa-I": ("I", [-6.0, -5.8, -6.3], dict(fingers=3, workpiece="cylinder", offset=(0.03, -0.02))),
    "box4-offset-yaw-I": ("I", -6.0, dict(fingers=4, workpiece="box", offset=(0.02, 0.01), workpiece_yaw=0.1)),
    "box4-kappa-I": ("I", [-6.0, -5.8, -6.3, -6.1], dict(fingers=4, workpiece="box")),
    "box2-kappa-offset-yaw-I": ("I", [-6.0, -6.1], dict(fingers=2, workpiece="box", offset=(0.02, 0.0),
                                                         workpiece_yaw=0.05)),
    "cyl5-offset-I": ("I", -6.0, dict(fingers=5, workpiece="cylinder", offset=(-0.03, 0.02))),
    "cyl3-offset-kappa-II": ("II", [5.0, 5.1, 4.9], dict(fingers=3, workpiece="cylinder", offset=(0.02, 0.01))),
    "box2-kappa-yaw-II": ("II", [5.0, 5.1], dict(fingers=2, workpiece="box", workpiece_yaw=0.05)),
}
CONVERGENCE = ["cyl3-offset-kappa-I", "box4-offset-yaw-I", "box4-kappa-I", "cyl3-offset-kappa-II"]


def _settle(name, n=N, params=STANDARD, tol=None, **kw):
    grip, profile, build = SCENES[name]
    return settle_gripper(build_gripper(grip, params, profile, n, **{**build, **kw}),
                          **({} if tol is None else {"tol": tol}), method="dynamics")


def _values(st) -> np.ndarray:
    """Per finger: N1, N2, N3, tip X, tip Y."""
    return np.array([[r.N1, r.N2, r.N3, r.tip[0], r.tip[1]] for r in st.records])


@pytest.fixture(scope="module")
def settled():
    return {name: _settle(name) for name in SCENES}


def _frame(azimuth):
    c, s = math.cos(azimuth), math.sin(azimuth)
    return np.array([c, s, 0.0]), np.array([-s, c, 0.0])


@pytest.mark.parametrize("name", list(SCENES))
def test_workpiece_is_balanced(settled, name):
    st = settled[name]
    K = st.fingers
    assert st.held and st.converged and st.residual <= st.tolerance and len(st.records) == K
    scene_yaw = 0.0
    M = STANDARD.M
    # the settle's own balance: the residual's translation rows, and its rotation rows (body frame)
    assert np.max(np.abs(st.force_balance)) <= st.residual + 1e-12 * (1 + K * M)
    assert np.linalg.norm(st.moment_balance) <= math.sqrt(3) * st.tolerance
    # recomputed from the published records: force on the rod N1 E1 + N3 E3 + N2 z at the contact point
    force, moment = np.array([0.0, 0.0, -K * M]), np.zeros(3)
    for r in st.records:
        e1, e3 = _frame(scene_yaw + 2 * math.pi * r.finger / K)
        on_rod = r.N1 * e1 + r.N3 * e3 + np.array([0.0, 0.0, r.N2])
        point = r.point[0] * e1 + r.point[2] * e3 + np.array([0.0, 0.0, r.point[1]])
        force -= on_rod
        moment += np.cross(point - st.workpiece_position, -on_rod)
    assert np.max(np.abs(force)) <= st.residual + 1e-9
    assert np.linalg.norm(moment) <= math.sqrt(3) * st.tolerance + 1e-9
    # every contact pushes and sticks
    assert all(r.normal > 0 and r.required_mu <= STANDARD.mu_s for r in st.records)


@pytest.mark.parametrize("name", CONVERGENCE)
def test_every_finger_converges_at_second_order_in_n(name):
    tol = 4e-6
    vals = []
    for n in (16, 32, 64):
        st = _settle(name, n=n, tol=tol)
        assert st.held and st.converged
        vals.append(_values(st))
    v = np.array(vals)  # (resolution, finger, quantity)
    if v.shape[1] >= 4:
        # K >= 4: how the vertical and out-of-plane forces split among the fingers is statically
        # indeterminate (2K - 6 internal modes of sticking friction; the settle keeps its start's
        # least-norm split), so only N1 and the tip are judged
        v = v[:, :, [0, 3, 4]]
    d1, d2 = np.abs(v[0] - v[1]), np.abs(v[1] - v[2])
    judged = d2 >= 100 * tol
    assert np.all(judged[:, 0])  # every finger's N1 (and most tip heights: Grip II's hardly move with n)
    orders = np.log2(d1[judged] / d2[judged])
    np.testing.assert_allclose(orders, 2.0, atol=0.3)


@pytest.mark.parametrize("name", ["cyl3-offset-kappa-I", "box4-offset-yaw-I", "box2-kappa-offset-yaw-I"])
def test_invariant_under_turning_the_scene_about_the_palm_axis(settled, name):
    a = settled[name]
    for yaw in (0.7, -2.0):
        b = _settle(name, yaw=yaw)
        assert b.held and b.converged
        diff = np.abs(_values(a) - _values(b))
        assert np.max(diff[:, :3]) <= a.tolerance  # forces
        assert np.max(diff[:, 3:]) <= a.tolerance  # tips, over l
        # the workpiece turned with the scene
        turn = 2 * math.atan2(b.workpiece_quat[3], b.workpiece_quat[0]) - 2 * math.atan2(a.workpiece_quat[3],
                                                                                        a.workpiece_quat[0])
        assert math.remainder(turn - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)


def test_deterministic(settled):
    # one of each pair is the module fixture's settle of the same inputs (run earlier, after other scenes)
    a, b = settled["box4-offset-yaw-I"], _settle("box4-offset-yaw-I")
    assert np.array_equal(a.qpos, b.qpos) and a.steps == b.steps
    assert np.array_equal(_values(a), _values(b))
    c, d = settled["cyl3-offset-kappa-II"], _settle("cyl3-offset-kappa-II")
    assert np.array_equal(c.qpos, d.qpos) and np.array_equal(_values(c), _values(d))


@pytest.mark.parametrize("K, shape, kappa", [(3, "cylinder", -6.0), (4, "box", -6.0), (3, "cylinder", 5.0)])
def test_no_offset_no_turn_equal_fingers_is_the_symmetric_grasp(K, shape, kappa):
    grip = "I" if kappa < 0 else "II"
    sym = settle_gripper(build_gripper(grip, STANDARD, kappa, N, fingers=K, workpiece=shape), method="dynamics")
    same = settle_gripper(build_gripper(grip, STANDARD, [kappa] * K, N, fingers=K, workpiece=shape,
                                        offset=(0.0, 0.0), workpiece_yaw=0.0), method="dynamics")
    assert sym.held and np.array_equal(sym.qpos, same.qpos) and np.array_equal(_values(sym), _values(same))
    # every finger alike, to round-off
    assert np.ptp(_values(sym), axis=0).max() <= 1e-9
    # through the balanced start (a vanishing offset): the same equilibrium within the tolerance
    near = settle_gripper(build_gripper(grip, STANDARD, kappa, N, fingers=K, workpiece=shape, offset=(1e-12, 0.0)),
                          method="dynamics")
    assert near.held and np.max(np.abs(_values(near) - _values(sym))) <= sym.tolerance


@pytest.mark.parametrize("name", ["cyl3-offset-kappa-I", "box4-offset-yaw-I", "cyl3-offset-kappa-II"])
def test_held_iff_the_friction_suffices(name):
    """Three fingers: the statics fixes every force, the same equilibrium at any sticking mu_s; four: only
    ``N1`` and the tips (the internal modes follow the contact solver's path, which mu_s changes)."""
    probe = _settle(name, params=STANDARD.replace(mu_s=3.0))
    need = max(r.required_mu for r in probe.records)
    assert need < 3.0
    for factor, held in ((1.02, True), (0.98, False)):
        st = _settle(name, params=STANDARD.replace(mu_s=need * factor))
        assert st.held is held and st.converged, factor
        if held:  # the same sticking equilibrium whatever mu_s
            cols = slice(None) if st.fingers == 3 else [0, 3, 4]
            np.testing.assert_allclose(_values(st)[:, cols], _values(probe)[:, cols], atol=probe.tolerance)
        else:
            assert st.records == []


def test_a_finger_out_of_reach_holds_nothing():
    # kappa = -2.5: the free finger's tip rests at X ~ 0.21, inside the centred cylinder's surface
    # (X = 0.3) but outside finger 0's when the cylinder sits 0.1 l towards it (X = 0.2): that
    # finger cannot touch, and the workpiece is reported not held, the fingers settling alone
    p = DimensionlessParams(D=1.0, M=0.5, b=0.6, mu_s=2.0)
    free = solve_chain("free", p, -2.5, N)
    assert 0.2 < np.sum(np.cos(free.link_angles)) / N < 0.3
    centred = settle_gripper(build_gripper("I", p, -2.5, N, fingers=3, workpiece="cylinder"), method="dynamics")
    assert centred.held
    st = settle_gripper(build_gripper("I", p, -2.5, N, fingers=3, workpiece="cylinder", offset=(-0.1, 0.0)),
                        method="dynamics")
    assert not st.held and st.converged and st.records == []
    # the fingers settle alone from this very chain shape (finger_chain "free"): the dynamics may move them
    # only while the residual is above its tolerance tol = 1e-5 (rho g l^2), i.e. each hinge by about
    # tol / (D n) and a link angle (a sum of n) by about tol / D = 1e-5
    np.testing.assert_allclose(st.link_angles, np.vstack([free.link_angles] * 3), atol=st.tolerance / p.D)
