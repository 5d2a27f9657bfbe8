"""The learner's arithmetic: a short PPO training gives a recorded policy to the last bit.

``--replay`` (:mod:`simgrip.envs.budget_replay`) reruns a record's trainings at its steps; it gives the record to
the last digit only where the envs and the learner both compute as the record's machine did.  The envs' side is
``tests/test_env_step_reference.py --which-host``; this file is the learner's: ``examples/train_sb3.py`` runs the
pinch's aided command (the README's, ``--action-offset -0.2 0.2 --log-std-init -1 --gamma 0.995``, seed 0) for two
of PPO's rollouts and updates (4,096 steps: 2 x 10 epochs of SB3's minibatches, Adam, the Gaussian policy), and the
digest of the policy it saves (:func:`simgrip.envs.budget_replay.policy_digest`) is compared with the recorded ones.
A set is recorded per (MuJoCo, NumPy, PyTorch, Stable-Baselines3) versions and host (``--add-host``); the set
recorded first (stop 66) is of a host of the kind that made and replayed the README's records (whose envs give
``env_step_reference.npz``), so where the test passes on it a replay of those records can give them whole; a set
added later names the CPU that gave it (``cpu``), and a host that reproduces only such a set replays the records to
other last bits.  Under versions no set names the test skips.

    python tests/test_learner_reference.py [--regenerate | --add-host | --which-host]

Needs the ``rl`` extra (skipped without it); about 10 CPU-s.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).parent / "data" / "learner_reference.json"
#: the pinch's aided command (README), two rollouts; evaluation on two held-out seeds
COMMAND = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--action-offset", "-0.2", "0.2",
           "--log-std-init", "-1", "--gamma", "0.995", "--seed", "0", "--steps", "4096",
           "--eval-episodes", "2", "--eval-seed", "8000", "--threads", "1"]
#: what the digest depends on besides the host (the versions a run records)
KEYS = ("mujoco", "numpy", "stable-baselines3", "torch")


def _run() -> dict:
    """This host's result of :data:`COMMAND`: the versions, the policy's digest, the steps and the held-out return."""
    with tempfile.TemporaryDirectory() as tmp:
        proc = subprocess.run([sys.executable, str(ROOT / "examples" / "train_sb3.py"), *COMMAND, "--out", tmp],
                              capture_output=True, text=True, cwd=ROOT, timeout=600)
        assert proc.returncode == 0, proc.stderr[-2000:]
        rec = json.loads((Path(tmp) / "ppo_eval.json").read_text(encoding="utf-8"))
    return {"versions": {k: rec["versions"][k] for k in KEYS}, "policy_digest": rec["policy_digest"],
            "timesteps": rec["timesteps"], "mean_return": rec["mean_return"]}


def _sets() -> list[dict]:
    return json.loads(DATA.read_text(encoding="utf-8"))["sets"] if DATA.exists() else []


def _cpu() -> str:  # pragma: no cover - maintenance command
    """This host's CPU model as Linux names it (``/proc/cpuinfo``), or ``platform.processor()`` elsewhere."""
    import platform

    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def which_set(got: dict) -> int | None:
    """The index of the recorded set whose versions and digest equal ``got``'s (:func:`_run`), or None."""
    for i, s in enumerate(_sets()):
        if s["versions"] == got["versions"] and s["policy_digest"] == got["policy_digest"]:
            return i
    return None


def test_the_learner_gives_a_recorded_policy():
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("torch")
    from simgrip.envs.budget_replay import versions

    installed = {k: versions()[k] for k in KEYS}
    recorded = [s for s in _sets() if s["versions"] == installed]
    if not recorded:
        pytest.skip(f"no learner set recorded for {installed} (python tests/test_learner_reference.py --add-host)")
    got = _run()
    assert got["versions"] == installed and got["timesteps"] == 4096
    assert which_set(got) is not None, (
        f"policy digest {got['policy_digest']} is none of the recorded "
        f"{[s['policy_digest'] for s in recorded]}: this host gives other last bits (its envs', where "
        f"tests/test_env_step_reference.py --which-host names no set, or its learner's)")


def test_a_digest_or_versions_not_recorded_is_no_set():
    """:func:`which_set` matches versions and digest together: one bit of either changed is no set."""
    first = _sets()[0]
    assert which_set(first) == 0
    assert which_set({**first, "policy_digest": format(int(first["policy_digest"], 16) ^ 1, "016x")}) is None
    assert which_set({**first, "versions": {**first["versions"], "torch": "0.0.0"}}) is None


def _write(sets: list[dict]) -> None:  # pragma: no cover - maintenance command
    text = json.dumps({"command": ["examples/train_sb3.py", *COMMAND], "sets": sets}, indent=2) + "\n"
    tmp = DATA.with_suffix(".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(DATA)


def main(argv: list[str]) -> None:  # pragma: no cover - maintenance command
    if argv not in ([], ["--regenerate"], ["--add-host"], ["--which-host"]):
        raise SystemExit("usage: python tests/test_learner_reference.py [--regenerate | --add-host | --which-host]")
    got = _run()
    found = which_set(got)
    if argv == ["--which-host"]:
        print(f"set {found} of {DATA.name}" if found is not None else
              f"none: this host's learner ({got['policy_digest']} under {got['versions']}) differs from every set")
    elif argv == ["--add-host"]:
        if found is not None:
            raise SystemExit(f"{DATA.name}: this host reproduces set {found} already")
        _write(_sets() + [{**got, "cpu": _cpu()}])
        print(f"{DATA.name}: set {len(_sets()) - 1} added")
    else:
        _write([got])
        print(f"{DATA.name}: recorded anew")


if __name__ == "__main__":  # pragma: no cover
    main(sys.argv[1:])
