"""Every registered pick env's ``reset`` / ``step`` output is bit-identical to a recorded reference.

``tests/data/env_step_reference.npz`` was recorded (``python tests/test_env_step_reference.py``) before the
hot-path rework of issue 18 (the env layer's Python time per control step): for each env id, the actions of
one episode of the scripted controller (up to 200 steps) and of one of uniform random actions in ``[-1.2, 1.2]``
(clipping, crushes, knock-overs; up to 30 steps), and a digest per ``reset`` / ``step`` of everything it
returns (observation bytes, reward, flags, every ``info`` key and value, in order).  The test replays the
stored actions and compares the digests: any change of an observation, reward, termination or info entry, by
a single bit, fails it, naming the env, episode and step.  The physics is MuJoCo's, so the reference holds
for the MuJoCo version it was recorded with (stored beside it with each later one whose replay gave every
digest, ``--add-version``: ``tests/reference_versions.py``; another version skips, saying so).  An
intended change of an env's output regenerates the file with the command above.  Ids retired since they were
recorded (``simgrip.envs.RETIRED``) are replayed through ``retired_spec``: every recorded id stays checked.

A host whose arithmetic gives other last bits holds its own digest set beside the file (``--add-host``;
``--which-host`` names the set this host reproduces: ``tests/reference_versions.py``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from reference_versions import installed_sets, maintain  # noqa: E402

DATA = Path(__file__).parent / "data" / "env_step_reference.npz"
SEED = 4321  # episode seeds SEED, SEED + 1 (the scripted and the random episode)
MAX_SCRIPTED, MAX_RANDOM = 200, 30


def _canon(v) -> str:
    """A canonical, exact text of a returned value (arrays by dtype, shape and bytes; floats by repr)."""
    if dataclasses.is_dataclass(v):
        return f"{type(v).__name__}{v!r}"
    if isinstance(v, np.ndarray):
        return f"arr({v.dtype.str},{v.shape},{v.tobytes().hex()})"
    if isinstance(v, (list, tuple)):
        return f"{type(v).__name__}[" + ",".join(_canon(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ",".join(f"{k!r}:{_canon(x)}" for k, x in v.items()) + "}"
    return f"{type(v).__name__}:{v!r}"


def _digest(*values) -> bytes:
    return hashlib.blake2b("|".join(_canon(v) for v in values).encode(), digest_size=8).digest()


def _replay(env, seed: int, actions) -> list[bytes]:
    """Digests of ``reset(seed)`` and of each ``step`` of ``actions`` (stops at a termination)."""
    obs, info = env.reset(seed=seed)
    out = [_digest(obs, info)]
    for a in actions:
        obs, r, te, tr, info = env.step(a)
        out.append(_digest(obs, r, te, tr, info))
        if te or tr:
            break
    return out


def _make(env_id: str):
    """``gym.make`` of a registered id, or of a retired one through ``retired_spec``."""
    import gymnasium as gym

    from simgrip.envs import RETIRED, retired_spec

    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id)


def _record() -> None:  # pragma: no cover - regenerates the reference
    import mujoco

    from simgrip.envs import _ENVS, FRAGILE_ENV_IDS, RETIRED
    from simgrip.envs.baselines import _members
    from simgrip.envs.scripted import ScriptedPickPolicy
    from simgrip.envs.scripted_multi import ScriptedMultiPolicy
    from simgrip.envs.valve import ValveCommand

    # the recorded order (an id's k seeds its random actions), the retired ids in place, the newer ones after
    ids = [i for i in _ENVS if i not in FRAGILE_ENV_IDS] + list(RETIRED) + list(FRAGILE_ENV_IDS)
    arrays = {"mujoco_version": np.array(mujoco.__version__), "ids": np.array(ids)}
    for k, env_id in enumerate(ids):
        env = _make(env_id)
        u = env.unwrapped
        n = env.action_space.shape[0]
        obs, info = env.reset(seed=SEED)
        if env_id in FRAGILE_ENV_IDS or env_id in RETIRED:
            claw = "cradle" if getattr(u, "grip", None) == "III" else \
                "sphere" if getattr(u, "shapes", ()) == ("sphere",) else None
            valve = isinstance(u, ValveCommand)
            act = _members("observation", "full", n == 3, claw, None, valve)[0][1](env, info, SEED)
        else:
            pol = (ScriptedMultiPolicy if "Multi" in env_id else ScriptedPickPolicy)()
            pol.reset(u, info)
            act = lambda o, t: pol(o)  # noqa: E731
        scripted = []
        for t in range(MAX_SCRIPTED):
            a = np.asarray(act(obs, t), dtype=np.float32)
            scripted.append(a)
            obs, _, te, tr, _ = env.step(a)
            if te or tr:
                break
        rand = np.random.default_rng(SEED + k).uniform(-1.2, 1.2, (MAX_RANDOM, n)).astype(np.float32)
        arrays[f"a{k}_0"] = np.array(scripted)
        arrays[f"a{k}_1"] = rand
        arrays[f"d{k}_0"] = np.frombuffer(b"".join(_replay(env, SEED, scripted)), dtype=np.uint64)
        arrays[f"d{k}_1"] = np.frombuffer(b"".join(_replay(env, SEED + 1, rand)), dtype=np.uint64)
        env.close()
        print(env_id, len(scripted), "scripted steps", len(arrays[f"d{k}_1"]) - 1, "random steps")
    np.savez_compressed(DATA, **arrays)


def _replay_all(ref) -> dict:
    """This host's digests of every recorded episode, keyed as the reference's (``d<k>_<e>``)."""
    import simgrip.envs  # noqa: F401  (registers the ids)

    got = {}
    for k, env_id in enumerate(ref["ids"].tolist()):
        env = _make(env_id)  # a retired id through retired_spec (no deprecation notice)
        try:
            for e in (0, 1):
                got[f"d{k}_{e}"] = np.frombuffer(b"".join(_replay(env, SEED + e, ref[f"a{k}_{e}"])), dtype=np.uint64)
        finally:
            env.close()
    return got


def _compare(ids: list, got: dict, want: dict) -> list[str]:
    """Where the digests ``got`` differ from the set ``want`` (empty: nowhere)."""
    out = []
    for k, env_id in enumerate(ids):
        for e in (0, 1):
            g, w = got[f"d{k}_{e}"], want[f"d{k}_{e}"]
            bad = [i for i in range(min(g.size, w.size)) if g[i] != w[i]]
            if bad or g.size != w.size:
                out.append(f"{env_id}, episode {e}: output differs from the reference at "
                           f"{'reset' if bad and bad[0] == 0 else 'step %d' % (bad[0] if bad else min(g.size, w.size))}"
                           f" ({g.size - 1} steps replayed, {w.size - 1} recorded)")
    return out


def _mismatches(ref) -> list[str]:
    """Where the replay of every recorded id under the installed MuJoCo differs from ``ref`` (empty: nowhere)."""
    return _compare(ref["ids"].tolist(), _replay_all(ref), {k: ref[k] for k in ref.files if k.startswith("d")})


def test_env_steps_match_the_reference():
    sets = installed_sets(DATA)  # (skips, naming the versions recorded, when none holds for this MuJoCo)
    with np.load(DATA) as ref:  # closed at the end (an open NpzFile warns when collected)
        ids, got = ref["ids"].tolist(), _replay_all(ref)
    found = [_compare(ids, got, want) for want in sets]
    assert any(not bad for bad in found), found[0][0]  # one recorded set, whole


if __name__ == "__main__":  # pragma: no cover
    maintain("test_env_step_reference.py", DATA, sys.argv[1:], _replay_all, _mismatches, _record)
