"""The learning page's screens of stop 72 against their records: the cradle's recipe with a charge near the crush,
the cradle with its palm the script's alone at half the valve's rate, and the cradle at the pinch's discount with the
best of validations kept (``docs/learning.md``; the helpers are ``test_learning_page.py``'s, the records' readers
``test_readme_tables.py``'s).

The scripted observation-only controller's first touches and successes, which the paragraphs set the learners
against, are measured here again with ``evaluate_policy.py``'s own command on the held-out seeds 8000-8049.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from helpers import load_example  # noqa: E402
from test_learning_page import (_assert_seeds_on_page, _listed, checkpoint_rates, learning_paragraph,  # noqa: E402
                                seed_runs)
from test_learning_page_claws import _evaluation  # noqa: E402
from test_readme_tables import ROOT, aggregate, final_rates, joined  # noqa: E402

RECIPE = "rl_cradle_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen"
MARGIN = "rl_cradle_v6_palm_alone_light_log_std_lr_decay_step_charge_share025_crush_margin_screen"
HALF = "rl_cradle_v6_residual_palm_light_log_std_lr_decay_share05_screen"
ALONE_HALF = "rl_cradle_v6_palm_alone_light_log_std_lr_decay_share05_screen"
GAMMA = "rl_cradle_v6_residual_palm_light_log_std_peak_gamma_screen"
SELECT = "rl_cradle_v6_residual_palm_light_log_std_peak_gamma_select"
IGNORED = ("command", "summary", "combined_from", "versions", "seeds")


@pytest.fixture(scope="module")
def controller():
    """``evaluate_policy.py --env simgrip/PickCradleFragile-v6 --policy observation --episodes 50 --seed 8000
    --json``: the scripted observation-only controller on the held-out seeds."""
    return load_example("evaluate_policy", "_cradle_touch").main(
        ["--env", "simgrip/PickCradleFragile-v6", "--policy", "observation", "--episodes", "50", "--seed", "8000",
         "--json"])


def _options(folder: str, *drop: str) -> dict:
    return {k: v for k, v in aggregate(folder).items() if k not in IGNORED + drop}


def _selection_paragraph() -> str:
    """"The cradle at the pinch's discount, with the best of validations kept", cut at the next paragraph's title
    (its own "**met**" would end :func:`learning_paragraph`'s cut)."""
    page = joined(ROOT / "docs" / "learning.md")
    title = "**The cradle at the pinch's discount, with the best of validations kept** (stop 72)."
    return page[page.index(title):page.index("**The cradle's recipe on the place, and the light pieces' share**")]


def _pct(x: float) -> str:
    return f"{x:.2f}"


def test_the_crush_margin_screen_is_its_record():
    """"The cradle's recipe with a charge near the crush": the recipe's options with the restrictor in place of the
    valve's keyword argument (a quarter: the same task bit for bit) and the charge, each seed's checkpoints, steps and
    crushes, the recipe's seeds it is set against, where its crushes come and by how much seed 1's overrun."""
    para = learning_paragraph("**The cradle's recipe with a charge near the crush**")
    assert f"`docs/baselines/{MARGIN}/`" in para
    agg, ref = aggregate(MARGIN), aggregate(RECIPE)
    assert ref["env_kwargs"] == {"kappa_rate": 0.005} and "env_kwargs" not in agg
    assert agg["valve_share"] == 0.25 and agg["crush_margin"] == 0.2 and agg["seeds"] == [0, 1]
    assert _options(MARGIN, "valve_share", "crush_margin") == _options(RECIPE, "env_kwargs")
    runs = seed_runs(MARGIN, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert f"against {_listed(checkpoint_rates(r) for r in seed_runs(RECIPE, (0, 1)))} % without the charge" in para
    evs = [_evaluation(MARGIN, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    after = [e["crushed_after_touch"] for e in evs]
    assert (f"{_listed(a['0'] for a in after)} in the touch's step, {_listed(a['5-24'] for a in after)} five to 24 "
            f"steps after it, {_listed(a['25+'] for a in after)} later still") in para
    crushed = runs[1]["outcomes"]["crushed"]
    assert f"seed 1 crushes {crushed} of 50 held-out pieces, over the limit by a median " \
           f"{100 * evs[1]['crush_overrun']['median']:.1f} %" in para
    assert f"(the K fingers with the same charge: " \
           f"{final_rates('rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge_crush_margin')} %, the place: " \
           f"{final_rates('rl_place_v8_residual_palm_log_std_crush_margin_screen')} %)" in para
    assert max(r["success_rate"] for r in runs) < 0.8 and "not adopted" in para


def test_the_palm_alone_half_rate_screen_is_its_record(controller):
    """"The cradle with its palm the script's alone at half the rate": the half-rate command's options with the palm
    the script's alone (the policy's action the curvature's only), each seed's checkpoints, steps and crushes, the
    half-rate screen with the palm's correction it is set against, and the crushes and first touches of both against
    the scripted controller's (measured again here)."""
    para = learning_paragraph("**The cradle with its palm the script's alone at half the rate**")
    assert f"`docs/baselines/{ALONE_HALF}/`" in para
    agg = aggregate(ALONE_HALF)
    assert agg["residual_alone"] is True and agg["action_offset"] == [-0.4] and agg["seeds"] == [0, 1]
    assert aggregate(HALF)["action_offset"] == [-0.4, 0.0]
    assert _options(ALONE_HALF, "residual_alone", "action_offset") == _options(HALF, "action_offset")
    runs = seed_runs(ALONE_HALF, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert f"against {_listed(checkpoint_rates(r) for r in seed_runs(HALF, (0, 1)))} % with the palm's correction" \
        in para
    evs = [_evaluation(ALONE_HALF, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    before = [_evaluation(HALF, k)["crushed_after_touch"]["0"] for k in (0, 1)]
    assert (f"as many crushes come in the touch's step ({_listed(e['crushed_after_touch']['0'] for e in evs)}, "
            f"against {_listed(before)})") in para
    touch = [e["first_touch"] for e in evs]
    assert (f"a median {_listed(_pct(t['read']['median']) for t in touch)} of the limit (at most "
            f"{_listed(_pct(t['read']['max']) for t in touch)})") in para
    first = controller["first_touch"]
    assert first["touches"] == 50 and first["above_limit"] == 0 and controller["crushed_after_touch"]["0"] == 0
    assert (f"against the controller's {_pct(first['read']['median'])} (at most {_pct(first['read']['max'])}; none "
            f"above the limit, no crush in the touch's step") in para
    assert min(t["read"]["median"] for t in touch) > first["read"]["median"]
    assert max(r["success_rate"] for r in runs) < 0.8 and "not adopted" in para


def test_the_environments_page_lists_them_as_measured_and_not_adopted():
    page = joined(ROOT / "docs" / "environments.md")
    assert (f"the cradle's recipe with a charge near the crush (`--crush-margin 0.2`: {final_rates(MARGIN)} %) and "
            f"with its palm the script's alone at half the valve's rate ({final_rates(ALONE_HALF)} %)") in page


def test_the_discount_and_selection_screens_are_their_records(controller):
    """"The cradle at the pinch's discount, with the best of validations kept": the screen's options (the aided
    command's, with the pinch's start and discount), the selection batches' (the same with ``--select-every 1``),
    each seed's checkpoints, steps and crushes, the verdict, the chosen and last policies' held-out success and
    when each was chosen, and seed 0's chosen policy against the controller."""
    para = _selection_paragraph()
    base = aggregate("rl_cradle_v6_residual_palm_light_log_std")
    agg = aggregate(GAMMA)
    assert agg["action_offset"] == [-0.2, 0.0] and base["action_offset"] == [-0.4, 0.0]
    assert agg["hyperparameters"] == base["hyperparameters"].replace("; but log_std",
                                                                      "; but gamma = 0.995; but log_std")
    assert _options(GAMMA, "action_offset", "hyperparameters") == _options(
        "rl_cradle_v6_residual_palm_light_log_std", "action_offset", "hyperparameters")
    runs = seed_runs(GAMMA, (0, 1))
    _assert_seeds_on_page(para, runs)
    peak = seed_runs("rl_cradle_v6_residual_palm_light_log_std_peak_screen", (0, 1))
    assert f"against {_listed(checkpoint_rates(r) for r in peak)} % at γ 0.99" in para
    for folder, seeds in ((SELECT, (0, 1, 2)), (SELECT + "_3", (3,))):
        assert f"`docs/baselines/{folder}/`" in para and aggregate(folder)["seeds"] == list(seeds)
        assert _options(folder, "selection") == _options(GAMMA)
        assert aggregate(folder)["selection"] == {"every_minutes": 1.0, "episodes": 50, "seeds": [20000, 20049]}
    chosen = seed_runs(SELECT, (0, 1, 2)) + seed_runs(SELECT + "_3", (3,))
    _assert_seeds_on_page(para, chosen[:3])
    assert f"seed 3, {checkpoint_rates(chosen[3])} % on {chosen[3]['timesteps']:,} steps" in para
    finals = [r["success_rate"] for r in chosen[:3]]
    assert sum(x >= 0.8 for x in finals) == 2 and "**met**, seeds 0 and 2 at 90 and 82 %" in para
    picks = [r["selection"]["validations"][r["selection"]["chosen"]] for r in chosen]
    assert (f"the policies chosen score {_listed(round(100 * r['success_rate']) for r in chosen)} % held out (chosen "
            f"at {_listed(format(v['minutes'], '.1f') for v in picks)} CPU-min, at "
            f"{_listed(round(100 * v['success_rate']) for v in picks)} % on the validation seeds), the last ones "
            f"{_listed(round(100 * r['selection']['last']['success_rate']) for r in chosen)} %") in para
    assert not any(r["selection"]["last"]["success_rate"] >= 0.8 for r in chosen[:3])  # "without it no seed of 0-2"
    assert {round(r["selection"]["cpu_s"]) for r in chosen} <= set(range(50, 53))  # "50–52 s of each budget"
    evs = [_evaluation(SELECT, k) for k in (0, 1, 2)] + [_evaluation(SELECT + "_3", 3)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in chosen]
    wins = controller["outcomes"]["success"]
    assert evs[0]["outcomes"]["success"] == wins == 45 and f"holds {wins} of the 50 held-out" in para
    assert f"crushes {evs[0]['crushed_after_touch']['0']} in the touch's step, where the controller crushes none" \
        in para and controller["crushed_after_touch"]["0"] == 0


def test_the_recipe_on_the_sphere_is_its_record():
    """The same paragraph's last sentences: the cradle's selection command on the sphere (its options the cradle
    batch's but the id), each seed's checkpoints, steps and crushes, and those in the touch's step."""
    para = _selection_paragraph()
    folder = "rl_sphere_v6_residual_palm_light_log_std_peak_gamma_select_screen"
    assert f"`docs/baselines/{folder}/`" in para and aggregate(folder)["env"] == "simgrip/PickSphereFragile-v6"
    assert _options(folder, "env") == _options(SELECT, "env") and aggregate(folder)["seeds"] == [0, 1]
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs)
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert f"{_listed(e['crushed_after_touch']['0'] for e in evs)} of them in the touch's step: not adopted" in para
    assert max(r["success_rate"] for r in runs) < 0.8
