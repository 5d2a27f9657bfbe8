"""Every scene the builders can make and every MJCF part compiles and runs one simulated second without a MuJoCo warning.

In the manner of mujoco_menagerie's model test: each model is stepped from its
initial state for one second of simulated time at its own time step, inside
:func:`simgrip.sim.checks.check_invalid_state` (any MuJoCo warning, NaN or inf
fails the test).
"""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.envs.pick_model import build_pick_model
from simgrip.models import available, model_path
from simgrip.scenes import build_scene as build_paper_scene
from simgrip.sim.checks import check_invalid_state
from simgrip.sim.scene import build_scene

KAPPA = {"free": -4.0, "I": -6.0, "II": 5.0, "III": -6.0}
N = 12

SCENES = [
    (grip, fingers, render, free)
    for grip, fingers, render, free in itertools.product(KAPPA, (1, 2), (False, True), (True, False))
    if grip != "free" or free  # the free rod has no workpiece to fix
]


def _run_one_second(model: mujoco.MjModel, data: mujoco.MjData, what: str) -> None:
    steps = int(round(1.0 / model.opt.timestep))
    t0 = data.time  # an environment's reset has already run its settling steps
    with check_invalid_state(data, what):
        mujoco.mj_forward(model, data)
        mujoco.mj_step(model, data, steps)
    assert data.time - t0 == pytest.approx(steps * model.opt.timestep)
    assert np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))


@pytest.mark.parametrize("grip, fingers, render, free", SCENES)
def test_every_scene_runs_a_second_without_warnings(grip, fingers, render, free):
    sc = build_scene(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=fingers, render=render, free_workpiece=free)
    _run_one_second(sc.model, sc.data, f"scene {grip}, {fingers} finger(s), render={render}, free={free}")


@pytest.mark.parametrize("fingers", [1, 2])
def test_the_paper_start_of_grip_iii_runs_a_second_without_warnings(fingers):
    sc = build_paper_scene("III", STANDARD, Uniform(KAPPA["III"]), N, fingers=fingers)
    _run_one_second(sc.model, sc.data, f"Grip III from the hinge chain's start, {fingers} finger(s)")


@pytest.mark.parametrize("grip", ["I", "III"])
def test_pick_models_run_a_second_without_warnings(grip):
    pm = build_pick_model(grip, n_links=N, length=0.1, EI=3e-3, rho=0.15, g=9.81, r_tip=0.004,
                          box_size=(0.05, 0.04, 0.06), box_mass_max=0.06, friction=0.8, spin_friction=0.004,
                          timestep=0.002, impratio=1.0, damping_time=0.02, armature=1e-5)
    m = pm.model
    d = mujoco.MjData(m)
    d.qpos[pm.palm_qpos] = d.ctrl[0] = 0.11 if grip == "I" else 0.135
    d.qpos[pm.box_qpos + 2] = pm.pedestal_height + 0.03
    _run_one_second(m, d, f"pick model {grip}")


@pytest.mark.parametrize("name", available())
def test_every_mjcf_part_compiles_and_runs_a_second_without_warnings(name):
    model = mujoco.MjModel.from_xml_path(str(model_path(name)))
    _run_one_second(model, mujoco.MjData(model), f"models/{name}")


def test_models_ship_the_parts_the_builders_load():
    names = available()
    for part in ("defaults.xml", "finger.xml", "palm.xml", "workpiece.xml", "dressing.xml", "pick_scene.xml"):
        assert part in names
        assert model_path(part).is_file()


GRIPPERS = [("I", 3, "cylinder", {}), ("II", 4, "box", {}), ("I", 2, "box", {}), ("I", 3, "sphere", {}),
            ("III", 4, "box", {}), ("I", 4, "box", {"offset": (0.02, 0.01), "workpiece_yaw": 0.1})]


@pytest.mark.parametrize("grip, fingers, shape, extra", GRIPPERS)
def test_every_gripper_runs_a_second_without_warnings(grip, fingers, shape, extra):
    from simgrip.gripper.scene import build_gripper

    sc = build_gripper(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=fingers, workpiece=shape, **extra)
    _run_one_second(sc.model, sc.data, f"gripper {grip}, {fingers} fingers, {shape}, {extra}")


@pytest.mark.parametrize("fingers, shape", [(3, "cylinder"), (3, "sphere"), (4, "box")])
def test_pick_multi_models_run_a_second_without_warnings(fingers, shape):
    from simgrip.envs.pick_multi import PickMultiEnv

    env = PickMultiEnv(fingers=fingers, shapes=(shape,), n_links=N)
    env.reset(seed=0)
    _run_one_second(env.model, env.data, f"PickMulti model, {fingers} fingers, {shape}")
