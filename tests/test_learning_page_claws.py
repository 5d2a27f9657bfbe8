"""The learning page's screens of the claws (stop 68) against their records: the cradle and the sphere on four copies
with minibatches of 128, and the sphere behind the K fingers' falling rate and step charge (``docs/learning.md``;
the helpers are ``test_learning_page.py``'s, the records' readers ``test_readme_tables.py``'s).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_learning_page import _assert_seeds_on_page, learning_paragraph, seed_runs  # noqa: E402
from test_readme_tables import BASELINES, ROOT, aggregate, final_rates, joined, measured_as, pct  # noqa: E402


def _evaluation(folder: str, seed: int) -> dict:
    """The record ``folder``'s ``evaluate_seed<seed>.json``: its final policy run again on the held-out seeds."""
    return json.loads((BASELINES / folder / f"evaluate_seed{seed}.json").read_text(encoding="utf-8"))


def test_the_claws_four_copies_screens_are_their_records():
    """"The claws on four copies with minibatches of 128": each claw's two-seed screen (its command's options, each
    seed's checkpoints, steps and crushes), the crushes within four steps of the first touch and those of the
    heaviest third (the final policies' ``evaluate_seedS.json``, whose success is the run's), and the records the
    screens are set against (their per-seed finals and their steps)."""
    para = learning_paragraph("**The claws on four copies with minibatches of 128**")
    touch, heavy = [], []
    for task, env in (("cradle", "PickCradleFragile-v6"), ("sphere", "PickSphereFragile-v6")):
        record = f"rl_{task}_v6_residual_palm_light_log_std"
        folder = f"{record}_4envs_512_batch128_screen"
        assert f"docs/baselines/{folder}/" in para
        agg = aggregate(folder)
        assert agg["seeds"] == [0, 1] and agg["minutes"] == 15.0 and agg["n_envs"] == 4 and measured_as(agg) == env
        assert agg["hyperparameters"].endswith("; but log_std_init = -1.0; but n_steps = 512; but batch_size = 128")
        assert agg["residual"] == ["palm_z"] and agg["light_bias"] == 0.5 and agg["action_offset"] == [-0.4, 0.0]
        runs = seed_runs(folder, (0, 1))
        _assert_seeds_on_page(para, runs)
        for k, run in enumerate(runs):
            ev = _evaluation(folder, k)
            assert ev["eval_seeds"] == [8000, 8049] and ev["success_rate"] == run["success_rate"]
            assert ev["outcomes"] == run["outcomes"]
            after = ev["crushed_after_touch"]
            touch.append(f"{after['0']} and {after['1-4']} of {ev['outcomes']['crushed']}")
            heavy.append(ev["by_mass"]["74-200 g"])
        final = aggregate(record)["summary"]["ppo"]["final"]
        steps = f"{round(min(final['timesteps']), -3) // 1000}k–{round(max(final['timesteps']), -3) // 1000}k steps"
        assert f"record's {final_rates(record)} % " in para and steps in para
    assert (f"{touch[0]} and {touch[1]} on the cradle, {touch[2]} and {touch[3]} on the sphere" in para)
    peak = [_evaluation("rl_sphere_v6_residual_palm_light_log_std_peak_screen", k)["by_mass"]["74-200 g"]["crushed"]
            for k in (0, 1)]
    assert (f"{heavy[2]['crushed']} and {heavy[3]['crushed']} of its {sum(heavy[2].values())} pieces, against "
            f"{peak[0]} and {peak[1]} for the peak screen's policies" in para)
    assert sum(heavy[2].values()) == sum(heavy[3].values())
    # the environments page's sentence: the screens' steps and finals
    screens = [f"rl_{t}_v6_residual_palm_light_log_std_4envs_512_batch128_screen" for t in ("cradle", "sphere")]
    steps = [s for f in screens for s in aggregate(f)["summary"]["ppo"]["final"]["timesteps"]]
    finals = [final_rates(f) for f in screens]
    page = joined(ROOT / "docs" / "environments.md")
    assert (f"twice their records' steps ({min(steps) / 1e6:.2f}M–{max(steps) / 1e6:.2f}M) and leave them where they "
            f"were: {finals[0]} % on the cradle and {finals[1]} % on the sphere") in page


def test_the_spheres_falling_rate_and_step_charge_screen_is_its_record():
    """"The sphere with the K fingers' falling rate and step charge": its options, each seed's checkpoints, steps and
    crushes, the crushes of the heaviest third and in the touch's step (``evaluate_seedS.json``, whose outcomes are
    the run's), and the record's finals it is set against."""
    folder = "rl_sphere_v6_residual_palm_light_log_std_lr_decay_step_charge_screen"
    para = learning_paragraph("**The sphere with the K fingers' falling rate and step charge**")
    assert f"docs/baselines/{folder}/" in para
    agg = aggregate(folder)
    assert agg["seeds"] == [0, 1] and agg["minutes"] == 15.0 and measured_as(agg) == "PickSphereFragile-v6"
    assert agg["hyperparameters"] == ("Stable-Baselines3 defaults, one env, one torch thread; but log_std_init = -1.0; "
                                      "but the learning rate falls linearly to 0 over the budget")
    assert agg["step_charge"] == 0.005 and agg["residual"] == ["palm_z"] and agg["light_bias"] == 0.5
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert all(c1["success_rate"] >= c0["success_rate"] for r in runs for c0, c1 in zip(r["checkpoints"],
                                                                                        r["checkpoints"][1:]))
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    heavy = [e["by_mass"]["74-200 g"] for e in evs]
    assert f"({heavy[0]['crushed']} and {heavy[1]['crushed']} of its {sum(heavy[0].values())} pieces" in para
    assert sum(heavy[0].values()) == sum(heavy[1].values())
    assert f"({evs[0]['crushed_after_touch']['0']} and {evs[1]['crushed_after_touch']['0']} of the crushes" in para
    assert f"against its record's {final_rates('rl_sphere_v6_residual_palm_light_log_std')} %." in para
    finals = " / ".join(str(pct(r["success_rate"])) for r in runs)
    assert f"behind the sphere's aids: {finals} %" in joined(ROOT / "docs" / "environments.md")
    # the K fingers' whole recipe: the same on four copies with minibatches of 128
    four = folder.replace("_screen", "_4envs_512_batch128_screen")
    assert f"docs/baselines/{four}/" in para
    agg = aggregate(four)
    assert agg["seeds"] == [0, 1] and agg["n_envs"] == 4 and agg["step_charge"] == 0.005
    assert agg["hyperparameters"].endswith("n_steps = 512; but batch_size = 128; but the learning rate falls linearly "
                                           "to 0 over the budget")
    runs = seed_runs(four, (0, 1))
    _assert_seeds_on_page(para, runs, crushes_end="),")
    touch = [_evaluation(four, k)["crushed_after_touch"]["0"] for k in (0, 1)]
    assert f"{touch[0]} and {touch[1]} of the crushes in the touch's step: the same as on one copy" in para
    finals = " / ".join(str(pct(r["success_rate"])) for r in runs)
    assert f"and {finals} % on four copies with minibatches of 128 as well" in joined(ROOT / "docs" / "environments.md")
