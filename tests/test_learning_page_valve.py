"""The learning page's screens of stop 69 against their records: the claws and the place with the valve at half its
rate, the sphere's first touch, and the sphere with its palm the script's alone (``docs/learning.md``; the helpers are
``test_learning_page.py``'s, the records' readers ``test_readme_tables.py``'s).

The scripted observation-only controller's figures the paragraphs set the learners against are measured here again,
with ``evaluate_policy.py``'s own command, on the held-out seeds 8000-8049.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from helpers import load_example  # noqa: E402
from test_learning_page import _assert_seeds_on_page, _listed, learning_paragraph, seed_runs  # noqa: E402
from test_learning_page_claws import _evaluation  # noqa: E402
from test_readme_tables import ROOT, aggregate, final_rates, joined, measured_as  # noqa: E402

SPHERE = "simgrip/PickSphereFragile-v6"
#: task -> (its aided record, the half-rate screen, the aided command's options)
VALVE = {"cradle": ("rl_cradle_v6_residual_palm_light_log_std", [-0.4, 0.0], ["palm_z"], 0.5),
         "sphere": ("rl_sphere_v6_residual_palm_light_log_std", [-0.4, 0.0], ["palm_z"], 0.5),
         "place": ("rl_place_v8_residual_palm_log_std", [-0.4, 0.0, 0.0], ["palm_x", "palm_z"], None)}
ALONE = "rl_sphere_v6_palm_alone_light_log_std_valve005_screen"
ALONE_HALF = "rl_sphere_v6_palm_alone_light_log_std_valve01_screen"


@pytest.fixture(scope="module")
def controller():
    """``evaluate_policy.py --policy observation --episodes 50 --seed 8000 --json`` on the sphere at the valve's
    registered, half and quarter rates (keys None, 0.01, 0.005), and on the cradle and the place at half."""
    ev = load_example("evaluate_policy", "_valve")
    out = {}
    for env, rate in ((SPHERE, None), (SPHERE, 0.01), (SPHERE, 0.005), ("simgrip/PickCradleFragile-v6", 0.01),
                      ("simgrip/PlaceFragile-v8", 0.01)):
        extra = [] if rate is None else ["--env-kwargs", f'{{"kappa_rate": {rate}}}']
        out[env, rate] = ev.main(["--env", env, "--policy", "observation", "--episodes", "50", "--seed", "8000",
                                  "--json", *extra])
    return out


def _ratio(x: float) -> str:
    return f"{x:.2f}"


def test_the_half_rate_screens_are_their_records(controller):
    """"The claws and the place with the valve at half its rate": each screen's options (the aided command's and the
    valve's rate), seeds, checkpoints, steps and crushes, the records it is set against, the controllers' success
    at that rate, and the crushes in the touch's step (``evaluate_seedS.json``, whose outcomes are the runs')."""
    para = learning_paragraph("**The claws and the place with the valve at half its rate**")
    touch = {}
    for task, (record, offset, residual, light) in VALVE.items():
        folder = f"{record}_valve01_screen"
        assert f"docs/baselines/{folder}/" in para
        agg = aggregate(folder)
        assert agg["env_kwargs"] == {"kappa_rate": 0.01} and agg["seeds"] == [0, 1] and agg["minutes"] == 15.0
        assert measured_as(aggregate(record)) == agg["env"].split("/")[1]  # the record: the registered task
        assert agg["action_offset"] == offset and agg["residual"] == residual and agg.get("light_bias") == light
        assert agg["hyperparameters"] == ("Stable-Baselines3 defaults, one env, one torch thread; "
                                          "but log_std_init = -1.0")
        runs = seed_runs(folder, (0, 1))
        _assert_seeds_on_page(para, runs)
        evs = [_evaluation(folder, k) for k in (0, 1)]
        assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
        touch[task] = ([e["crushed_after_touch"]["0"] for e in evs], [r["outcomes"]["crushed"] for r in runs], evs)
        assert f"against its record's {final_rates(record)} %" in para
    rates = [round(100 * controller[env, 0.01]["success_rate"]) for env in
             ("simgrip/PickCradleFragile-v6", SPHERE, "simgrip/PlaceFragile-v8")]
    assert f"controllers keep {rates[0]}, {rates[1]} and {rates[2]} % of the held-out seeds with it" in para
    (c0, c1), (n0, n1), evs = touch["cradle"]
    assert f"({c0} and {c1} of {n0} and {n1}, `evaluate_seedS.json`, `crushed_after_touch`;" in para
    four = [_evaluation("rl_cradle_v6_residual_palm_light_log_std_4envs_512_batch128_screen", k) for k in (0, 1)]
    assert (f"{four[0]['crushed_after_touch']['0']} and {four[1]['crushed_after_touch']['0']} of "
            f"{four[0]['outcomes']['crushed']} and {four[1]['outcomes']['crushed']} in the four copies' screen") in para
    assert c0 + c1 < sum(f["crushed_after_touch"]["0"] for f in four)  # "fewer of the crushes come in the touch's step"
    heavy = sum(e["by_mass"]["74-200 g"].get("crushed", 0) for e in evs)
    assert heavy == 1 and "all but one on the lighter two thirds of the masses" in para
    (s0, s1), (m0, m1), _ = touch["sphere"]
    assert f"on the sphere no fewer ({s0} and {s1} of {m0} and {m1})." in para
    # the environments page's sentence: the screens' finals
    page = joined(ROOT / "docs" / "environments.md")
    finals = {t: final_rates(f"{VALVE[t][0]}_valve01_screen") for t in VALVE}
    assert (f"{finals['cradle']} % on the cradle, {finals['sphere']} % on the sphere and {finals['place']} % on "
            f"the place in two-seed screens (`*_valve01_screen`") in page
    assert (f"at half the valve's rate {final_rates(ALONE_HALF)} % (`{ALONE_HALF}`) and at a quarter of it "
            f"{final_rates(ALONE)} % (`{ALONE}`)") in page


def test_the_first_touch_paragraph_is_the_policies_and_the_controllers_figures(controller):
    """"The first touch on the sphere": the half-rate policies' first touches (``first_touch``: peak and end
    medians, the peaks' largest, how many read above the limit) and the controller's at the three rates."""
    para = learning_paragraph("**The first touch on the sphere: an impact the peak rule reads**")
    evs = [_evaluation("rl_sphere_v6_residual_palm_light_log_std_valve01_screen", k)["first_touch"] for k in (0, 1)]
    read = _listed(_ratio(e["read"]["median"]) for e in evs)
    most = _listed(_ratio(e["read"]["max"]) for e in evs)
    end = _listed(_ratio(e["end"]["median"]) for e in evs)
    assert f"read a median {read} of the limit at the first touch's peak (at most {most}) and {end} at" in para
    assert f"{_listed(e['above_limit'] for e in evs)} of their first touches read above the limit" in para
    base = controller[SPHERE, None]
    assert (f"reads a median {_ratio(base['first_touch']['read']['median'])} (at most "
            f"{_ratio(base['first_touch']['read']['max'])}) and crushes {base['crushed_after_touch']['0']} of 50 at "
            "the touch") in para
    slow = [controller[SPHERE, r]["crushed_after_touch"]["0"] for r in (0.01, 0.005)]
    assert f"and {slow[0]} and {slow[1]} with the valve at half and a quarter of its rate" in para
    assert base["crushed_after_touch"]["0"] <= min(slow)  # "closing more slowly does not remove them"
    for e in [base["first_touch"]] + evs:  # every episode touched: the medians are over all 50
        assert e["touches"] == 50


def test_the_palm_alone_screens_are_their_records(controller):
    """"The sphere with the palm the script's alone": each screen's options, seeds, checkpoints, steps and crushes;
    at half the rate its crushes in the touch's step and first touches against the residual's screen; at a quarter
    its first touches against the controller's at the same rate, its crushes in the touch's step, its heavy third."""
    para = learning_paragraph("**The sphere with the palm the script's alone**")
    assert f"docs/baselines/{ALONE_HALF}/" in para
    agg = aggregate(ALONE_HALF)
    assert agg["env_kwargs"] == {"kappa_rate": 0.01} and agg["residual"] == ["palm_z"] and agg["residual_alone"]
    assert agg["action_offset"] == [-0.4] and agg["light_bias"] == 0.5 and agg["seeds"] == [0, 1]
    runs = seed_runs(ALONE_HALF, (0, 1))
    _assert_seeds_on_page(para, runs, crushes_end="),")
    evs = [_evaluation(ALONE_HALF, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    touch = [e["first_touch"] for e in evs]
    with_palm = [_evaluation("rl_sphere_v6_residual_palm_light_log_std_valve01_screen", k) for k in (0, 1)]
    assert (f"{_listed(e['crushed_after_touch']['0'] for e in evs)} of them in the touch's step, whose first touches "
            f"read a median {_listed(_ratio(t['read']['median']) for t in touch)} of the limit (at most "
            f"{_listed(_ratio(t['read']['max']) for t in touch)}; the controller's at this rate "
            f"{_ratio(controller[SPHERE, 0.01]['first_touch']['read']['median'])}): without the palm's correction the "
            f"learners crush as often at the touch as with it "
            f"({_listed(e['crushed_after_touch']['0'] for e in with_palm)}, above)") in para
    assert sum(e["crushed_after_touch"]["0"] for e in evs) >= sum(e["crushed_after_touch"]["0"] for e in with_palm)
    assert min(t["read"]["median"] for t in touch) > controller[SPHERE, 0.01]["first_touch"]["read"]["median"]
    assert f"docs/baselines/{ALONE}/" in para
    agg = aggregate(ALONE)
    assert agg["env_kwargs"] == {"kappa_rate": 0.005} and agg["residual"] == ["palm_z"] and agg["residual_alone"]
    assert agg["action_offset"] == [-0.8] and agg["light_bias"] == 0.5 and agg["seeds"] == [0, 1]
    runs = seed_runs(ALONE, (0, 1))
    _assert_seeds_on_page(para, runs)
    evs = [_evaluation(ALONE, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]
    touch = [e["first_touch"] for e in evs]
    ref = controller[SPHERE, 0.005]
    assert (f"(a median {_listed(_ratio(t['read']['median']) for t in touch)} of the limit, at most "
            f"{_listed(_ratio(t['read']['max']) for t in touch)}; the controller's at this rate "
            f"{_ratio(ref['first_touch']['read']['median'])} and {_ratio(ref['first_touch']['read']['max'])})") in para
    on_touch = [e["crushed_after_touch"]["0"] for e in evs]
    assert f"{on_touch[0]} and {on_touch[1]} of them in the touch's step" in para
    assert f"({on_touch[0]} and {on_touch[1]}) are about as many as the controller's own at this rate " \
           f"({ref['crushed_after_touch']['0']} of 50)" in para
    heavy = [e["by_mass"]["74-200 g"] for e in evs]
    held = [h.get("success", 0) for h in heavy]
    lost = [h.get("timeout", 0) + h.get("dropped", 0) for h in heavy]
    assert f"of its {sum(heavy[0].values())} pieces {held[0]} and {held[1]} are held, and {lost[0]} and {lost[1]} " \
           "time out or are dropped" in para
    assert f"where the controller at the same rate holds {ref['by_mass']['74-200 g']['success']}." in para
    # "it crushes less than any sphere screen with the palm's correction"
    crushes = [r["outcomes"]["crushed"] for r in runs]
    others = [f.name for f in (ROOT / "docs" / "baselines").glob("rl_sphere_v6_*_screen")
              if not aggregate(f.name).get("residual_alone")]
    assert len(others) >= 6
    assert max(crushes) < min(r["outcomes"].get("crushed", 0) for f in others for r in
                              (seed_runs(f, aggregate(f)["seeds"])))


def test_the_palm_alone_with_the_falling_rate_and_step_charge_is_its_record():
    """"The palm the script's alone with a falling rate and a step charge": its options, seeds, checkpoints, steps
    and crushes, the highest mean final of the sphere's screens, its heavy third against the quarter-rate screen's,
    and its first touches; the environments page's sentence."""
    folder = "rl_sphere_v6_palm_alone_light_log_std_lr_decay_step_charge_valve005_screen"
    para = learning_paragraph("**The palm the script's alone with a falling rate and a step charge**")
    assert f"docs/baselines/{folder}/" in para
    agg = aggregate(folder)
    assert agg["env_kwargs"] == {"kappa_rate": 0.005} and agg["residual_alone"] and agg["action_offset"] == [-0.8]
    assert agg["step_charge"] == 0.005 and agg["hyperparameters"].endswith(
        "but the learning rate falls linearly to 0 over the budget")
    runs = seed_runs(folder, (0, 1))
    _assert_seeds_on_page(para, runs, crushes_end="):")
    evs = [_evaluation(folder, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs] == [r["outcomes"] for r in runs]

    def mean_final(f):
        final = aggregate(f)["summary"]["ppo"]["final"]["success_rates"]
        return sum(final) / len(final)

    four = folder.replace("_valve005", "_4envs_512_batch128_valve005")  # the same on four copies, after it
    screens = [f.name for f in (ROOT / "docs" / "baselines").glob("rl_sphere_v6_*_screen")
               if f.name not in (folder, four)]
    best = max(mean_final(f) for f in screens)
    assert mean_final(folder) > best and mean_final(four) == mean_final(folder)  # "the same mean"
    assert f"({round(100 * mean_final(folder))} %; the best before, {round(100 * best)} %" in para
    held = [e["by_mass"]["74-200 g"]["success"] for e in evs]
    before = [_evaluation(ALONE, k)["by_mass"]["74-200 g"]["success"] for k in (0, 1)]
    assert f"({held[0]} and {held[1]} of its 17 pieces, against {before[0]} and {before[1]} without" in para
    touch = [e["first_touch"] for e in evs]
    assert (f"(a median {_listed(_ratio(t['read']['median']) for t in touch)} of the limit, at most "
            f"{_listed(_ratio(t['read']['max']) for t in touch)}; "
            f"{_listed(e['crushed_after_touch']['0'] for e in evs)} crushes in the touch's step)") in para
    assert all(all(c1["success_rate"] >= c0["success_rate"] for c0, c1 in zip(r["checkpoints"], r["checkpoints"][1:]))
               for r in runs)  # "both seeds climbing to the budget's end"
    # the same on four copies with minibatches of 128
    assert f"docs/baselines/{four}/" in para
    agg = aggregate(four)
    assert agg["n_envs"] == 4 and agg["hyperparameters"].endswith(
        "n_steps = 512; but batch_size = 128; but the learning rate falls linearly to 0 over the budget")
    assert {k: agg[k] for k in ("env_kwargs", "residual_alone", "action_offset", "step_charge")} == {
        "env_kwargs": {"kappa_rate": 0.005}, "residual_alone": True, "action_offset": [-0.8], "step_charge": 0.005}
    runs4 = seed_runs(four, (0, 1))
    _assert_seeds_on_page(para, runs4, crushes_end="),")
    evs4 = [_evaluation(four, k) for k in (0, 1)]
    assert [e["outcomes"] for e in evs4] == [r["outcomes"] for r in runs4]
    assert all(e["by_mass"]["10-27 g"]["crushed"] == e["outcomes"]["crushed"] for e in evs4)  # all on the lightest
    steps = [r["timesteps"] for r in runs4] + [r["timesteps"] for r in runs]
    assert 1.6 < sum(steps[:2]) / sum(steps[2:]) < 1.7  # "two thirds more steps"
    page = joined(ROOT / "docs" / "environments.md")
    assert (f"it holds them again, {final_rates(folder)} % (`{folder}`; on four copies with minibatches of 128, "
            f"{final_rates(four)} %), the sphere's best screens so far") in page
