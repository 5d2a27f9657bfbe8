"""A flat charge on a crush (issue 18): :class:`simgrip.envs.crush_charge.CrushCharge`, ``train_sb3.py
--crush-charge`` and ``evaluate_policy.py --crush-charge``.

The wrapped env runs the same episode as the task, step for step; only a crushing step's reward differs, by exactly the
charge, and only from the ``start``-th wrapped step on (counted over episodes).  ``evaluate_policy.py`` values a
policy under a charge no env has: checked against the env wrapped to charge it.
"""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.crush_charge import CrushCharge
from helpers import load_example as _example


def _closing_episode(env, seed: int) -> list:
    """``(obs, reward, crushed, info)`` per step of an episode that closes the valve at full rate on a limit every
    grasp overruns (the K-finger pinch: a crush within a few steps)."""
    env.reset(seed=seed, options={"crush_limit": 0.05})
    rows = []
    for _ in range(400):
        a = np.zeros(env.action_space.shape, dtype=np.float32)
        a[0] = -1.0
        obs, r, term, trunc, info = env.step(a)
        rows.append((obs, r, info["crushed"], info))
        if term or trunc:
            break
    return rows


def test_the_charge_lowers_the_crushing_steps_reward_and_nothing_else():
    plain = _closing_episode(gym.make("simgrip/PickMultiFragile-v7"), 3)
    charged = _closing_episode(CrushCharge(gym.make("simgrip/PickMultiFragile-v7"), 7.5), 3)
    assert len(plain) == len(charged) and plain[-1][2] and charged[-1][2]  # both end in the crush
    for (o0, r0, c0, _), (o1, r1, c1, i1) in zip(plain, charged):
        assert np.array_equal(o0, o1) and c0 == c1
        assert r1 == (r0 - 7.5 if c1 else r0) and i1["reward_crush_charge"] == (-7.5 if c1 else 0.0)


def test_the_charge_starts_at_its_step_counted_over_episodes():
    env = CrushCharge(gym.make("simgrip/PickMultiFragile-v7"), 7.5, start=1)
    first = _closing_episode(env, 3)
    n = len(first)
    env.start = n + len(first)  # the second episode (the same seed: as long) crushes on its last step, step 2n - 1
    assert first[-1][2] and first[-1][3]["reward_crush_charge"] == -7.5 and env.steps == n  # crushed at n - 1 >= 1
    second = _closing_episode(env, 3)
    assert len(second) == n and second[-1][2] and second[-1][3]["reward_crush_charge"] == 0.0  # before its start
    env.start = 2 * n + n - 1  # the third episode's crush is its start: charged
    third = _closing_episode(env, 3)
    assert third[-1][3]["reward_crush_charge"] == -7.5 and third[-1][1] == second[-1][1] - 7.5 and env.steps == 3 * n


@pytest.mark.parametrize("kwargs, word", [
    ({"charge": -1.0}, "charge"), ({"charge": float("nan")}, "charge"), ({"charge": float("inf")}, "charge"),
    ({"charge": True}, "charge"), ({"charge": "1"}, "charge"),
    ({"charge": 1.0, "start": -1}, "start"), ({"charge": 1.0, "start": 1.5}, "start"),
    ({"charge": 1.0, "start": True}, "start"),
])
def test_bad_arguments_name_themselves(kwargs, word):
    with pytest.raises(ValueError, match=word):
        CrushCharge(gym.make("simgrip/PickFragile-v7"), **kwargs)


def test_a_task_without_a_crush_is_refused():
    with pytest.raises(ValueError, match="env"):
        CrushCharge(gym.make("simgrip/Pick-v1"), 1.0)


def test_crush_weight_is_each_crushs_discount_averaged_over_the_episodes():
    from simgrip.envs.evaluation import EpisodeResult

    # crushed on steps 1 and 3 (lengths 1 and 3: the crush is the last step), a success and a timeout not
    infos = [{"crushed": True}, {"crushed": True}, {"is_success": True}, {}]
    results = [EpisodeResult(i, i, 0.0, n, info) for i, (n, info) in enumerate(zip([1, 3, 2, 5], infos))]
    assert _example("evaluate_policy").crush_weight(results, 0.5) == pytest.approx((1.0 + 0.25) / 4, abs=1e-15)
    assert _example("evaluate_policy").crush_weight(results[2:], 0.5) == 0.0


def test_evaluate_policy_crush_charge_is_the_return_of_an_env_that_charges_it(capsys):
    """``--crush-charge F``'s return against the same controller run on the env with ``F`` charged on the crushing
    step by a wrapper (the discounted sum of its rewards, summed afresh)."""
    import gymnasium as gym

    from simgrip.envs.evaluation import run_episodes

    module = _example("evaluate_policy")
    # the cradle controller crushes seed 8011's piece and holds 8010's
    out = module.main(["--env", "simgrip/PickCradleFragile-v6", "--policy", "observation", "--episodes", "2",
                       "--seed", "8010", "--gamma", "0.98", "--crush-charge", "0", "10", "--json"])
    assert out["outcomes"] == {"crushed": 1, "success": 1} and set(out["crush_charged_return"]) == {"0", "10"}

    class Charged(gym.Wrapper):
        def step(self, action):
            obs, reward, terminated, truncated, info = self.env.step(action)
            return obs, reward - (10.0 if info["crushed"] else 0.0), terminated, truncated, info

    env = Charged(gym.make("simgrip/PickCradleFragile-v6"))
    act, on_reset = module._scripted(env, "observation")
    results = run_episodes(env, act, 2, 8010, on_reset=on_reset, gamma=0.98)
    env.close()
    crushed = [r for r in results if r.info["crushed"]]
    assert len(crushed) == 1 and out["crush_weight"] == pytest.approx(0.98 ** (crushed[0].length - 1) / 2, rel=1e-12)
    assert out["crush_charged_return"]["10"] == pytest.approx(sum(r.discounted for r in results) / 2, rel=1e-12)
    assert out["crush_charged_return"]["0"] == out["mean_discounted_return"]


@pytest.mark.parametrize("value", ["-1", "nan", "inf", "x"])
def test_evaluate_policy_refuses_a_bad_crush_charge(value, capsys):
    with pytest.raises(SystemExit) as e:
        _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v7", "--policy", "observation",
                                          "--crush-charge", value])
    assert e.value.code == 2 and "--crush-charge" in capsys.readouterr().err


def test_evaluate_policy_refuses_a_crush_charge_where_nothing_crushes(tmp_path, capsys):
    model = tmp_path / "model.zip"
    model.write_bytes(b"")  # never loaded: the option is refused first
    with pytest.raises(SystemExit) as e:
        _example("evaluate_policy").main(["--env", "simgrip/Pick-v1", "--model", str(model), "--crush-charge", "1"])
    assert e.value.code == 2 and "--crush-charge" in capsys.readouterr().err


def test_train_sb3_crush_charge_charges_the_training_crushes_from_its_step(tmp_path):
    """``--crush-charge 10``: one rollout (2048 steps, the policy not yet updated) runs the same training episodes as
    without it, each crushed one's return exactly 10 lower; ``--crush-charge-from 2048``: none charged yet.  The
    held-out evaluation runs the task's own reward, and the JSON records the option."""
    pytest.importorskip("stable_baselines3")
    import csv

    mod = _example("train_sb3")
    common = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--seed", "2", "--action-offset", "-0.4", "0.2",
              "--steps", "2048", "--eval-episodes", "1", "--eval-seed", "8330"]
    runs = {}
    for key, extra in (("plain", []), ("charged", ["--crush-charge", "10"]),
                       ("later", ["--crush-charge", "10", "--crush-charge-from", "2048"])):
        mod.main(common + extra + ["--out", str(tmp_path / key)])
        with open(tmp_path / key / "ppo_curve.csv", newline="") as f:
            runs[key] = [(float(r["episode_return"]), int(r["length"]), int(r["success"])) for r in csv.DictReader(f)]
        res = json.loads((tmp_path / key / "ppo_eval.json").read_text())
        if extra:
            assert res["crush_charge"] == {"charge": 10.0, "start": 2048 if key == "later" else 0}
            assert "CrushCharge(10.0" in res["wrapper"]
        else:
            assert "crush_charge" not in res
        runs[key + "_eval"] = (res["mean_return"], res["outcomes"])
    plain, charged = runs["plain"], runs["charged"]
    assert len(plain) == len(charged) > 3 and runs["later"] == plain
    diffs = [round(c[0] - p[0], 9) for p, c in zip(plain, charged)]
    assert [p[1:] for p in plain] == [c[1:] for c in charged] and set(diffs) == {0.0, -10.0}  # some crushed, not all
    assert runs["later_eval"] == runs["plain_eval"]  # the same rollout, the same update, the same policy
    # the charged run's policy differs (its update saw the charges), and its held-out crush is paid the task's own
    # reward: a crushed episode of v6 returns more than -w_crush = -2 (the lift it was paid is taken back), charged 10
    # it would return less than -8
    mean_return, outcomes = runs["charged_eval"]
    assert outcomes == {"crushed": 1} and mean_return > -2.0


def test_train_sb3_crush_charge_refusals_exit_2(tmp_path, capsys):
    for argv in (["--env", "simgrip/Pick-v1", "--crush-charge", "1"],
                 ["--env", "simgrip/PickFragile-v7", "--crush-charge", "-1"],
                 ["--env", "simgrip/PickFragile-v7", "--crush-charge", "nan"],
                 ["--env", "simgrip/PickFragile-v7", "--crush-charge-from", "10"],
                 ["--env", "simgrip/PickFragile-v7", "--crush-charge", "1", "--crush-charge-from", "-1"]):
        with pytest.raises(SystemExit) as e:
            _example("train_sb3").main(["--algo", "ppo", *argv, "--out", str(tmp_path / "o")])
        assert e.value.code == 2 and "--crush-charge" in capsys.readouterr().err.strip().splitlines()[-1]
