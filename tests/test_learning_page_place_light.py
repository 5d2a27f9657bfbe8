"""The learning page's screens of stop 73 against their records: the cradle's recipe on the place at the light bias
of 0.5 and of 0.25, and the sphere's recipe behind the restrictor at half the valve's rate (``docs/learning.md``,
"The cradle's recipe on the place, and the light pieces' share"; the helpers are ``test_learning_page.py``'s, the
records' readers ``test_readme_tables.py``'s).

The place's scripted observation-only controller, which the paragraph sets the learners against, is measured here
again with ``evaluate_policy.py``'s own command on the held-out seeds 8000-8049.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from helpers import load_example  # noqa: E402
from test_learning_page import _assert_seeds_on_page, _listed, learning_paragraph, seed_runs  # noqa: E402
from test_learning_page_claws import _evaluation  # noqa: E402
from test_learning_page_cradle_touch import _options  # noqa: E402
from test_readme_tables import aggregate, final_rates  # noqa: E402

TITLE = "**The cradle's recipe on the place, and the light pieces' share** (stop 73;"
CRADLE_SELECT = "rl_cradle_v6_residual_palm_light_log_std_peak_gamma_select"
SPHERE_SELECT = "rl_sphere_v6_residual_palm_light_log_std_peak_gamma_select_screen"
PLACE_HALF = "rl_place_v8_residual_palm_light_log_std_peak_gamma_select_screen"
PLACE_QUARTER = "rl_place_v8_residual_palm_light25_log_std_peak_gamma_select"
SPHERE_SHARE = "rl_sphere_v6_residual_palm_light_log_std_peak_gamma_select_share05_screen"
#: the stop-62 place screens whose light pieces' crushes the paragraph opens with (two seeds each)
PLACE_STOP62 = ("rl_place_v8_residual_palm_log_std_peak_screen", "rl_place_v8_residual_palm_log_std_rerun_screen",
                "rl_place_v8_residual_palm_log_std_crush_margin_screen")
LIGHT, HEAVY = "5-18 g", "68-250 g"


@pytest.fixture(scope="module")
def controller():
    """``evaluate_policy.py --env simgrip/PlaceFragile-v8 --policy observation --episodes 50 --seed 8000 --json``:
    the place's scripted observation-only controller on the held-out seeds."""
    return load_example("evaluate_policy", "_place_light").main(
        ["--env", "simgrip/PlaceFragile-v8", "--policy", "observation", "--episodes", "50", "--seed", "8000",
         "--json"])


def _count(ev: dict, bin_: str, outcome: str) -> int:
    return ev["by_mass"][bin_].get(outcome, 0)


def test_the_place_screens_are_the_cradles_recipe(controller):
    """The place's screens: the cradle's selection batch's options but the id, its three-entry offset and its
    palm's two residual channels (at the light bias of 0.5, and of 0.25 in the three-seed batch); each seed's
    checkpoints, steps and crushes; the light and heavy pieces placed and knocked over (the final policies'
    ``evaluate_seedS.json``, whose outcomes are the runs'); the chosen and the last policies' held-out success; and
    the controller's crushes and placements they are set against."""
    para = learning_paragraph(TITLE)
    assert _options(PLACE_HALF, "env", "action_offset", "residual") == _options(CRADLE_SELECT, "env", "action_offset",
                                                                                  "residual")
    half, quarter = aggregate(PLACE_HALF), aggregate(PLACE_QUARTER)
    assert half["env"] == "simgrip/PlaceFragile-v8" and half["action_offset"] == [-0.2, 0.0, 0.0]
    assert half["residual"] == ["palm_x", "palm_z"] and half["light_bias"] == 0.5 and half["seeds"] == [0, 1]
    assert _options(PLACE_QUARTER, "light_bias") == _options(PLACE_HALF, "light_bias")
    assert quarter["light_bias"] == 0.25 and quarter["seeds"] == [0, 1, 2]
    for folder in (PLACE_HALF, PLACE_QUARTER):
        assert f"`docs/baselines/{folder}/`" in para
    runs_h, runs_q = seed_runs(PLACE_HALF, (0, 1)), seed_runs(PLACE_QUARTER, (0, 1, 2))
    _assert_seeds_on_page(para, runs_h)
    _assert_seeds_on_page(para, runs_q, crushes_end="): not met")
    assert not any(r["success_rate"] >= 0.8 for r in runs_h + runs_q)
    ev_h, ev_q = [_evaluation(PLACE_HALF, k) for k in (0, 1)], [_evaluation(PLACE_QUARTER, k) for k in (0, 1, 2)]
    assert [e["outcomes"] for e in ev_h + ev_q] == [r["outcomes"] for r in runs_h + runs_q]
    lights = {sum(e["by_mass"][LIGHT].values()) for e in ev_h + ev_q}
    heavies = {sum(e["by_mass"][HEAVY].values()) for e in ev_h + ev_q}
    assert lights == {21} and heavies == {17}
    placed = _listed(_count(e, HEAVY, "success") for e in ev_h)
    assert (f"held now, {_listed(_count(e, LIGHT, 'success') for e in ev_h)} of the 21, and the heavy ones lost: of "
            f"the 17 pieces of 68–250 g the chosen policies place {placed}"
            f" and knock {_listed(_count(e, HEAVY, 'knocked_over') for e in ev_h)} over, where the controller places "
            f"{_count(controller, HEAVY, 'success')}") in para
    assert (f"Seed 0 places {_count(ev_q[0], LIGHT, 'success')} of the light pieces and "
            f"{_count(ev_q[0], HEAVY, 'success')} of the heavy ones; seeds 1 and 2 place "
            f"{_listed(_count(e, LIGHT, 'success') for e in ev_q[1:])} of the light ones and knock "
            f"{_listed(_count(e, HEAVY, 'knocked_over') for e in ev_q[1:])} of the heavy ones over") in para
    runs = runs_h + runs_q
    assert (f"the policies chosen score {_listed(round(100 * r['success_rate']) for r in runs)} % held out, the last "
            f"ones {_listed(round(100 * r['selection']['last']['success_rate']) for r in runs)} %") in para
    assert (f"the scripted observation-only controller crushes {_count(controller, LIGHT, 'crushed')} and places "
            f"{controller['outcomes']['success']} of the 50") in para
    stop62 = [_count(_evaluation(f, k), LIGHT, "crushed") for f in PLACE_STOP62 for k in (0, 1)]
    assert f"crush {min(stop62)}–{max(stop62)} of the 21 pieces of 5–18 g" in para


def test_the_sphere_at_half_the_valves_rate_is_its_record():
    """The paragraph's last sentences: the sphere's selection screen's options with the restrictor at a half and the
    offset doubled (the start's closing, offset x share, unchanged), its checkpoints, steps, crushes and those in
    the touch's step, against the full rate's screen's."""
    para = learning_paragraph(TITLE)
    assert f"`docs/baselines/{SPHERE_SHARE}/`" in para
    agg, ref = aggregate(SPHERE_SHARE), aggregate(SPHERE_SELECT)
    assert _options(SPHERE_SHARE, "action_offset", "valve_share") == _options(SPHERE_SELECT, "action_offset")
    assert agg["valve_share"] == 0.5 and "valve_share" not in ref and agg["seeds"] == [0]
    assert agg["action_offset"][0] * agg["valve_share"] == ref["action_offset"][0] == -0.2
    runs = seed_runs(SPHERE_SHARE, (0,))
    ev = _evaluation(SPHERE_SHARE, 0)
    assert ev["outcomes"] == runs[0]["outcomes"] and runs[0]["success_rate"] < 0.8
    _assert_seeds_on_page(para, runs, crushes_end=f"), {ev['crushed_after_touch']['0']} of them in the touch's step")
    full = [_evaluation(SPHERE_SELECT, k)["crushed_after_touch"]["0"] for k in (0, 1)]
    assert f"against {_listed(full)} at the valve's full rate: not adopted" in para


PALM_ALONE = "rl_place_v8_palm_alone_light_log_std_peak_gamma_select_screen"
ALONE_TITLE = "**The place with its palm the script's alone, on the cradle's recipe** (stop 73)."


def test_the_light_bias_batches_knock_their_pieces_over_before_the_carry():
    """The paragraph's premise: the pieces the light-bias batches' chosen policies knock over on the held-out seeds
    (``evaluate_seedS.json``), and how many of them had been carried."""
    para = learning_paragraph(ALONE_TITLE)
    evs = [_evaluation(PLACE_HALF, k) for k in (0, 1)] + [_evaluation(PLACE_QUARTER, k) for k in (0, 1, 2)]
    knocked = sum(e["outcomes"].get("knocked_over", 0) for e in evs)
    carried = sum(e["carried"]["outcomes"].get("knocked_over", 0) for e in evs)
    heavy = sum(_count(e, HEAVY, "knocked_over") for e in evs)
    assert (f"of the {knocked} pieces its five chosen policies knock over, {heavy} of the heaviest third, "
            f"{'one' if carried == 1 else carried} had been carried") in para


def test_the_palm_alone_screen_is_its_record():
    """The palm-alone screen: the place screen's options with the palm the script's alone and the offset on the
    curvature alone; each seed's checkpoints, steps and crushes; no piece knocked over; the pieces of each third
    placed, crushed and timed out (the final policies' ``evaluate_seedS.json``, whose outcomes are the runs'); the
    screen it is set against; and seed 1's best validation in its last minute."""
    para = learning_paragraph(ALONE_TITLE)
    assert f"`docs/baselines/{PALM_ALONE}/`" in para
    agg = aggregate(PALM_ALONE)
    assert _options(PALM_ALONE, "action_offset", "residual_alone") == _options(PLACE_HALF, "action_offset")
    assert agg["action_offset"] == [-0.2] and agg["residual_alone"] is True and agg["seeds"] == [0, 1]
    runs = seed_runs(PALM_ALONE, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert f"against {final_rates(PLACE_HALF)} % with the palm corrected" in para
    assert not any(r["success_rate"] >= 0.8 for r in runs) and "Not met" in para
    evs = [_evaluation(PALM_ALONE, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert "No piece is knocked over" in para and not any("knocked_over" in e["outcomes"] for e in evs)
    middle = "18-68 g"
    assert {sum(e["by_mass"][middle].values()) for e in evs} == {12}
    assert all(e["by_mass"][middle] == {"success": 12} for e in evs) and "all 12 of the middle third" in para
    assert (f"place {_listed(_count(e, LIGHT, 'success') for e in evs)} of the 21 light pieces") in para
    assert (f"of the 17 heavy ones place {_listed(_count(e, HEAVY, 'success') for e in evs)}, crush "
            f"{_listed(_count(e, HEAVY, 'crushed') for e in evs)} and run out of time on "
            f"{_listed(_count(e, HEAVY, 'timeout') for e in evs)}") in para
    sel = runs[1]["selection"]
    best = max(v["success_rate"] for v in sel["validations"])
    assert sel["chosen"] == len(sel["validations"]) - 1 and sel["validations"][-1]["success_rate"] == best
    assert f"seed 1's validations reach their best, {round(100 * best)} %, in the budget's last minute" in para


def test_the_palm_alone_screen_given_twice_the_budget_is_its_record(controller):
    """The paragraph's last sentences: the palm-alone command at 30 CPU-minutes (its options but the budget), each
    seed's six checkpoints, steps and crushes, seed 0's choice (when, and its validation and held-out success), and
    the heavy pieces placed, crushed and timed out against the controller's."""
    para = learning_paragraph(ALONE_TITLE)
    folder = PALM_ALONE.replace("_screen", "_30min_screen")
    assert f"`docs/baselines/{folder}/`" in para
    assert _options(folder, "minutes") == _options(PALM_ALONE, "minutes") and aggregate(folder)["minutes"] == 30.0
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs, span="… / 30")
    assert not any(c["success_rate"] >= 0.8 for r in runs for c in r["checkpoints"])
    sel = runs[0]["selection"]
    chosen = sel["validations"][sel["chosen"]]
    assert len(sel["validations"]) == 30 and "the best of thirty validations" in para
    assert (f"Seed 0's choice, at {chosen['minutes']:.1f} CPU-min, scored {round(100 * chosen['success_rate'])} % on "
            f"the validation seeds and {round(100 * runs[0]['success_rate'])} % held out") in para
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert (f"({_listed(_count(e, HEAVY, 'success') for e in evs)} of the 17 placed, "
            f"{_listed(_count(e, HEAVY, 'crushed') for e in evs)} crushed, "
            f"{_listed(_count(e, HEAVY, 'timeout') for e in evs)} timed out)") in para
    assert f"the scripted observation-only controller places {_count(controller, HEAVY, 'success')} of them" in para
