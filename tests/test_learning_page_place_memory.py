"""The learning page's runs of stop 74 against their records: the place's palm-alone command without the light bias,
the sphere's best screen at the pinch's discount with the best of validations kept, and the place and the sphere
given the first touch's memory (``docs/learning.md``, "The place with its palm the script's alone, without the light
bias", "The sphere's falling rate and step charge, with the pinch's discount and the best of validations kept", "The
first touch remembered", "The place with the first touch remembered, given twice the budget"; the helpers are ``test_learning_page.py``'s, the records' readers
``test_readme_tables.py``'s).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_learning_page import (_assert_seeds_on_page, _listed, checkpoint_rates, learning_paragraph,  # noqa: E402
                                seed_runs)
from test_learning_page_claws import _evaluation  # noqa: E402
from test_learning_page_cradle_touch import _options  # noqa: E402
from test_learning_page_place_light import HEAVY, LIGHT, PALM_ALONE, _count, controller  # noqa: E402, F401
from test_readme_tables import ROOT, aggregate, final_rates, joined  # noqa: E402

NO_LIGHT = "rl_place_v8_palm_alone_log_std_peak_gamma_select_screen"
NO_LIGHT_TITLE = "**The place with its palm the script's alone, without the light bias** (stop 74)."
MIDDLE = "18-68 g"


def test_the_palm_alone_screen_without_the_light_bias_is_its_record():
    """The palm-alone screen's options but the light bias; each seed's checkpoints, steps and crushes; the pieces
    of each third placed against the light-bias screen's (the final policies' ``evaluate_seedS.json``, whose
    outcomes are the runs')."""
    para = learning_paragraph(NO_LIGHT_TITLE)
    assert f"`docs/baselines/{NO_LIGHT}/`" in para
    assert _options(NO_LIGHT) == _options(PALM_ALONE, "light_bias") and "light_bias" not in aggregate(NO_LIGHT)
    assert aggregate(PALM_ALONE)["light_bias"] == 0.5 and aggregate(NO_LIGHT)["seeds"] == [0, 1]
    runs = seed_runs(NO_LIGHT, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert not any(r["success_rate"] >= 0.8 for r in runs) and "Not met, not adopted" in para
    evs, biased = [_evaluation(NO_LIGHT, k) for k in (0, 1)], [_evaluation(PALM_ALONE, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert {sum(e["by_mass"][LIGHT].values()) for e in evs} == {21}
    assert {sum(e["by_mass"][HEAVY].values()) for e in evs} == {17}
    assert (f"of the 17 heavy pieces the chosen policies place {_listed(_count(e, HEAVY, 'success') for e in evs)} "
            f"(behind the bias {_listed(_count(e, HEAVY, 'success') for e in biased)}), of the 21 light ones "
            f"{_listed(_count(e, LIGHT, 'success') for e in evs)} (behind the bias "
            f"{_listed(_count(e, LIGHT, 'success') for e in biased)})") in para
    assert f"seed 1 crushes {_count(evs[1], MIDDLE, 'crushed')} of the 12 in the middle third" in para
    assert _count(evs[0], MIDDLE, "crushed") == 0


def test_the_environments_page_lists_it_as_not_adopted():
    """The Gymnasium environments page's "Measured and not adopted" names the screen's final success."""
    page = joined(ROOT / "docs" / "environments.md")
    assert f"so without the light bias, {final_rates(NO_LIGHT)} %)" in page


SPHERE_CHARGE = "rl_sphere_v6_residual_palm_light_log_std_lr_decay_step_charge_screen"
SPHERE_SELECT = SPHERE_CHARGE.replace("_screen", "_gamma_select_screen")
SPHERE_TITLE = ("**The sphere's falling rate and step charge, with the pinch's discount and the best of validations "
                "kept**")


def test_the_spheres_charge_screen_with_the_discount_and_the_choice_is_its_record():
    """The sphere's screen: its base's options with the discount and the selection; each seed's checkpoints, steps
    and crushes; when and from what the choices came and what the last policies hold; the crushes in the touch's
    step against the base's (the final policies' ``evaluate_seedS.json``, whose outcomes are the runs')."""
    para = learning_paragraph(SPHERE_TITLE)
    assert f"`docs/baselines/{SPHERE_SELECT}/`" in para
    agg = aggregate(SPHERE_SELECT)
    assert _options(SPHERE_SELECT, "hyperparameters", "selection") == _options(SPHERE_CHARGE, "hyperparameters")
    assert agg["hyperparameters"] == aggregate(SPHERE_CHARGE)["hyperparameters"].replace(
        "; but log_std_init", "; but gamma = 0.995; but log_std_init")
    assert agg["selection"]["every_minutes"] == 1.0 and "selection" not in aggregate(SPHERE_CHARGE)
    assert agg["seeds"] == [0, 1]
    assert f"behind its aids: {final_rates(SPHERE_CHARGE)} %)" in para
    runs = seed_runs(SPHERE_SELECT, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert not any(r["success_rate"] >= 0.8 for r in runs) and "Not met, not adopted" in para
    chosen = [r["selection"]["validations"][r["selection"]["chosen"]] for r in runs]
    when = _listed(format(c["minutes"], ".1f") for c in chosen)
    assert f"choices came at {when} CPU-min" in para
    assert f"from {_listed(round(100 * c['success_rate']) for c in chosen)} % on the validation seeds" in para
    last = [round(100 * r["selection"]["last"]["success_rate"]) for r in runs]
    assert f"the last policies hold {_listed(last)} % held" in para and last[1] > 100 * runs[1]["success_rate"]
    evs = [_evaluation(SPHERE_SELECT, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    base = [_evaluation(SPHERE_CHARGE, k)["crushed_after_touch"]["0"] for k in (0, 1)]
    assert (f"{_listed(e['crushed_after_touch']['0'] for e in evs)} of the crushes come in the touch's step "
            f"({_listed(base)} without the discount and the choice)") in para
    page = joined(ROOT / "docs" / "environments.md")
    assert f"with the best of validations kept ({final_rates(SPHERE_SELECT)} %)" in page


MEMORY = "rl_place_v8_palm_alone_light_log_std_peak_gamma_select_touch_memory"
SPHERE_MEMORY = SPHERE_CHARGE.replace("_screen", "_touch_memory_screen")
MEMORY_TITLE = "**The first touch remembered (`--touch-memory`)** (stop 74)."


def test_the_place_given_the_first_touchs_memory_is_its_record():
    """The place's batch: the palm-alone screen's options with the memory; each seed's checkpoints, steps and
    crushes against the screen's; the heavy and light pieces placed, the touch's crushes of seed 1, the verdict and
    the last policies (the final policies' ``evaluate_seedS.json``, whose outcomes are the runs')."""
    para = learning_paragraph(MEMORY_TITLE)
    assert f"`docs/baselines/{MEMORY}/`" in para and "`tests/test_touch_memory.py`" in para
    agg = aggregate(MEMORY)
    assert _options(MEMORY, "touch_memory") == _options(PALM_ALONE) and agg["touch_memory"] is True
    assert agg["seeds"] == [0, 1, 2] and "touch_memory" not in aggregate(PALM_ALONE)
    runs, before = seed_runs(MEMORY, (0, 1, 2)), seed_runs(PALM_ALONE, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert f"against {_listed(checkpoint_rates(r) for r in before)} % without it" in para
    finals = [round(100 * r["success_rate"]) for r in runs]
    assert sum(x >= 80 for x in finals) == 1 and finals[0] == 80 and "Seed 0 ends at 80 %" in para
    assert "not met" in para
    evs, biased = [_evaluation(MEMORY, k) for k in (0, 1, 2)], [_evaluation(PALM_ALONE, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    heavy = _listed(_count(e, HEAVY, "success") for e in evs)
    assert (f"of the 17 pieces of 68–250 g the chosen policies place {heavy}"
            f" (without it {_listed(_count(e, HEAVY, 'success') for e in biased)})") in para
    assert not any(_count(e, HEAVY, k) for e in evs for k in ("timeout", "knocked_over"))
    assert (f"place {_listed(_count(e, LIGHT, 'success') for e in evs)} of the 21 pieces of 5–18 g (without it "
            f"{_listed(_count(e, LIGHT, 'success') for e in biased)})") in para
    assert (f"seed 1 crushes {evs[1]['crushed_after_touch']['0']} of its {_count(evs[1], LIGHT, 'crushed')} in the "
            f"touch's step") in para
    last = [round(100 * r["selection"]["last"]["success_rate"]) for r in runs]
    assert f"the last policies hold {_listed(last)} % held out (the chosen {_listed(finals)} %)" in para
    readme = joined(ROOT / "README.md")
    assert ("not on the place (given the first touch's memory, which its controller keeps and a feed-forward policy "
            f"cannot: {final_rates(MEMORY)} %) or the sphere") in readme


def test_the_sphere_given_the_first_touchs_memory_is_its_record():
    """The paragraph's sphere run: its recipe's options with the memory, its checkpoints, steps, crushes and those in
    the touch's step, against its recipe's seed 0."""
    para = learning_paragraph(MEMORY_TITLE)
    assert f"`docs/baselines/{SPHERE_MEMORY}/`" in para
    assert _options(SPHERE_MEMORY, "touch_memory") == _options(SPHERE_CHARGE)
    assert aggregate(SPHERE_MEMORY)["seeds"] == [0] and aggregate(SPHERE_MEMORY)["touch_memory"] is True
    run, = seed_runs(SPHERE_MEMORY, (0,))
    base, = seed_runs(SPHERE_CHARGE, (0,))
    assert (f"gives {checkpoint_rates(run)} % at 5 / 10 / 15 CPU-min, on {run['timesteps']:,} steps "
            f"({run['outcomes']['crushed']} crushes of 50 held out), against {round(100 * base['success_rate'])} % "
            "without it") in para
    ev = _evaluation(SPHERE_MEMORY, 0)
    assert ev["outcomes"] == run["outcomes"]
    assert f"({ev['crushed_after_touch']['0']} of the {run['outcomes']['crushed']} here)" in para
    page = joined(ROOT / "docs" / "environments.md")
    assert f"(`--touch-memory`, one seed: {final_rates(SPHERE_MEMORY)} %)" in page


MEMORY_30 = MEMORY + "_30min_screen"


def test_the_place_given_the_memory_and_twice_the_budget_is_its_record():
    """The batch's command at 30 CPU-minutes (its options but the budget), each seed's six checkpoints, steps and
    crushes, the choices (when, their validation success) and the last policies, the heavy pieces placed and the
    light ones crushed against the controller's (the final policies' ``evaluate_seedS.json``)."""
    para = learning_paragraph("**The place with the first touch remembered, given twice the budget** (stop 74).")
    assert f"`docs/baselines/{MEMORY_30}/`" in para
    assert _options(MEMORY_30, "minutes") == _options(MEMORY, "minutes") and aggregate(MEMORY_30)["minutes"] == 30.0
    runs = seed_runs(MEMORY_30, (0, 1))
    _assert_seeds_on_page(para, runs, span="… / 30")
    assert not any(c["success_rate"] >= 0.8 for r in runs for c in r["checkpoints"]) and "Not met" in para
    sels = [r["selection"] for r in runs]
    chosen = [s["validations"][s["chosen"]] for s in sels]
    assert all(len(s["validations"]) == 30 for s in sels)
    assert (f"The choices came at {_listed(format(c['minutes'], '.1f') for c in chosen)} CPU-min, from "
            f"{_listed(round(100 * c['success_rate']) for c in chosen)} % on the validation seeds, and the last "
            f"policies hold {_listed(round(100 * s['last']['success_rate']) for s in sels)} % held out") in para
    evs = [_evaluation(MEMORY_30, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert f"({_listed(_count(e, HEAVY, 'success') for e in evs)} of the 17 placed)" in para
    assert f"({_listed(_count(e, LIGHT, 'crushed') for e in evs)} of the 21 crushed)" in para


def test_the_controller_crushes_one_light_piece(controller):
    """The paragraph's comparison, measured again (``test_learning_page_place_light.controller``: the place's
    scripted observation-only controller on the held-out seeds), the pieces of 5-18 g it crushes."""
    para = learning_paragraph("**The place with the first touch remembered, given twice the budget** (stop 74).")
    assert f"the scripted observation-only controller crushes {_count(controller, LIGHT, 'crushed')} of them" in para
