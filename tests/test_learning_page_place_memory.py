"""The learning page's place screens of stop 74 against their records: the palm-alone command without the light bias
(``docs/learning.md``, "The place with its palm the script's alone, without the light bias"; the helpers are
``test_learning_page.py``'s, the records' readers ``test_readme_tables.py``'s).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_learning_page import _assert_seeds_on_page, _listed, learning_paragraph, seed_runs  # noqa: E402
from test_learning_page_claws import _evaluation  # noqa: E402
from test_learning_page_cradle_touch import _options  # noqa: E402
from test_learning_page_place_light import HEAVY, LIGHT, PALM_ALONE, _count  # noqa: E402
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
