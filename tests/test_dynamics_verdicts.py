"""Issue 16 §6: the planar dynamics' hold/drop verdicts against the Newton settle and the BVP.

Two defects of the planar over-damped dynamics (``settle(method="dynamics")``), each reproduced here:

* a weightless (or nearly weightless) workpiece was dropped: the planar scene floored its mass at 1e-12
  rho l, and MuJoCo's soft contact, whose depth goes as the contact's mobility (the workpiece's inverse
  mass), let the corner sink through the rod (Grip III) or the tip tunnel into the face (Grips I/II);
  now the inertia is floored (:data:`simgrip.sim.workpiece.MIN_WORKPIECE_MASS` rho l per finger, the
  K-finger gripper's floor) and the weight stays exactly ``M`` (gravity compensation);
* Grip III's drop test called a workpiece dropped on a fall or a separation of fixed size; now it is
  dropped only when it falls away: out of contact, moving down, with no finger beneath a corner
  (:func:`simgrip.sim.workpiece_motion.corners_over_fingers`).  A drop the point-contact statics do not share
  is checked against the static settle and warned (MuJoCo's surface contact couple, or the flow's path).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip.params import DimensionlessParams
from simgrip.profiles import Uniform
from simgrip.reference import elastica
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.chain_model import ChainModel
from simgrip.sim.scene import finger_state
from simgrip.sim.workpiece import MIN_WORKPIECE_MASS
from simgrip.sim.workpiece_motion import corners_over_fingers

N = 32


def _params(D, M, mu_s, **kw):
    return DimensionlessParams(D=D, M=M, b=kw.pop("b", 0.6), mu_s=mu_s, gamma=kw.pop("gamma", 0.8))


def _weight_on_z(scene) -> float:
    """The net gravity MuJoCo puts on the workpiece's z slide (gravity less its compensation), [N], up > 0."""
    m, d = scene.model, scene.data
    dof = [j for name, j in zip(scene.workpiece_joints, scene.workpiece_dof) if name == "z"][0]
    d.qvel[:] = 0.0
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_passive(m, d)
    mujoco.mj_rne(m, d, 0, d.qfrc_bias)
    return float(d.qfrc_bias[dof] - d.qfrc_passive[dof])


# ---------------------------------------------------------------------------
# the inertia floor keeps the weight


@pytest.mark.parametrize("grip,kappa", [("I", -3.5), ("III", -4.0)])
@pytest.mark.parametrize("fingers", [1, 2])
def test_light_workpiece_inertia_is_floored_and_its_weight_kept(grip, kappa, fingers):
    for M in (0.0, 1e-3):
        sc = build_scene(grip, _params(1.0, M, 1.0), Uniform(kappa), N, fingers=fingers)
        floor = fingers * MIN_WORKPIECE_MASS  # l = rho = g = 1
        assert sc.workpiece_inertial_mass == floor and sc.workpiece_mass == fingers * M
        # the model's gravity on the workpiece is its true weight (M = 0: exactly none)
        if M == 0.0:
            assert _weight_on_z(sc) == 0.0
        else:
            assert _weight_on_z(sc) == pytest.approx(fingers * M, rel=1e-12)
        # the Newton settle's analytic model reads the true weight, never body_mass
        cm = ChainModel(sc)
        assert cm.weight == sc.workpiece_mass * sc.physical.g / sc.force_scale


def test_standard_workpiece_model_is_unchanged():
    # M above the floor: the model is the one it always was (no compensation, mass M): Newton bit-identical
    sc = build_scene("III", _params(1.0, 5.0, 1.0), Uniform(-4.0), N)
    wb = sc.workpiece_body
    assert sc.model.body_mass[wb] == 5.0 and sc.model.body_gravcomp[wb] == 0.0 and sc.model.ngravcomp == 0
    assert _weight_on_z(sc) == 5.0


# ---------------------------------------------------------------------------
# group 1: weightless workpieces


@pytest.mark.parametrize("D,kappa", [(1e-2, -2.0), (1e-2, -4.0), (1e-2, -7.0), (1.0, -4.0)])
def test_weightless_cradle_is_held_by_the_dynamics_as_by_newton_and_the_bvp(D, kappa):
    """``settle(build_scene("III", D=1e-2, M=0, mu_s=100), method="dynamics")`` dropped the workpiece (the
    corner sank through the rod) while M = 1e-3 held; the Newton settle and the BVP hold it (the audit's
    silent rows at M = 0, mu_s = 100)."""
    p = _params(D, 0.0, 100.0)
    dyn = settle(build_scene("III", p, Uniform(kappa), N), method="dynamics")
    nw = settle(build_scene("III", p, Uniform(kappa), N))
    assert dyn.converged and dyn.held and nw.held
    assert elastica.solve("III", p, Uniform(kappa)).feasible
    # where it rests: MuJoCo's soft contact within its rest depth, the contact where Newton puts it
    assert dyn.penetration < 1e-4
    assert dyn.contact.gamma == pytest.approx(nw.contact.gamma, abs=2e-3)


def test_weightless_four_finger_cradle_dynamics_holds():
    """The K = 4 cradle's dynamics replicates the planar dynamics: it dropped where the planar one did."""
    from simgrip.scenes import start_angles
    from simgrip.gripper.symmetry import settle_cradle_dynamics
    from simgrip.gripper.scene import build_gripper

    p = _params(1e-2, 0.0, 100.0)
    sc = build_gripper("III", p, Uniform(-4.0), N, fingers=4, workpiece="box",
                       initial_angles=start_angles("III", p, Uniform(-4.0), N))
    st = settle_cradle_dynamics(sc)
    assert st.held and st.converged


@pytest.mark.parametrize("grip,kappa", [("I", -6.0), ("II", 3.5)])
def test_weightless_frictionless_tip_does_not_tunnel(grip, kappa):
    """Grips I/II at M = 0, mu_s = 0: 'dynamic settle tunnelled ... at every step down to h/8' (the tip sank
    into a nearly massless box); now the dynamics answers, holding as the BVP does."""
    p = _params(1.0, 0.0, 0.0)
    st = settle(build_scene(grip, p, Uniform(kappa), N), method="dynamics")
    assert st.converged and st.held and st.penetration < 1e-4
    assert elastica.solve(grip, p, Uniform(kappa)).feasible


def test_light_grip_i_is_held_by_the_dynamics_as_by_newton():
    # M = 1e-3 on the softest finger: the dynamics dropped it (the tip slid into the light box), Newton holds;
    # its robustness to round-off of the start (MuJoCo's constraint solve converged): tests/test_dynamics_solver.py
    p = _params(1e-2, 1e-3, 1.0)
    st = settle(build_scene("I", p, Uniform(-3.5), N), method="dynamics")
    assert st.converged and st.held and settle(build_scene("I", p, Uniform(-3.5), N)).held


def test_workpiece_at_rest_touching_no_finger_is_not_held():
    """M = 0, mu_s = 1 (the friction cone's edge for the point contact): the corner slips, the finger springs
    off, and the weightless workpiece stays where it was, at rest and touching nothing.  Nothing holds it: not
    held (it was reported held without a contact, which the K = 4 cradle could not replicate: AttributeError
    at M = 0, mu_s = 0), and the state says the static settle holds it.  The Newton settle holds it at the
    cone's edge (with its own warning), the BVP does not."""
    p = _params(1.0, 0.0, 1.0)
    st = settle(build_scene("III", p, Uniform(-4.0), N), method="dynamics")
    assert st.converged and not st.held and st.contact is None
    assert any(w.startswith("dropped by the dynamics where the static settle") for w in st.warnings)
    assert not elastica.solve("III", p, Uniform(-4.0)).feasible


def test_weightless_frictionless_four_finger_cradle_dynamics_answers():
    from simgrip.scenes import start_angles
    from simgrip.gripper.symmetry import settle_cradle_dynamics
    from simgrip.gripper.scene import build_gripper

    p = _params(1.0, 0.0, 0.0)
    sc = build_gripper("III", p, Uniform(-4.0), N, fingers=4, workpiece="box",
                       initial_angles=start_angles("III", p, Uniform(-4.0), N))
    st = settle_cradle_dynamics(sc)
    assert st.converged and not st.held  # as the Newton settle and the BVP


# ---------------------------------------------------------------------------
# group 2: Grip III's drop test


def test_corners_over_fingers_reads_the_geometry():
    sc = build_scene("III", _params(1.0, 5.0, 1.0), Uniform(-4.0), N)
    m, d = sc.model, sc.data
    corner = sc.workpiece_geoms[0]
    assert corners_over_fingers(sc)  # the start: the corner rests on the rod
    # the finger straight out along +x at the palm's height: nothing beneath the corner
    d.qpos[sc.joint_qpos[0]] = 0.0
    mujoco.mj_forward(m, d)
    assert np.allclose(finger_state(sc)[2][:, 1], 0.0) and float(d.geom_xpos[corner][2]) < 0.0
    assert not corners_over_fingers(sc)
    # the finger straight, tilted down so that its paired links (around s = 0.8) pass under the corner: caught
    cx, cz = float(d.geom_xpos[corner][0]), float(d.geom_xpos[corner][2])
    theta = -float(np.arccos(cx / 0.8))
    assert 0.8 * np.sin(theta) < cz  # the finger's point below the corner is below it
    d.qpos[sc.joint_qpos[0]] = 0.0
    d.qpos[sc.joint_qpos[0][0]] = theta
    mujoco.mj_forward(m, d)
    assert corners_over_fingers(sc)
    # the box lowered below that point: the finger is above the corner, nothing beneath
    wz = [q for name, q in zip(sc.workpiece_joints, sc.workpiece_qpos) if name == "z"][0]
    d.qpos[wz] -= 0.5
    mujoco.mj_forward(m, d)
    assert float(d.geom_xpos[corner][2]) < 0.8 * np.sin(theta) and not corners_over_fingers(sc)
    # other grips: always True (their drop test is the slip along the face)
    assert corners_over_fingers(build_scene("I", _params(1.0, 5.0, 1.0), Uniform(-3.5), N))


@pytest.mark.parametrize("kappa", [-4.0, -7.0])
def test_heavy_cradle_drop_is_the_surface_contacts_and_warned(kappa):
    """Grip III, D = 1, M = 1e4, mu_s = 100: the Newton settle (point contact) holds, the dynamics drops with
    no warning.  The dynamics is right for its own contact: MuJoCo's friction acts r_link off the centreline,
    and the static settle with that surface contact drops it too (it agrees with the dynamics to three
    digits of the required mu wherever it holds, M <= 1000).  Now the drop says so."""
    p = _params(1.0, 1e4, 100.0)
    dyn = settle(build_scene("III", p, Uniform(kappa), N), method="dynamics")
    assert dyn.converged and not dyn.held
    assert any("contact='surface'" in w and "couple" in w for w in dyn.warnings), dyn.warnings
    assert settle(build_scene("III", p, Uniform(kappa), N)).held
    assert not settle(build_scene("III", p, Uniform(kappa), N), contact="surface").held


def test_cradle_carried_while_it_sinks_is_held():
    # M = 1000: the surface contact holds (required mu 18.5 of 100); the workpiece sinks with the loaded finger
    # while the corner stays on the rod, and the dynamics ends where the surface-contact statics does
    p = _params(1.0, 1e3, 100.0)
    dyn = settle(build_scene("III", p, Uniform(-4.0), N), method="dynamics")
    sur = settle(build_scene("III", p, Uniform(-4.0), N), contact="surface")
    assert dyn.converged and dyn.held and sur.held and not dyn.warnings
    assert dyn.contact.gamma == pytest.approx(sur.contact.gamma, abs=2e-3)
    assert dyn.contact.required_mu == pytest.approx(sur.contact.required_mu, rel=1e-2)


def test_drop_on_the_flows_path_is_warned():
    """Grip III at the gamma = 0.31 edge (D = 1, M = 5, mu_s = 1): the start has the corner at s = 0.82 on a
    finger far from its equilibrium; the over-damped flow pulls the finger away faster than the damped
    workpiece follows, and the workpiece falls past it, while both static settles hold it (mu 0.17 of 1).
    The drop is the path's, and the state says so."""
    p = _params(1.0, 5.0, 1.0, gamma=0.31)
    dyn = settle(build_scene("III", p, Uniform(-4.0), N), method="dynamics")
    assert dyn.converged and not dyn.held
    assert any("way to rest from the start" in w for w in dyn.warnings), dyn.warnings


def test_drop_that_the_statics_share_is_not_warned():
    # Grip III, kappa = -4, D = 1e-2, M = 5, mu_s = 1: dropped by every method, no warning
    p = _params(1e-2, 5.0, 1.0)
    dyn = settle(build_scene("III", p, Uniform(-4.0), N), method="dynamics")
    assert dyn.converged and not dyn.held and not settle(build_scene("III", p, Uniform(-4.0), N)).held
    assert not any(w.startswith("dropped by the dynamics") for w in dyn.warnings)
