"""One Ctrl-C stops each learning command with one line and status 130, no traceback (issue 18; the brief's
"well-behaved processes").

Each command is started in its own process group and, once it has spent a given CPU time (so the signal
lands in its work, not in the interpreter's start), sent SIGINT to the whole group, as a terminal's Ctrl-C is.
Before :func:`simgrip.interrupt.run_main`, ``python -m simgrip.envs.baselines`` and ``train_sb3.py`` printed a
traceback, and ``rl_baselines.py`` one when the signal came before its trainings started.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads CPU times from /proc")


def _env():
    import simgrip

    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(simgrip.__file__).resolve().parent.parent),
                                         env.get("PYTHONPATH", "")])
    return env


def _cpu_s(pid: int) -> float:
    """The process's user + system CPU time [s] (0 once it is gone)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0.0
    fields = text[text.rindex(")") + 2:].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _ctrl_c_after(cmd: list[str], cpu_s: float, cwd: Path) -> tuple[int, str]:
    """Start ``cmd``, send SIGINT to its process group once it has used ``cpu_s`` of CPU; ``(status, stderr)``."""
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=_env(), cwd=cwd,
                         start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while p.poll() is None and _cpu_s(p.pid) < cpu_s and time.monotonic() < deadline:
            time.sleep(0.05)
        assert p.poll() is None, f"ended before the signal: {p.returncode}"
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    return p.returncode, err


def _one_line(err: str, name: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{name}: interrupted"), err
    assert "Traceback" not in err


def test_baselines_ctrl_c_one_line_and_no_file(tmp_path):
    out = tmp_path / "open.json"
    code, err = _ctrl_c_after([sys.executable, "-m", "simgrip.envs.baselines", "--env", "simgrip/PickFragile-v7",
                               "--policy", "openloop", "--seeds", "8000-8999", "--out", str(out)], 2.0, tmp_path)
    assert code == 130
    _one_line(err, "baselines")
    assert not out.exists() and list(tmp_path.iterdir()) == []  # nothing half-written


def test_evaluate_policy_ctrl_c_one_line(tmp_path):
    code, err = _ctrl_c_after([sys.executable, str(EXAMPLES / "evaluate_policy.py"), "--env",
                               "simgrip/PickFragile-v7", "--policy", "observation", "--episodes", "500"], 2.0, ROOT)
    assert code == 130
    _one_line(err, "evaluate_policy")


def test_train_sb3_ctrl_c_one_line(tmp_path):
    pytest.importorskip("stable_baselines3")
    code, err = _ctrl_c_after([sys.executable, str(EXAMPLES / "train_sb3.py"), "--algo", "ppo", "--env",
                               "simgrip/PickFragile-v7", "--minutes", "5", "--eval-episodes", "1",
                               "--out", str(tmp_path / "run")], 4.0, ROOT)
    assert code == 130
    _one_line(err, "train_sb3")


def test_rl_baselines_ctrl_c_before_the_trainings_start(tmp_path):
    """A Ctrl-C in the driver's own checks (it builds the env once, before any training starts) ends as one
    line and 130 too: before run_main it printed a traceback (the driver handled it only around the runs).  The
    script runs as ``__main__`` with its env check made to raise what a Ctrl-C there raises."""
    pytest.importorskip("stable_baselines3")
    argv = ["rl_baselines.py", "--env", "simgrip/PickFragile-v7", "--algo", "ppo", "--seeds", "0", "--minutes", "5",
            "--out", str(tmp_path / "runs")]
    code = ("import runpy, sys\n"
            "import simgrip.envs.evaluation as evaluation\n"
            "def interrupted(*args, **kwargs):\n"
            "    raise KeyboardInterrupt\n"
            "evaluation.check_env_id = interrupted\n"
            f"sys.argv = {argv!r}\n"
            f"runpy.run_path({str(EXAMPLES / 'rl_baselines.py')!r}, run_name='__main__')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), cwd=ROOT, timeout=120)
    assert r.returncode == 130
    _one_line(r.stderr, "rl_baselines")
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize("script", ["random_policy", "scripted_pick"])
def test_episode_examples_ctrl_c_one_line(script):
    """The two episode examples under run_main too (an audit found a KeyboardInterrupt traceback)."""
    code, err = _ctrl_c_after([sys.executable, str(EXAMPLES / f"{script}.py"), "--episodes", "100000"], 2.0, ROOT)
    assert code == 130
    _one_line(err, script)


@pytest.mark.parametrize("script", ["random_policy", "scripted_pick"])
def test_episode_examples_into_a_closed_pipe_end_quietly(script):
    """``scripted_pick.py --episodes 3 | head -1`` printed a BrokenPipeError traceback and exited 1."""
    r = subprocess.run(f"{sys.executable} {EXAMPLES / f'{script}.py'} --episodes 3 | head -c 1",
                       shell=True, capture_output=True, text=True, env=_env(), cwd=ROOT, timeout=120)
    assert r.returncode == 0 and "Traceback" not in r.stderr and r.stderr == "", r.stderr


@pytest.mark.parametrize("args, name", [(["--env", "CartPole-v1"], "--env"),
                                        (["--env", "simgrip/PickMulti-v0", "--fingers", "100000"], "--fingers")])
@pytest.mark.parametrize("script", ["random_policy", "scripted_pick"])
def test_episode_examples_refuse_by_name(script, args, name):
    """Another library's env (no pick info keys: a KeyError mid-run) and a finger count past MAX_FINGERS (a
    ValueError traceback from the env) are refused before any episode, in argparse's way, naming the option."""
    r = subprocess.run([sys.executable, str(EXAMPLES / f"{script}.py"), *args], capture_output=True, text=True,
                       env=_env(), cwd=ROOT, timeout=120)
    assert r.returncode == 2 and name in r.stderr.strip().splitlines()[-1] and "Traceback" not in r.stderr
