"""The learning page's paragraphs and tables against the records their commands wrote (issue 18: "no number ...
that its command does not give"): the screens, the replays and the longer budgets of ``docs/learning.md``, each
read back from its ``docs/baselines/`` folder (the README's and the target table's cells: ``test_readme_tables.py``,
whose row map and readers this file shares).
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from test_readme_tables import (AIDED, BASELINES, ROOT, ROWS, TASKS, aggregate, final_rates, joined,  # noqa: E402
                                measured_as, pct, training_command)


def learning_paragraph(title: str) -> str:
    """The learning page's paragraph that opens with ``title`` (``**...**``), up to the next bold text."""
    text = joined(ROOT / "docs" / "learning.md")
    start = text.index(title)
    return text[start:text.index(" **", start + len(title))]


def seed_runs(folder: str, seeds) -> list[dict]:
    """The runs ``ppo_seed<S>.json`` of the record ``folder`` for ``seeds``."""
    return [json.loads((BASELINES / folder / f"ppo_seed{k}.json").read_text(encoding="utf-8")) for k in seeds]


def batch_of(agg: dict, seed: int) -> str:
    """The folder that seed ``seed``'s batch of the combined record ``agg`` was written to (its command's ``--out``,
    ``combined_from``): where a replay of that seed reads its record."""
    return next(c[c.index("--out") + 1] for c in agg["combined_from"] if c[c.index("--seeds") + 1] == str(seed))


def checkpoint_rates(run: dict) -> str:
    """A run's held-out success at its checkpoints as the pages write it: "x / y / z"."""
    return " / ".join(str(pct(c["success_rate"])) for c in run["checkpoints"])


def test_the_peak_probe_screens_on_the_learning_page_are_their_records():
    """The learning page's table of the stop-62 screens (the claws and the place behind the peak probe, the place
    with the crush margin, and its control): each seed's checkpoints, its final crushes and those within the step
    of the first touch (its ``evaluate_seedS.json``, the final model run on the same held-out seeds), its steps,
    and the offset and the margin the options name are the record's."""
    lines = (ROOT / "docs" / "learning.md").read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| task | options | seed 0 at 5 / 10 / 15"))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    assert [r[0] for r in rows] == ["place", "place", "place", "cradle", "cradle", "sphere", "sphere"]
    for task, options, seed0, seed1, crushes, steps, folder in rows:
        folder = folder.strip("`/")
        agg = aggregate(folder)
        seeds = [0] if seed1 == "—" else [0, 1]  # (the claws' controls: seed 0 alone)
        assert measured_as(agg) == TASKS[task] and agg["seeds"] == seeds and agg["minutes"] == 15.0, folder
        command = training_command(agg)
        assert float(command[command.index("--action-offset") + 1]) == (-0.2 if "peak" in options else -0.4)
        margin = re.search(r"crush margin ([\d.]+)", options)
        assert ("--crush-margin" in command) == bool(margin), folder
        if margin:
            value = float(margin.group(1))
            assert float(command[command.index("--crush-margin") + 1]) == value == agg["crush_margin"], folder
        said = re.findall(r"(\d+) \((\d+)\)", crushes)
        for seed, cells in enumerate((seed0, seed1)[:len(seeds)]):
            run, = seed_runs(folder, [seed])
            assert [int(v) for v in cells.rstrip(" %").split(" / ")] == \
                [pct(c["success_rate"]) for c in run["checkpoints"]], (folder, seed)
            ev = json.loads((BASELINES / folder / f"evaluate_seed{seed}.json").read_text(encoding="utf-8"))
            assert ev["success_rate"] == run["success_rate"] and ev["eval_seeds"] == [8000, 8049]
            assert ev["episodes"] == 50
            assert (int(said[seed][0]), int(said[seed][1])) == (ev["outcomes"]["crushed"],
                                                                ev["crushed_after_touch"]["0"]), (folder, seed)
            assert f"{round(run['timesteps'] / 1000)}k" == steps.split(", ")[seed], (folder, seed)


def test_the_sac_screens_behind_the_aids_are_their_records():
    """The learning page's "SAC behind the aids" paragraph: each screen's options (its command), 0 % at every
    checkpoint, its steps, training episodes, and the final policy's crushes and timeouts of 50 held out."""
    para = learning_paragraph("**SAC behind the aids**")
    screens = [("rl_pick_v7_peak_sac_screen", ["--action-offset", "-0.2", "0.2"]),
               ("rl_multi_v7_peak_light_step_charge_sac_screen",
                ["--action-offset", "-0.2", "0.2", "--light-bias", "0.5", "--step-charge", "0.005"])]
    runs = []
    for folder, options in screens:
        assert folder in para
        agg = aggregate(folder)
        command = agg["command"]
        assert " ".join(options) in " ".join(command) and agg["algos"] == ["sac"] and agg["minutes"] == 15.0
        assert agg["eval_seeds"] == [8000, 8049] and agg["seeds"] == [0], folder
        assert [c["minutes"] for c in agg["summary"]["sac"]["checkpoints"]] == [5.0, 10.0, 15.0]
        assert all(c["success_rates"] == [0.0] for c in agg["summary"]["sac"]["checkpoints"]), folder
        runs.append(json.loads((BASELINES / folder / "sac_seed0.json").read_text(encoding="utf-8")))
    assert f"on {runs[0]['timesteps']:,} and {runs[1]['timesteps']:,} steps" in para
    assert f"no success in {runs[0]['train_episodes']} and {runs[1]['train_episodes']} training episodes" in para
    assert all(r["success_rate"] == 0.0 for r in runs)
    crushed, timeout = [r["outcomes"]["crushed"] for r in runs], [r["outcomes"]["timeout"] for r in runs]
    assert f"crush {crushed[0]} and {crushed[1]} of 50 and let {timeout[0]} and {timeout[1]} time out" in para


def test_the_25_hz_screen_on_the_learning_page_is_its_record():
    """The learning page's "K fingers commanded at 25 Hz": the record's options (the control step, the valve's rate
    and the episode's steps, per second what the registered task's are; the step charge per second too), each seed's
    checkpoints, its steps and the simulated seconds they cover, and its crushes of 50 held out."""
    para = learning_paragraph("**The K fingers commanded at 25 Hz**")
    folder = "rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge_25hz_screen"
    assert folder in para
    agg = aggregate(folder)
    assert agg["seeds"] == [0, 1] and agg["minutes"] == 15.0 and agg["eval_seeds"] == [8000, 8049]
    import gymnasium as gym

    import simgrip.envs  # noqa: F401

    spec = gym.spec("simgrip/PickMultiFragile-v7")
    env = gym.make(spec.id).unwrapped
    try:
        fs, rate, dt = env.frame_skip, env.kappa_rate, env.dt
    finally:
        env.close()
    kwargs = agg["env_kwargs"]
    # twice the control step; per second the valve's rate, the episode and the step charge of the registered task
    assert kwargs["frame_skip"] == 2 * fs and kwargs["kappa_rate"] == 2 * rate
    assert kwargs["max_episode_steps"] * 2 == spec.max_episode_steps and agg["step_charge"] == 2 * 0.005
    runs = seed_runs(folder, (0, 1))
    rates = [checkpoint_rates(r) for r in runs]
    assert f"{rates[0]} and {rates[1]} % at 5 / 10 / 15 CPU-min" in para
    assert f"on {runs[0]['timesteps']:,} and {runs[1]['timesteps']:,} steps" in para
    seconds = [round(r["timesteps"] * 2 * dt, -1) for r in runs]
    assert f"({seconds[0]:,.0f} and {seconds[1]:,.0f} s of simulated time" in para
    crushed = [r["outcomes"]["crushed"] for r in runs]
    assert f"{crushed[0]} and {crushed[1]} crushes of 50 held out" in para


#: the README's aided cells since replaced -> the record that replaced each and the stop it did (the cradle's at stop
#: 72, the place's at stop 74; the environments page says so)
FORMER_CELLS = {
    "rl_cradle_v6_residual_palm_light_log_std": ("rl_cradle_v6_residual_palm_light_log_std_peak_gamma_select", 72),
    "rl_place_v8_residual_palm_log_std": ("rl_place_v8_palm_alone_light_log_std_peak_gamma_select_touch_memory", 74)}


def _assert_replayed(cell: str, folder: str, seed: int, rates: str, steps: str, episodes: str) -> None:
    """Seed ``seed`` of the README cell ``cell``'s record replayed into ``folder``: the replay says ``identical``
    against that record, whose checkpoints (``rates``, "x / y / z"), steps and training episodes (as the page writes
    them) are the page's and the replay's.  A cell the README has since replaced counts too (:data:`FORMER_CELLS`)."""
    assert cell in {columns[AIDED] for _, columns in ROWS.values()} | set(FORMER_CELLS), cell  # a README cell's
    record, = seed_runs(cell, [seed])
    run, = seed_runs(folder, [seed])
    assert run["replay"]["identical"] is True and run["replay"]["from"].endswith(f"{cell}/ppo_seed{seed}.json")
    assert [pct(c["success_rate"]) for c in record["checkpoints"]] == [int(v) for v in rates.split(" / ")], folder
    assert f"{record['timesteps']:,}" == steps == f"{run['timesteps']:,}", (folder, seed)
    assert f"{record['train_episodes']:,}" == episodes == f"{run['train_episodes']:,}", (folder, seed)
    assert [c["success_rate"] for c in run["checkpoints"]] == [c["success_rate"] for c in record["checkpoints"]]


def test_the_identical_replays_on_the_learning_page_are_their_records():
    """The learning page's replays of README cells on a machine of the references' arithmetic (stop 64: three cells
    whole, seed 0 of a fourth; stop 65: the fourth's seeds 1 and 2): each replayed seed's JSON says ``identical``
    against the cell's own record (the folder it names), and the checkpoints, steps and training episodes the page
    gives are the record's."""
    text = joined(ROOT / "docs" / "learning.md")
    found = re.findall(r"the \w+'s aided cell \(`(rl_[\w]+)`, recorded at stop \d+\): seeds 0–2 \*\*identical\*\* to "
                       r"the record \(`docs/baselines/(rl_[\w]+_replay_012)/`\): ([\d /,and]+) % at 5 / 10 / 15 CPU-min, "
                       r"on ([\d,]+), ([\d,]+) and ([\d,]+) steps, .*? training episodes too \(([\d,]+), ([\d,]+) and "
                       r"([\d,]+)\)", text)
    assert len(found) == 3, found
    page = joined(ROOT / "docs" / "environments.md")
    for former, (now, stop) in FORMER_CELLS.items():
        assert now in {columns[AIDED] for _, columns in ROWS.values()}, now
        assert f"`{now}/` since stop {stop} (before it `{former}/`" in page, (former, now)
    for cell, folder, rates, *numbers in found:
        for seed, seed_rates in enumerate(re.split(r", | and ", rates)):
            _assert_replayed(cell, folder, seed, seed_rates, numbers[seed], numbers[3 + seed])
    # seed 0 of one more cell: "(`A`, recorded ...): **identical** too (`docs/baselines/B/`): x / y / z % at 5 / 10 / 15
    # CPU-min, on N steps and E training episodes"
    more = re.search(r"seed 0 of the \w+'s aided cell \(`(rl_\w+)`, recorded at stop \d+\): \*\*identical\*\* too "
                     r"\(`docs/baselines/(rl_\w+_replay_s0)/`\): ([\d /]+) % at 5 / 10 / 15 CPU-min, on ([\d,]+) steps and "
                     r"([\d,]+) training episodes", text)
    assert more, "the sphere's replay"
    cell, folder, rates, steps, episodes = more.groups()
    _assert_replayed(cell, folder, 0, rates, steps, episodes)
    # and its seeds 1 and 2: "(`docs/baselines/B/`): x / y / z and x / y / z % at 5 / 10 / 15 CPU-min, on N and N steps
    # and E and E training episodes"
    rest = re.search(r"its seeds 1 and 2 \(stop \d+, [^)]*\) \*\*identical\*\* too "
                     r"\(`docs/baselines/(rl_\w+_replay_12)/`\): ([\d /]+) and ([\d /]+) % at 5 / 10 / 15 CPU-min, "
                     r"on ([\d,]+) and ([\d,]+) steps and ([\d,]+) and "
                     r"([\d,]+) training episodes", text)
    assert rest, "the sphere's seeds 1 and 2"
    folder, r1, r2, s1, s2, e1, e2 = rest.groups()
    _assert_replayed(cell, folder, 1, r1, s1, e1)
    _assert_replayed(cell, folder, 2, r2, s2, e2)


def test_the_lr_decay_rerun_and_its_replays_are_their_records():
    """The learning page's "A learning rate that follows the clock, replayed": the rerun, the K fingers' README cell
    from stop 66 to 67, is the experiment of the stop-58 batch it replaced (the same options and hyperparameters), its
    checkpoints, crushes and steps are the page's, each seed's replay says ``identical`` against it having read every
    one of the rate's readings, and the environments page gives its final success and the replaced batch's."""
    text = joined(ROOT / "docs" / "learning.md")
    para = text[text.index("**A learning rate that follows the clock, replayed**"):]
    first = "rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge"  # its batch of stop 58, not replayable
    rerun = f"{first}_rerun"
    assert f"docs/baselines/{rerun}/" in para and f"docs/baselines/{rerun}_replay_012/" in para
    agg = aggregate(rerun)
    old = aggregate(first)
    for key in ("env", "algos", "minutes", "checkpoint_minutes", "clock", "eval_seeds", "hyperparameters",
                "action_offset", "light_bias", "step_charge", "seeds"):
        assert agg.get(key) == old.get(key), key
    runs = seed_runs(rerun, range(3))
    rates = [checkpoint_rates(r) for r in runs]
    assert f"{rates[0]}, {rates[1]} and {rates[2]} % at 5 / 10 / 15 CPU-min" in para
    crushed = [r["outcomes"]["crushed"] for r in runs]
    assert f"{crushed[0]}, {crushed[1]} and {crushed[2]} crushes of 50 held out" in para
    assert f"on {runs[0]['timesteps']:,}, {runs[1]['timesteps']:,} and {runs[2]['timesteps']:,} steps" in para
    episodes, readings = [], []
    for k, run in enumerate(runs):
        assert len(run["lr_fractions"]) == 1 + 2 * (run["timesteps"] // 2048), k  # built, then two an update
        rep, = seed_runs(f"{rerun}_replay_012", [k])
        # the record replayed: this seed's batch of the rerun (the folder its command wrote, combined_from)
        batch = batch_of(agg, k)
        assert rep["replay"]["identical"] is True and rep["replay"]["from"] == f"{batch}/ppo_seed{k}.json"
        assert rep["replay"]["lr_readings"] == [len(run["lr_fractions"])] * 2 and rep["lr_fractions"] == \
            run["lr_fractions"]
        assert rep["train_episodes"] == run["train_episodes"] and rep["timesteps"] == run["timesteps"]
        episodes.append(f"{run['train_episodes']:,}")
        readings.append(str(len(run["lr_fractions"])))
    assert f"training episodes ({episodes[0]}, {episodes[1]} and {episodes[2]}), with all {readings[0]}, " \
        f"{readings[1]} and {readings[2]} of the rate's readings" in para
    final = " / ".join(str(pct(r["success_rate"])) for r in runs)
    replaced = " / ".join(str(pct(v)) for v in old["summary"]["ppo"]["final"]["success_rates"])
    page = joined(ROOT / "docs" / "environments.md")
    assert f"{final} % at 15 CPU-min" in page and f"batch of stop 58, {replaced} %" in page


def _listed(items) -> str:
    """Items as the pages list them: "a", "a and b", "a, b and c"."""
    items = [str(i) for i in items]
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _assert_seeds_on_page(para: str, runs: list, span: str = "15", crushes_end: str = ")") -> None:
    """Each run's checkpoints ("a, b and c % at 5 / 10 / {span} CPU-min"), steps ("on n, m and k steps") and crushes
    ("(a, b and c crushes of 50 held out{crushes_end}") as the paragraph ``para`` gives them."""
    assert f"{_listed(checkpoint_rates(r) for r in runs)} % at 5 / 10 / {span} CPU-min" in para
    assert f"on {_listed(format(r['timesteps'], ',') for r in runs)} steps" in para
    assert f"({_listed(r['outcomes']['crushed'] for r in runs)} crushes of 50 held out{crushes_end}" in para


def _assert_replays_identical(folder: str, replayed: str, seeds: tuple) -> list[dict]:
    """Each seed's replay in ``replayed`` says ``identical`` against its batch of the record ``folder`` (the folder
    its command wrote, ``combined_from``), having read every one of the rate's readings, with the record's policy
    digest; returns the record's runs."""
    agg, runs = aggregate(folder), seed_runs(folder, seeds)
    for k, run, rep in zip(seeds, runs, seed_runs(replayed, seeds)):
        assert rep["replay"]["identical"] is True and rep["replay"]["from"] == f"{batch_of(agg, k)}/ppo_seed{k}.json"
        assert rep["replay"]["lr_readings"] == [len(run["lr_fractions"])] * 2
        assert rep["policy_digest"] == run["policy_digest"]
    return runs


def _assert_long_run(title: str, folder: str, minutes: int, seeds: tuple) -> None:
    """The learning page's paragraph ``title`` on the record ``folder`` (``--minutes minutes``, ``seeds``): each
    seed's checkpoints ("a, b and c % at 5 / 10 / … / M CPU-min"), its steps and crushes, and that the runs keep what
    a replay needs (the rate's readings, the policy's digest)."""
    para = learning_paragraph(title)
    assert f"docs/baselines/{folder}/" in para
    agg = aggregate(folder)
    assert agg["minutes"] == float(minutes) and agg["seeds"] == list(seeds) and agg["step_charge"] == 0.005
    runs = seed_runs(folder, seeds)
    _assert_seeds_on_page(para, runs, f"… / {minutes}")
    assert all(len(r["lr_fractions"]) == 1 + 2 * (r["timesteps"] // 2048) and len(r["policy_digest"]) == 16
               for r in runs)


def test_the_30_minute_rerun_on_the_learning_page_is_its_record():
    _assert_long_run("**Twice the budget again, from a fresh clone**",
                     "rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge_30min_rerun", 30, (0, 1))


def test_the_40_minute_batch_and_its_replays_are_their_records():
    """"Forty CPU-minutes, from a fresh clone": each seed's eight checkpoints, steps and crushes (the page), seeds 0
    and 1 replayed ``identical`` against their batches having read every one of the rate's readings, and the steps the
    environments page gives."""
    folder = "rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge_40min"
    _assert_long_run("**Forty CPU-minutes, from a fresh clone**", folder, 40, (0, 1, 2))
    agg = aggregate(folder)
    runs = _assert_replays_identical(folder, f"{folder}_replay_01", (0, 1))
    para = learning_paragraph("**Forty CPU-minutes, from a fresh clone**")
    readings = _listed(format(len(r["lr_fractions"]), ",") for r in runs)
    assert f"{folder}_replay_01/" in para and f"their {readings} readings of the rate" in para
    steps = agg["summary"]["ppo"]["final"]["timesteps"]  # the environments page's "on 1.72M–2.25M steps"
    assert f"on {min(steps) / 1e6:.2f}M–{max(steps) / 1e6:.2f}M steps" in joined(ROOT / "docs" / "environments.md")


def test_four_copies_and_minibatches_of_128_are_their_records():
    """"Four copies and minibatches of 128": the README's K-finger aided cell since stop 67; its options (four
    copies, a rollout of 512 a copy, minibatches of 128) in the command and the hyperparameters, each seed's
    checkpoints, crushes and steps (the page), the batch of seeds 3-5 likewise, both batches' finals in the README,
    and the replayed seeds ``identical`` against their batches having read every one of the rate's readings."""
    folder = "rl_multi_v7_peak_light_log_std_half_lr_decay_step_charge_4envs_512_batch128"
    assert ROWS["PickMultiFragile-v7"][1][AIDED] == folder
    para = learning_paragraph("**Four copies and minibatches of 128")
    for name, seeds in ((folder, (0, 1, 2)), (f"{folder}_345", (3, 4, 5))):
        assert f"docs/baselines/{name}/" in para
        agg = aggregate(name)
        assert agg["seeds"] == list(seeds) and agg["minutes"] == 15.0 and agg["n_envs"] == 4
        assert "; but n_steps = 512; but batch_size = 128;" in agg["hyperparameters"]
        runs = seed_runs(name, seeds)
        assert all(r["hyperparameters"].endswith("n_steps = 512, batch_size = 128, learning_rate = 0.0003 falling "
                                                 "linearly to 0 over the budget") for r in runs)
        means = " / ".join(str(pct(c["mean"])) for c in agg["summary"]["ppo"]["checkpoints"])
        _assert_seeds_on_page(para, runs, crushes_end=f"; mean {means} %)")
        assert all(len(r["lr_fractions"]) == 1 + 2 * (r["timesteps"] // 2048) for r in runs)
    finals = [final_rates(f) for f in (folder, f"{folder}_345")]
    assert f"(seeds 0–2: {finals[0]} %; 3–5: {finals[1]} %;" in joined(ROOT / "README.md")
    replayed = f"{folder}_replay_012"
    assert f"docs/baselines/{replayed}/" in para
    runs = _assert_replays_identical(folder, replayed, (0, 1, 2))
    assert all(rep["train_episodes"] == run["train_episodes"] for run, rep in zip(runs, seed_runs(replayed, (0, 1, 2))))
    assert f"training episodes ({_listed(format(r['train_episodes'], ',') for r in runs)}), their " \
        f"{_listed(format(len(r['lr_fractions']), ',') for r in runs)} readings of the rate" in para
    # seeds 3-5 replayed at stop 68 against their batches (named on the environments page too)
    replayed = f"{folder}_replay_345"
    assert f"docs/baselines/{replayed}/" in para and (BASELINES / replayed).is_dir()
    assert "its batch of seeds 3–5 (`..._batch128_replay_345`" in joined(ROOT / "docs" / "environments.md")
    runs = _assert_replays_identical(f"{folder}_345", replayed, (3, 4, 5))
    assert all(rep["train_episodes"] == run["train_episodes"] for run, rep in zip(runs, seed_runs(replayed, (3, 4, 5))))
    assert f"training episodes ({_listed(format(r['train_episodes'], ',') for r in runs)}), their " \
        f"{_listed(format(len(r['lr_fractions']), ',') for r in runs)} readings of the rate" in para


def test_the_pinchs_four_copies_batch_is_its_record():
    """"The pinch's discount command on four copies with minibatches of 128": seeds 3-5 and 0-2 of the pinch's aided
    command with the K fingers' four copies; each seed's checkpoints, steps and crushes are the record's, and the
    one-copy numbers each batch is set against are that copy's batch of the same seeds."""
    folder = "rl_pick_v7_peak_log_std_gamma_4envs_512_batch128_345"
    para = learning_paragraph("**The pinch's discount command on four copies with minibatches of 128**")
    assert f"docs/baselines/{folder}/" in para
    agg = aggregate(folder)
    assert agg["seeds"] == [3, 4, 5] and agg["n_envs"] == 4 and measured_as(agg) == "PickFragile-v7"
    assert agg["hyperparameters"].endswith("; but gamma = 0.995; but log_std_init = -1.0; but n_steps = 512; but "
                                           "batch_size = 128")
    _assert_seeds_on_page(para, seed_runs(folder, (3, 4, 5)))
    one = seed_runs("rl_pick_v7_peak_log_std_gamma_345", (3, 4))
    assert f"against {_listed(checkpoint_rates(r) for r in one)} % for seeds 3 and 4 on one copy" in para
    fifth, = seed_runs("rl_pick_v7_peak_log_std_gamma_345", (5,))
    assert f"whose seed 5 ended at {pct(fifth['success_rate'])} %" in para
    millions = [f"{r['timesteps'] / 1e6:.2f}M" for r in one]
    assert f"({_listed(millions)} steps" in para
    # seeds 0-2 (stop 68): met, with one seed that never grips; the count and the steps over six seeds
    first = folder.removesuffix("_345")
    assert f"docs/baselines/{first}/" in para and aggregate(first)["hyperparameters"] == agg["hyperparameters"]
    runs = seed_runs(first, (0, 1, 2))
    _assert_seeds_on_page(para, runs)
    one = seed_runs("rl_pick_v7_peak_log_std_gamma", (0, 1, 2))
    assert f"as one copy's batch of these seeds ({' / '.join(str(pct(r['success_rate'])) for r in one)} %)" in para
    assert runs[1]["outcomes"]["timeout"] == 40 and "(40 of its 50 held-out episodes time out)" in para
    four = runs + seed_runs(folder, (3, 4, 5))
    one += seed_runs("rl_pick_v7_peak_log_std_gamma_345", (3, 4, 5))
    assert sum(r["success_rate"] >= 0.8 for r in four) == sum(r["success_rate"] >= 0.8 for r in one) == 3
    span = [f"{min(r['timesteps'] for r in rs) / 1e6:.2f}M–{max(r['timesteps'] for r in rs) / 1e6:.2f}M"
            for rs in (four, one)]
    assert f"({span[0]} against {span[1]})" in para
