"""Issue 17 section 1: no impossible state passes as a grip, on every path (library, simulate, compare, sweep rows,
figures' overlays, K-finger grippers, the pick envs' info)."""

import json
import math

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.cli import main
from simgrip.compare import compare, simulate

N = 32


def _simulate_json(capsys, kappa: float) -> dict:
    assert main(["simulate", "I", "--kappa", str(kappa), "--links", str(N), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("kappa", [-10.0, -14.0])
def test_a_self_crossing_grip_i_is_not_a_grip(capsys, kappa):
    """Was: held true, N = 30.2 (-10) / 47 (-14), no warning: the chain loops through itself and the box."""
    rec = _simulate_json(capsys, kappa)
    assert rec["held"] is False and rec["valid"] is False and rec["feasible"] is False
    text = " ".join(rec["warnings"])
    assert "invalid state" in text and ("crosses itself" in text or "inside the workpiece" in text)


def test_the_standard_case_is_valid(capsys):
    rec = _simulate_json(capsys, -6.0)
    assert rec["held"] and rec["valid"] and rec["feasible"]
    assert not any("invalid state" in w for w in rec["warnings"])


def _sweep(grip, kappas):
    return [(k, simulate(grip, STANDARD, Uniform(float(k)), N)) for k in kappas]


@pytest.mark.parametrize("grip,kappas", [("I", np.linspace(0.0, -6.0, 13)), ("II", np.linspace(0.0, 6.0, 13))])
def test_no_false_positive_over_the_papers_grip_i_ii_ranges(grip, kappas):
    """Figs. 7 and 8 (n = 32): every state, held or dropped, is valid."""
    bad = [(k, st.warnings) for k, st in _sweep(grip, kappas) if not st.valid]
    assert bad == []


def test_grip_iii_range_invalid_only_where_condition_23_fails_or_the_free_rod_overlaps():
    """Fig. 9 (n = 32, kappa in [0, -10]): valid over the paper's feasible part; beyond it a state is invalid only
    where condition (23) fails (the rod beyond the contact through the box's bottom) or, dropped, the free finger
    turns through more than a full turn (a uniform curl of |kappa| > 2 pi overlaps itself)."""
    for k, st in _sweep("III", np.linspace(0.0, -10.0, 21)):
        turn = float(np.ptp(np.concatenate([[0.0], st.link_angles[0]])))
        if k >= -5.5:
            assert st.valid, (k, st.warnings)
        elif not st.valid:
            cond23 = any("condition (23) violated" in w for w in st.warnings)
            assert cond23 or turn > 2.0 * math.pi, (k, turn, st.warnings)


def test_compare_checks_the_reference_too():
    res = compare("I", STANDARD, Uniform(-10.0), N)
    sim, ref = res["simulation"], res["reference"]
    assert not sim["valid"] and not sim["feasible"] and ref["valid"] is False and not ref["feasible"]
    assert any(w.startswith("the reference itself crosses itself / enters the workpiece") for w in res["warnings"])
    ok = compare("I", STANDARD, Uniform(-6.0), N)
    assert ok["simulation"]["valid"] and ok["reference"]["valid"]


def test_k_fingers_crossing_each_other_are_not_held():
    """Grip I, kappa = -10, two fingers on a box: each curls past the palm axis into the other."""
    from simgrip.gripper import gripper_record, simulate_gripper

    st = simulate_gripper("I", STANDARD, Uniform(-10.0), 16, fingers=2, workpiece="box")
    rec = gripper_record(st, STANDARD)
    assert not st.valid and not st.held and rec["valid"] is False and rec["feasible"] is False
    assert any("fingers 0 and 1 pass through each other" in w for w in st.warnings)
    ok = simulate_gripper("I", STANDARD, Uniform(-6.0), 16, fingers=3, workpiece="cylinder")
    assert ok.valid and ok.held and gripper_record(ok, STANDARD)["valid"] is True


def test_sweep_rows_carry_valid():
    from simgrip.sweep.grid import SweepPoint
    from simgrip.sweep.point import COLUMNS, evaluate_point
    from simgrip.sweep.store import format_csv

    assert "valid" in COLUMNS
    rows = [evaluate_point(SweepPoint(i, "I", k, 1.0, 5.0, 1.0, 0.6, 0.8, N, "newton"))
            for i, k in enumerate((-6.0, -10.0))]
    assert [r["valid"] for r in rows] == [True, False]
    header = format_csv(rows).splitlines()[0].split(",")
    assert "valid" in header


def test_overlay_marks_invalid_states():
    from simgrip.figures.overlay import simulation_overlay

    ov = simulation_overlay("fig07", links=8, kappas=(-6.0, -10.0))
    assert list(ov["valid"]) == [True, False] and list(ov["feasible"]) == [True, False]


@pytest.mark.parametrize("env_id", ["simgrip/Pick-v1", "simgrip/PickMulti-v0"])
def test_env_info_has_valid_and_the_probe_finds_a_crossing(env_id):
    import gymnasium as gym
    import mujoco

    env = gym.make(env_id)
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(env.action_space.shape))
    assert info["valid"] is True and "invalid" not in info
    u = env.unwrapped
    d = u.data
    # curl finger 0 through 1.5 turns: its links cross (no self-contact pair in the pick scenes)
    jq = np.asarray(u.fingers.joint_qpos)[0]
    d.qpos[jq] = -3.0 * math.pi / len(jq)
    mujoco.mj_kinematics(u.model, d)
    found = u._validity(d.qpos.tolist(), d)
    assert found and any("crosses itself" in m or "closer than their capsules" in m for m in found)
    env.close()
