"""Long random rollouts of every registered pick env are bit-identical to a reference recorded before a change.

``tests/test_env_step_reference.py`` replays one scripted episode and 30 random steps per id; this test adds
longer runs of the kind ``simgrip.envs.throughput.measure_throughput`` times (issue 18, item 5: the env layer's
overhead over bare ``mj_step``), so that a per-step shortcut is checked where curled fingers, crushes, drops,
knock-overs, invalid states and resets happen:

* ``uniform``: actions uniform in ``[-1, 1]`` (the throughput measure's), ``STEPS`` steps, a new episode
  (``reset(seed=SEED + step)``) after each termination;
* ``smooth``: a random walk clipped to ``[-1.2, 1.2]`` (clipping, held grips, lifts), likewise.

``tests/data/env_rollout_reference.npz`` holds the actions and a digest per ``reset`` / ``step`` of everything
it returns (``test_env_step_reference._digest``: observation bytes, reward, flags, every ``info`` key and value
in order).  It was recorded (``python tests/test_env_rollout_reference.py``) by the code before the issue-18
item-5 pass of the env layer (commit 4640f23, run from a worktree of it); any change of a returned value by a
single bit fails the test, naming the id, run and step.  Ids retired since (``simgrip.envs.RETIRED``) are
replayed through ``retired_spec``; ids registered since were appended by the same command (PickFragile-v4 and
PickMultiFragile-v4, recorded at 5aaecbb's successors, whose env layer gives the recorded ids' bytes; PickFragile-v5,
PickMultiFragile-v5, PickCradleFragile-v5 and PickSphereFragile-v5 at a9625e7 with v5 added, appended without
re-recording the others; PlaceFragile-v4 likewise; PickFragile-v6 and PickMultiFragile-v6 with v6 added, the
others' digests reproduced unchanged; PlaceFragile-v5 likewise, then PlaceFragile-v6 and PlaceFragile-v7;
PickFragile-v7, PickMultiFragile-v7, PlaceFragile-v8, PickCradleFragile-v6 and PickSphereFragile-v6 under MuJoCo 4.0.1,
the others' digests reproduced unchanged).  The physics is MuJoCo's: the reference holds for the MuJoCo versions
stored beside it (the one it was recorded with and each later one whose replay gave every digest,
``--add-version``: ``tests/reference_versions.py``); another version skips, saying so.  An intended change
of an env's output regenerates the file with the command above.

A host whose arithmetic gives other last bits holds its own digest set beside the file (``--add-host``;
``--which-host`` names the set this host reproduces: ``tests/reference_versions.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from reference_versions import installed_sets, maintain, recorded_versions  # noqa: E402
from test_env_step_reference import _digest  # noqa: E402  (the canonical digest of a step's output)

DATA = Path(__file__).parent / "data" / "env_rollout_reference.npz"
SEED = 9100
STEPS = 400
RUNS = ("uniform", "smooth")


def _actions(run: str, k: int, n: int) -> np.ndarray:
    """The ``run``'s actions for the ``k``-th id (``n`` entries each): float16 values (stored as such: half the
    file), passed as float32 as the measure passes its actions."""
    rng = np.random.default_rng(SEED + 10 * k + RUNS.index(run))
    if run == "uniform":
        return rng.uniform(-1.0, 1.0, (STEPS, n)).astype(np.float16)
    steps = rng.normal(0.0, 0.25, (STEPS, n))
    a = np.empty((STEPS, n))
    x = np.zeros(n)
    for t in range(STEPS):
        x = np.clip(x + steps[t], -1.2, 1.2)
        a[t] = x
    return a.astype(np.float16)


def _rollout(env, seed: int, actions) -> list[bytes]:
    """Digests of ``reset(seed)`` and of every step of ``actions``, a new episode after each termination."""
    obs, info = env.reset(seed=seed)
    out = [_digest(obs, info)]
    for t, a in enumerate(actions.astype(np.float32)):
        obs, r, te, tr, info = env.step(a)
        out.append(_digest(obs, r, te, tr, info))
        if te or tr:
            obs, info = env.reset(seed=seed + t + 1)
            out.append(_digest(obs, info))
    return out


def _make(env_id: str):
    """The measure's env (no time limit, so the runs go on): a registered id, or a retired one through
    ``retired_spec`` (ids retired since they were recorded stay checked)."""
    import gymnasium as gym

    from simgrip.envs import RETIRED, retired_spec

    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id).unwrapped


def _record() -> None:  # pragma: no cover - regenerates the reference
    import mujoco

    from simgrip.envs import _ENVS

    # the recorded ids in their order (an id's k seeds its actions; retired ones stay), newly registered ones after
    # (the MuJoCo versions the old file holds for stay, where this one reproduces it: only ids are appended)
    ids, versions = [], [mujoco.__version__]
    if DATA.exists():
        with np.load(DATA) as old:
            ids = old["ids"].tolist()
            if not _mismatches(old)[0]:
                versions = list(dict.fromkeys(recorded_versions(old) + versions))
    ids += [i for i in _ENVS if i not in ids]
    arrays = {"mujoco_version": np.array(versions), "ids": np.array(ids)}
    for k, env_id in enumerate(ids):
        env = _make(env_id)
        for run in RUNS:
            actions = _actions(run, k, env.action_space.shape[0])
            digests = _rollout(env, SEED + k, actions)
            arrays[f"a{k}_{run}"] = actions
            arrays[f"d{k}_{run}"] = np.frombuffer(b"".join(digests), dtype=np.uint64)
            print(env_id, run, len(digests) - STEPS - 1, "resets")
        env.close()
    np.savez_compressed(DATA, **arrays)


def _replay_all(ref) -> dict:
    """This host's digests of every recorded run, keyed as the reference's (``d<k>_<run>``)."""
    import simgrip.envs  # noqa: F401  (registers the ids)

    got = {}
    for k, env_id in enumerate(ref["ids"].tolist()):
        env = _make(env_id)
        try:
            for run in RUNS:
                actions = ref[f"a{k}_{run}"]  # (stored: a change of numpy's random streams changes nothing here)
                got[f"d{k}_{run}"] = np.frombuffer(b"".join(_rollout(env, SEED + k, actions)), dtype=np.uint64)
        finally:
            env.close()
    return got


def _compare(ids: list, got: dict, want: dict) -> tuple[list[str], int]:
    """Where the digests ``got`` differ from the set ``want`` (empty: nowhere), and how many resets it holds."""
    out, resets = [], 0
    for k, env_id in enumerate(ids):
        for run in RUNS:
            g, w = got[f"d{k}_{run}"], want[f"d{k}_{run}"]
            bad = np.flatnonzero(g[:w.size] != w[:g.size])
            if bad.size or g.size != w.size:
                out.append(f"{env_id}, {run} run: output differs from the reference at digest "
                           f"{int(bad[0]) if bad.size else min(g.size, w.size)} ({g.size} replayed, "
                           f"{w.size} recorded)")
            resets += w.size - STEPS - 1
    return out, resets


def _mismatches(ref) -> tuple[list[str], int]:
    """Where the replay of every recorded id under the installed MuJoCo differs from ``ref`` (empty: nowhere),
    and how many resets the recorded runs hold."""
    return _compare(ref["ids"].tolist(), _replay_all(ref), {k: ref[k] for k in ref.files if k.startswith("d")})


def test_long_rollouts_match_the_reference():
    sets = installed_sets(DATA)  # (skips, naming the versions recorded, when none holds for this MuJoCo)
    with np.load(DATA) as ref:  # closed at the end (an open NpzFile warns when collected)
        ids, got = ref["ids"].tolist(), _replay_all(ref)
    found = [_compare(ids, got, want) for want in sets]
    match = [resets for bad, resets in found if not bad]
    assert match, found[0][0][0]  # one recorded set, whole
    assert match[0] > 10, "the runs should reach terminations (and the resets after them)"


if __name__ == "__main__":  # pragma: no cover
    maintain("test_env_rollout_reference.py", DATA, sys.argv[1:], _replay_all, lambda ref: _mismatches(ref)[0], _record)
