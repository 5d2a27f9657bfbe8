"""The learning page's paragraphs of stop 71 against their records: the value function given the hidden workpiece
(``--privileged-critic``) and gSDE's exploration (``--sde``) (``docs/learning.md``; the helpers are
``test_learning_page.py``'s, the records' readers ``test_readme_tables.py``'s).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_learning_page import (_assert_seeds_on_page, _listed, checkpoint_rates, learning_paragraph,  # noqa: E402
                                seed_runs)
from test_learning_page_claws import _evaluation  # noqa: E402
from test_readme_tables import ROOT, aggregate, final_rates  # noqa: E402

CRADLE_AIDED = "rl_cradle_v6_residual_palm_light_log_std"
SPHERE_RECIPE = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_share025"
CRADLE_PC = CRADLE_AIDED + "_privileged_critic_screen"
SPHERE_PC = SPHERE_RECIPE + "_privileged_critic_screen"
PLACE_AIDED = "rl_place_v8_residual_palm_log_std"
PLACE_PC = PLACE_AIDED + "_privileged_critic_screen"
IGNORED = ("command", "summary", "combined_from", "versions", "seeds", "privileged_critic")


def _same_options_but_the_critic(folder: str, base: str) -> None:
    agg, ref = aggregate(folder), aggregate(base)
    assert agg["privileged_critic"] is True and "privileged_critic" not in ref
    assert {k: v for k, v in agg.items() if k not in IGNORED} == {k: v for k, v in ref.items() if k not in IGNORED}


def test_the_privileged_critic_screens_are_their_records():
    """"The value function given the hidden workpiece": each screen's options (its base's with the critic), seeds,
    checkpoints, steps and crushes, the records it is set against, and where its crushes come and its heavy pieces
    end (its final policies' ``evaluate_seedS.json``, whose outcomes are the runs')."""
    para = learning_paragraph("**The value function given the hidden workpiece (`--privileged-critic`)**")
    assert "(`tests/test_privileged_critic.py`)" in para and (ROOT / "tests" / "test_privileged_critic.py").is_file()
    for folder, base in ((CRADLE_PC, CRADLE_AIDED), (SPHERE_PC, SPHERE_RECIPE), (PLACE_PC, PLACE_AIDED)):
        assert f"`docs/baselines/{folder}/`" in para
        _same_options_but_the_critic(folder, base)
        assert aggregate(folder)["seeds"] == [0, 1]
        runs = seed_runs(folder, (0, 1))
        assert f"{_listed(checkpoint_rates(r) for r in runs)} % at 5 / 10 / 15 CPU-min" in para
        assert f"on {_listed(format(r['timesteps'], ',') for r in runs)} steps" in para
        assert f"({_listed(r['outcomes']['crushed'] for r in runs)} crushes of 50 held out)" in para
        evs = [_evaluation(folder, k) for k in (0, 1)]
        assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
        assert all(e["privileged_critic"] is True for e in evs)
    base = seed_runs(CRADLE_AIDED, (0, 1))
    finals = " / ".join(str(round(100 * r["success_rate"])) for r in base)
    steps = _listed(format(r["timesteps"], ",") for r in base)
    assert f"against {finals} % for the same seeds in the cradle's record, on {steps} steps" in para
    after = [_evaluation(CRADLE_PC, k)["crushed_after_touch"] for k in (0, 1)]
    assert f"; {_listed(a['0'] for a in after)} of its crushes come in the touch's step" in para
    assert f"against {final_rates(SPHERE_RECIPE)} % for the recipe's three seeds" in para
    sphere = [_evaluation(SPHERE_PC, k) for k in (0, 1)]
    after = [e["crushed_after_touch"] for e in sphere]
    assert f"{_listed(a['5-24'] for a in after)} of its crushes come five to 24 steps after the touch and " \
           f"{_listed(a['25+'] for a in after)} later still" in para
    heavy = [e["by_mass"]["74-200 g"] for e in sphere]
    assert f"of the {sum(heavy[0].values())} heaviest pieces {_listed(h['timeout'] for h in heavy)} time out" in para
    for base, rerun in ((PLACE_AIDED, PLACE_AIDED + "_rerun_screen"),):
        ref, again = seed_runs(base, (0, 1)), seed_runs(rerun, (0, 1))
        assert f"against {' / '.join(str(round(100 * r['success_rate'])) for r in ref)} % for the same seeds in the " \
               f"place's record, on {_listed(format(r['timesteps'], ',') for r in ref)} steps, and " \
               f"{' / '.join(str(round(100 * r['success_rate'])) for r in again)} % for its rerun at stop 62 on " \
               f"{_listed(format(r['timesteps'], ',') for r in again)}" in para
    after = [_evaluation(PLACE_PC, k)["crushed_after_touch"] for k in (0, 1)]
    assert f"; {_listed(a['0'] for a in after)} of its crushes come in the touch's step. Not adopted" in para
    assert max(r["success_rate"] for f in (CRADLE_PC, SPHERE_PC, PLACE_PC) for r in seed_runs(f, (0, 1))) < 0.8


def test_the_gsde_screen_is_its_record():
    """"Exploration by gSDE": the aided command with ``--sde`` and its own initial log standard deviation (the
    options otherwise the cradle's record's), each seed's checkpoints, steps and crushes, and no success at 15."""
    folder = "rl_cradle_v6_residual_palm_light_sde_screen"
    para = learning_paragraph("**Exploration by gSDE (`--sde`)**")
    assert f"`docs/baselines/{folder}/`" in para
    agg, ref = aggregate(folder), aggregate(CRADLE_AIDED)
    assert agg["hyperparameters"] == ref["hyperparameters"].replace("-1.0", "-2.25") + "; but use_sde = True"
    same = ("env", "action_offset", "residual", "light_bias")
    assert {k: agg[k] for k in same} == {k: ref[k] for k in same} and agg["seeds"] == [0, 1]
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs)
    assert "--log-std-init -2.25 --sde" in para and all(r["success_rate"] == 0.0 for r in runs)
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    assert f"in their {_listed(format(r['train_episodes'], ',') for r in runs)} training episodes" in para


def test_the_environments_page_lists_them_as_measured_and_not_adopted():
    from test_readme_tables import joined

    page = joined(ROOT / "docs" / "environments.md")
    assert (f"a value function given the hidden workpiece (`--privileged-critic`: the cradle "
            f"{final_rates(CRADLE_PC)} %, the sphere's recipe {final_rates(SPHERE_PC)} %, the place "
            f"{final_rates(PLACE_PC)} %), gSDE's exploration (`--sde`: the cradle "
            f"{final_rates('rl_cradle_v6_residual_palm_light_sde_screen')} %)") in page


def _assert_unaided_replays(para: str, cells) -> None:
    """Each ``(cell, seeds, replayed)``: the replay folder named in ``para`` with the cell's ``--replay``, each seed
    ``identical`` against its record's run (checkpoints, outcomes), the training episodes equal, and ``para``'s
    figures the records'."""
    for cell, seeds, replayed in cells:
        assert f"`docs/baselines/{replayed}/`" in para and re.search(rf"--replay docs/baselines/{cell}[ `]", para)
        runs, again = seed_runs(cell, seeds), seed_runs(replayed, seeds)
        for k, run, rep in zip(seeds, runs, again):
            assert rep["replay"]["identical"] is True
            assert rep["replay"]["from"] == f"docs/baselines/{cell}/ppo_seed{k}.json"
            assert rep["train_episodes"] == run["train_episodes"] and rep["timesteps"] == run["timesteps"]
            assert [c["success_rate"] for c in rep["checkpoints"]] == [c["success_rate"] for c in run["checkpoints"]]
            assert rep["outcomes"] == run["outcomes"]
        assert f"{_listed(checkpoint_rates(r) for r in runs)} % at 5 / 10 / 15 CPU-min on " \
               f"{_listed(format(r['timesteps'], ',') for r in runs)} steps" in para
        assert f"the training episodes too ({_listed(format(r['train_episodes'], ',') for r in runs)})" in para
        agg = aggregate(replayed)
        assert agg["seeds"] == list(seeds)
        commands = [c for c in agg.get("combined_from") or [agg["command"]]]
        assert all("--replay" in c for c in commands)


def test_the_unaided_cells_replays_are_identical():
    """"The README's unaided cells, replayed": seeds 0 and 2 of ``rl_pick_v7`` and 0 and 1 of ``rl_multi_v7`` replayed
    with each cell's own command, each ``identical`` against its record's run (checkpoints, outcomes), the training
    episodes equal, and the page's figures the records'."""
    from test_readme_tables import joined

    page = joined(ROOT / "docs" / "learning.md")
    para = page[page.index("- **The README's unaided cells, replayed** (stop 71)."):]
    _assert_unaided_replays(para, (("rl_pick_v7", (0, 2), "rl_pick_v7_replay_02"),
                                   ("rl_multi_v7", (0, 1), "rl_multi_v7_replay_01")))
    readme = joined(ROOT / "README.md")
    assert "and two seeds each of the pinch's and the K fingers' unaided cells" in readme
    never = seed_runs("rl_pick_v7", (1,))[0]  # the pinch's seed not replayed: it never grips
    assert never["outcomes"].get("success", 0) == 0 and all(c["success_rate"] == 0 for c in never["checkpoints"])


def test_the_claws_unaided_replays_are_identical():
    """"The cradle's and the sphere's unaided cells, replayed": the one seed of each that ends above 0 % (seed 2 of
    ``rl_cradle_v6``, seed 0 of ``rl_sphere_v6``), as the test above; every other seed of theirs and of the place's
    unaided cell ends at 0 %, as the page and the README say."""
    from test_readme_tables import joined

    page = joined(ROOT / "docs" / "learning.md")
    para = page[page.index("- **The cradle's and the sphere's unaided cells, replayed** (stop 72)."):]
    _assert_unaided_replays(para, (("rl_cradle_v6", (2,), "rl_cradle_v6_replay_2"),
                                   ("rl_sphere_v6", (0,), "rl_sphere_v6_replay_0")))
    for cell, others in (("rl_cradle_v6", (0, 1)), ("rl_sphere_v6", (1, 2)), ("rl_place_v8", (0, 1, 2))):
        assert all(r["success_rate"] == 0 for r in seed_runs(cell, others))
    assert "Their other seeds, and every seed of the place's unaided cell, end at 0 %." in para
    readme = joined(ROOT / "README.md")
    assert "unaided cells and the one seed of the cradle's and of the sphere's that grips." in readme
