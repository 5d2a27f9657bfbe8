"""The learning page's paragraphs of stop 70 against their records: the restrictor between the policy and the valve
(``--valve-share``) and the screens run with it or with the valve it stands for (``docs/learning.md``; the helpers
are ``test_learning_page.py``'s, the records' readers ``test_readme_tables.py``'s).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_learning_page import (_assert_long_run, _assert_seeds_on_page, _listed, checkpoint_rates,  # noqa: E402
                                learning_paragraph, seed_runs)
from test_learning_page_claws import _evaluation  # noqa: E402
from test_readme_tables import ROOT, aggregate, final_rates, joined, pct  # noqa: E402

BASELINES = ROOT / "docs" / "baselines"
CRADLE_RECIPE = "rl_cradle_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen"


def test_the_restrictor_stands_for_every_restricted_valve_screen():
    """"A restrictor between the policy and the valve": every screen run with the valve restricted (``kappa_rate``
    at 1/2 or 1/4 of 0.02) leaves the curvature to the policy, where ``tests/test_valve_share.py`` shows the
    restrictor at that share to step bit for bit as that valve."""
    para = learning_paragraph("**A restrictor between the policy and the valve (`--valve-share`)**")
    assert "`tests/test_valve_share.py`" in para and (ROOT / "tests" / "test_valve_share.py").is_file()
    assert "for `S` = 1/2 and 1/4" in para
    restricted = [f.name for f in BASELINES.iterdir() if (f / "aggregate.json").is_file()
                  and aggregate(f.name).get("env_kwargs", {}).get("kappa_rate", 0.02) < 0.02]  # (25 Hz: 0.04)
    assert len(restricted) >= 8
    for folder in restricted:
        agg = aggregate(folder)
        assert agg["env_kwargs"] == {"kappa_rate": agg["env_kwargs"]["kappa_rate"]}, folder  # nothing else changed
        assert agg["env_kwargs"]["kappa_rate"] in (0.01, 0.005), folder
        assert "curvature" not in agg.get("residual", []), folder  # the curvature is the policy's


def test_the_spheres_recipe_on_the_cradle_is_its_record():
    """"The sphere's recipe on the cradle": its options, seeds, checkpoints, steps and crushes, the records it is
    set against, and where its crushes come (its final policies' ``evaluate_seedS.json``, whose outcomes are the
    runs')."""
    para = learning_paragraph("**The sphere's recipe on the cradle**")
    assert f"docs/baselines/{CRADLE_RECIPE}/" in para
    agg = aggregate(CRADLE_RECIPE)
    assert agg["env"] == "simgrip/PickCradleFragile-v6" and agg["env_kwargs"] == {"kappa_rate": 0.005}
    assert agg["residual"] == ["palm_z"] and agg["residual_alone"] and agg["action_offset"] == [-0.8]
    assert agg["step_charge"] == 0.005 and agg["light_bias"] == 0.5 and agg["seeds"] == [0, 1]
    assert agg["hyperparameters"].endswith("log_std_init = -1.0; but the learning rate falls linearly to 0 over the "
                                           "budget")
    sphere = aggregate(CRADLE_RECIPE.replace("cradle", "sphere"))
    assert {k: v for k, v in agg.items() if k not in ("env", "command", "summary", "combined_from", "versions")} == \
        {k: v for k, v in sphere.items() if k not in ("env", "command", "summary", "combined_from", "versions")}
    runs = seed_runs(CRADLE_RECIPE, (0, 1))
    _assert_seeds_on_page(para, runs, crushes_end="),")
    assert f"against {final_rates('rl_cradle_v6_residual_palm_light_log_std')} % for the cradle's record and " \
           f"{final_rates('rl_cradle_v6_residual_palm_light_log_std_valve01_screen')} % at half the rate" in para
    evs = [_evaluation(CRADLE_RECIPE, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    heavy = [e["by_mass"]["74-200 g"] for e in evs]
    assert f"({_listed(h['success'] for h in heavy)} of {sum(heavy[0].values())})" in para
    after = [e["crushed_after_touch"] for e in evs]
    assert f"({_listed(a['0'] for a in after)} in the touch's step)" in para
    assert f"({_listed(a['5-24'] for a in after)} five to 24 steps after the first touch)" in para
    assert all(a["5-24"] > a["0"] + a["1-4"] + a.get("25+", 0) for a in after)  # "most come in the squeeze"
    assert sum(h.get("crushed", 0) for h in heavy) == 1  # "all but one on the lighter two thirds"
    page = joined(ROOT / "docs" / "environments.md")
    assert (f"On the cradle the same recipe gives {final_rates(CRADLE_RECIPE)} % (`{CRADLE_RECIPE}`; the learning "
            "page, \"The sphere's recipe on the cradle\")") in page
    assert "it is the registered task behind a restrictor, `--valve-share 0.5`, bit for bit" in page


def test_the_spheres_recipe_given_twice_the_budget_is_its_record():
    """"The sphere's recipe given twice the budget, behind the restrictor": the 15-minute screen's options with the
    restrictor in place of the valve's keyword argument (so the registered task), each seed's six checkpoints,
    steps and crushes, none at 80 %, the first touches alike, and seed 1's light pieces crushed in the squeeze."""
    title = "**The sphere's recipe given twice the budget, behind the restrictor**"
    folder = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_share025_30min_screen"
    _assert_long_run(title, folder, 30, (0, 1))
    agg = aggregate(folder)
    screen = aggregate("rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen")
    assert "env_kwargs" not in agg and agg["valve_share"] == 0.25 and screen["env_kwargs"] == {"kappa_rate": 0.005}
    same = ("env", "action_offset", "residual", "residual_alone", "light_bias", "step_charge", "hyperparameters")
    assert {k: agg[k] for k in same} == {k: screen[k] for k in same}
    runs = seed_runs(folder, (0, 1))
    assert max(c["success_rate"] for r in runs for c in r["checkpoints"]) < 0.8  # "no checkpoint of either at 80 %"
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    para = learning_paragraph(title)
    assert evs[0]["first_touch"] == evs[1]["first_touch"]  # "their first touches read the same"
    assert f"a median {evs[0]['first_touch']['read']['median']:.2f} of the limit" in para
    light = evs[1]["by_mass"]["10-27 g"]
    assert f"{light['crushed']} of the {sum(light.values())} lightest crushed" in para
    crushed = evs[1]["outcomes"]["crushed"]
    assert f"{evs[1]['crushed_after_touch']['5-24']} of its {crushed} crushes five to 24 steps after the touch" in para
    page = joined(ROOT / "docs" / "environments.md")
    at15 = " / ".join(str(round(100 * r["checkpoints"][2]["success_rate"])) for r in runs)
    assert f"ends at {final_rates(folder)} % (at 15 CPU-min {at15} %) (`{folder}`;" in page


def test_the_cradle_at_half_the_rate_behind_the_restrictor_is_its_record():
    """"The cradle at half the rate behind the restrictor, with the learning rate falling": the half-rate screen's
    options with the restrictor in place of the valve's keyword argument and the falling rate, each seed's
    checkpoints, steps and crushes, the screen it is set against (the same mean), and the crushes in the touch's
    step."""
    title = "**The cradle at half the rate behind the restrictor, with the learning rate falling**"
    folder = "rl_cradle_v6_residual_palm_light_log_std_lr_decay_share05_screen"
    para = learning_paragraph(title)
    assert f"docs/baselines/{folder}/" in para
    agg, half = aggregate(folder), aggregate("rl_cradle_v6_residual_palm_light_log_std_valve01_screen")
    assert "env_kwargs" not in agg and agg["valve_share"] == 0.5 and half["env_kwargs"] == {"kappa_rate": 0.01}
    same = ("env", "action_offset", "residual", "light_bias", "seeds")
    assert {k: agg[k] for k in same} == {k: half[k] for k in same} and "residual_alone" not in agg
    assert agg["hyperparameters"] == half["hyperparameters"] + "; but the learning rate falls linearly to 0 over the " \
                                                               "budget"
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs, crushes_end="),")
    assert f"against {final_rates('rl_cradle_v6_residual_palm_light_log_std_valve01_screen')} % at the same rate" \
        in para

    def mean(f):
        return round(100 * aggregate(f)["summary"]["ppo"]["final"]["mean"])

    assert f"a mean of {mean(folder)} % against {mean('rl_cradle_v6_residual_palm_light_log_std_valve01_screen')} %" \
        in para
    spread = {f: aggregate(f)["summary"]["ppo"]["final"] for f in (folder, "rl_cradle_v6_residual_palm_light_log_std_"
                                                                       "valve01_screen")}
    ours, theirs = (s["max"] - s["min"] for s in spread.values())
    assert ours < theirs  # "with less spread"
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    touch = [e["crushed_after_touch"]["0"] for e in evs]
    assert f"Half its crushes ({_listed(touch)}) come in the touch's step" in para
    assert all(2 * t >= e["outcomes"]["crushed"] - 1 for t, e in zip(touch, evs))  # half, to within one


def test_the_spheres_recipe_behind_the_restrictor_is_its_batch():
    """"The sphere's recipe behind the restrictor, seeds 0–2": the screen's options with the restrictor in place of
    the valve's keyword argument, each seed's checkpoints, steps and crushes, the means set against each other, and
    seed 0's crushes (its final policy's ``evaluate_seed0.json``)."""
    title = "**The sphere's recipe behind the restrictor, seeds 0–2**"
    folder = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_share025"
    screen = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen"
    para = learning_paragraph(title)
    assert f"docs/baselines/{folder}/" in para
    agg, scr = aggregate(folder), aggregate(screen)
    assert "env_kwargs" not in agg and agg["valve_share"] == 0.25 and agg["seeds"] == [0, 1, 2]
    same = ("env", "action_offset", "residual", "residual_alone", "light_bias", "step_charge", "hyperparameters",
            "minutes")
    assert {k: agg[k] for k in same} == {k: scr[k] for k in same}
    runs = seed_runs(folder, (0, 1, 2))
    _assert_seeds_on_page(para, runs, crushes_end="):")
    means = [round(100 * aggregate(f)["summary"]["ppo"]["final"]["mean"]) for f in (folder, screen)]
    assert f"a mean of {means[0]} % where the screen's two seeds gave {means[1]} %" in para
    finals = [pct(r["success_rate"]) for r in runs]
    assert f"this recipe's seeds spread from {min(finals)} to {max(finals)} %" in para
    evs = [_evaluation(folder, k) for k in (0, 1, 2)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    lighter = [v for k, v in evs[0]["by_mass"].items() if k != "74-200 g"]
    n = sum(sum(v.values()) for v in lighter)
    assert all(set(v) == {"crushed"} for v in lighter) and f"Seed 0 crushes all {n} pieces of its lighter" in para
    assert (f"{evs[0]['crushed_after_touch']['5-24']} of its {evs[0]['outcomes']['crushed']} crushes five to 24 steps "
            "after the touch") in para


def test_the_spheres_recipe_on_the_place_is_its_record():
    """"The sphere's recipe on the place": one seed's checkpoints, steps and crushes, the place's record it is set
    against, and where its crushes come (``evaluate_seed0.json``)."""
    folder = "rl_place_v8_palm_alone_log_std_lr_decay_step_charge_share025_screen"
    para = learning_paragraph("**The sphere's recipe on the place**")
    assert f"docs/baselines/{folder}/" in para
    agg = aggregate(folder)
    assert agg["env"] == "simgrip/PlaceFragile-v8" and agg["seeds"] == [0] and "env_kwargs" not in agg
    assert agg["residual"] == ["palm_x", "palm_z"] and agg["residual_alone"] and agg["valve_share"] == 0.25
    assert agg["step_charge"] == 0.005 and "light_bias" not in agg
    (run,) = seed_runs(folder, (0,))
    assert f"{checkpoint_rates(run)} % at 5 / 10 / 15 CPU-min, on {run['timesteps']:,} steps " \
           f"({run['outcomes']['crushed']} crushes of 50 held out)" in para
    assert f"against {final_rates('rl_place_v8_residual_palm_log_std')} % for the place's record" in para
    ev = _evaluation(folder, 0)
    assert ev["outcomes"] == run["outcomes"]
    lighter = [v for k, v in ev["by_mass"].items() if k != "68-250 g"]
    assert all(set(v) == {"crushed"} for v in lighter)  # "every piece of its lighter two thirds is crushed"
    late = ev["crushed_after_touch"]["5-24"] + ev["crushed_after_touch"]["25+"]
    assert f"{late} of the {run['outcomes']['crushed']} crushes five or more steps after the touch" in para


def test_the_environments_page_gives_the_restrictor_batch():
    folder = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_share025"
    screen = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen"
    page = joined(ROOT / "docs" / "environments.md")
    assert (f"the sphere's recipe gives {final_rates(folder)} % over seeds 0–2 (`{folder}`; the learning page, "
            f"\"The sphere's recipe behind the restrictor, seeds 0–2\"): the screen's {final_rates(screen)} % was "
            "the good end of a wide spread") in page
