"""The planar dynamics' verdict does not hang on round-off of its start (MuJoCo's constraint solve converges).

Grip I, D = 1e-2, M = 1e-3, mu_s = 1, Uniform(-3.5), n = 32 (tests/test_dynamics_verdicts.py's light Grip I):
the chain start holds the box with a wide margin (tip normal force N = 131.5 W, tangential T = W, so the
friction needed is T/N = 0.0076 against mu_s = 1).  Yet ``settle(method="dynamics")`` held or dropped it
depending on 1e-16 of the start: MuJoCo's Newton constraint solve, whose line search was capped at MuJoCo's
default 50 evaluations, needed 59 in the third step (elliptic cone, impratio 1e4); the cut solve returned a
force with the friction at the cone's edge and the normal force 40 % off (N = 82 W), the kicks grew
chaotically (speed 2e-6 -> 7e-2 in 36 steps) and threw the box off the tip.  With the line search to its own
tolerance (:data:`simgrip.settle.integrator.DYN_LS_ITERATIONS`) every solve converges and the flow comes to
rest in one stop-test batch, the tip not slipping.
"""

from __future__ import annotations

import numpy as np
import pytest

import mujoco

from simgrip.params import DimensionlessParams
from simgrip.profiles import Uniform
from simgrip.reference import chain_start
from simgrip.scenes import build_scene
from simgrip.settle import integrator, settle

N = 32
PARAMS = DimensionlessParams(D=1e-2, M=1e-3, b=0.6, mu_s=1.0, gamma=0.8)


def _perturbed_start(monkeypatch, rel: float) -> None:
    """Make the Grip I chain start's joint angles ``(1 + rel)`` times the solved ones (a round-off-sized change)."""
    solved = chain_start.grip_start

    def grip_start(*args, **kw):
        r = solved(*args, **kw)
        return r._replace(joint_angles=r.joint_angles * (1.0 + rel))

    monkeypatch.setattr(chain_start, "grip_start", grip_start)


@pytest.mark.parametrize("rel", [0.0, 1e-12, -1e-12, 1e-9, -1e-9])
def test_light_grip_i_verdict_does_not_depend_on_round_off_of_the_start(monkeypatch, rel):
    _perturbed_start(monkeypatch, rel)
    st = settle(build_scene("I", PARAMS, Uniform(-3.5), N), method="dynamics")
    assert st.converged and st.held
    assert not st.warnings


def test_each_constraint_solve_of_the_light_grip_i_converges(monkeypatch):
    """Every physics step's Newton constraint solve ends below MuJoCo's own tolerance (``opt.tolerance`` on the
    scaled gradient, its convergence test): a solve cut short by the line search's cap ended at 0.05."""
    grads = []

    def step(self, k=1):  # Dyn.step one physics step at a time (mj_step(m, d, k) is k such steps)
        self.update_damping()
        for _ in range(k):
            mujoco.mj_step(self.m, self.d)
            it = int(self.d.solver_niter[0])
            if self.d.ncon:
                grads.append(float(self.d.solver[max(it - 1, 0)].gradient) if it else np.inf)
        self.steps += k
        self.calls += k
        if self.held_q is not None:
            self.d.qpos[self.scene.workpiece_qpos] = self.held_q
            self.d.qvel[self.scene.workpiece_dof] = 0.0

    monkeypatch.setattr(integrator.Dyn, "step", step)
    sc = build_scene("I", PARAMS, Uniform(-3.5), N)
    st = settle(sc, method="dynamics")
    assert st.converged and st.held
    assert grads and max(grads) <= sc.model.opt.tolerance
    assert sc.model.opt.ls_iterations == mujoco.MjModel.from_xml_string("<mujoco/>").opt.ls_iterations  # put back


def test_a_settle_puts_the_line_search_cap_back_whatever_path_raised_it():
    """save_options/restore_options carry ``ls_iterations``: the dynamics raises it (DYN_LS_ITERATIONS), and a
    path that restores through them alone (the full-contact settle's dynamics fallback) left it raised."""
    from simgrip.settle.statics import restore_options, save_options

    scene = build_scene("I", DimensionlessParams(D=1.0, M=5.0, b=0.6, mu_s=1.0, gamma=0.8), Uniform(-5.0), 8)
    m = scene.model
    own = int(m.opt.ls_iterations)
    saved = save_options(m)
    m.opt.ls_iterations = integrator.DYN_LS_ITERATIONS
    restore_options(m, saved)
    assert int(m.opt.ls_iterations) == own
