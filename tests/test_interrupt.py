"""One Ctrl-C stops everything: the command, its worker processes, and leaves no partial file.

Each case starts a real ``simgrip`` command with ``--jobs 2`` in its own
session, waits until its worker processes are up (and ~2 s at least), sends
SIGINT (to the process, or to its whole process group as a terminal's Ctrl-C
does) or SIGTERM, and checks:

* it exits with status 130 (within :data:`EXIT_WITHIN_S`, a hang guard);
* stderr is the one line ``simgrip <command>: interrupted`` (no traceback);
* no process of its session is left (found through ``/proc``: the session id
  of every process, so workers re-parented to init are found too);
* ``--out`` holds no partial file: no temporary file of
  :func:`simgrip.io.atomic_write`, and every result file present is whole.

:func:`test_interrupt_inside_one_long_solve` does the same to ``simulate``
inside one long phase: MuJoCo's compile of a large model (one C call, where
Python cannot run the signal handler: the watchdog of
:mod:`simgrip.interrupt` ends the run) and a long settle.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from simgrip.io import TEMP_PREFIX

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")

#: Seconds from the signal to the exit of the command and all its workers: a hang guard only (issue 22, item 8;
#: ~1 s alone, but a 2-core machine shared by other jobs may take many times that).  The guarantee is the rest:
#: status 130 (the signal, not the end of the run, ended it), no process of its session left, no partial file.
EXIT_WITHIN_S = 30.0
#: Seconds the command runs before the signal (at least; workers must be up too).
RUN_BEFORE_S = 2.0
#: Seconds allowed for the workers to start on a loaded machine.
START_WITHIN_S = 60.0

COMMANDS = {
    "bench": ["bench", "--quick"],
    "stress": ["stress", "--cases", "50"],
    "figures": ["figures"],
}


def _stat(pid: int) -> list[str] | None:
    """Fields of /proc/PID/stat after the command name (state is [0], ppid [1], pgrp [2], session [3])."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text[text.rindex(")") + 2:].split()


def session_processes(sid: int) -> dict[int, str]:
    """Live (non-zombie) processes of session ``sid``: pid -> state."""
    found = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            st = _stat(int(entry))
            if st is not None and int(st[3]) == sid and st[0] not in ("Z", "X"):
                found[int(entry)] = st[0]
    return found


def assert_no_partial_files(out: Path) -> None:
    for path in out.rglob("*"):
        if path.is_dir():
            continue
        assert not path.name.startswith(TEMP_PREFIX), f"partial file left: {path}"
        assert not path.name.endswith(".tmp"), f"temporary file left: {path}"
        data = path.read_bytes()
        assert data, f"empty result file: {path}"
        if path.suffix == ".json":
            json.loads(data)
        elif path.suffix == ".png":
            assert data.endswith(b"IEND\xaeB`\x82"), f"truncated PNG: {path}"
        elif path.suffix == ".csv":
            assert data.endswith(b"\n"), f"truncated CSV: {path}"


@pytest.mark.parametrize(
    "command, how",
    [
        ("bench", "SIGINT"),
        ("stress", "SIGINT"),
        ("figures", "SIGINT"),
        ("stress", "Ctrl-C"),  # SIGINT to the whole process group, as a terminal sends it
        ("bench", "SIGTERM"),
    ],
)
def test_interrupt_stops_the_command_and_its_workers(tmp_path, command, how):
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "simgrip.cli", *COMMANDS[command], "--jobs", "2", "--no-progress", "--out", str(out)]
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            cwd=tmp_path, start_new_session=True)
    try:
        started = time.monotonic()
        while True:  # wait for the workers (two processes besides the command), and RUN_BEFORE_S at least
            elapsed = time.monotonic() - started
            workers = len(session_processes(proc.pid)) - 1
            if proc.poll() is not None:
                pytest.fail(f"simgrip {command} ended before the signal: rc {proc.returncode}")
            if workers >= 2 and elapsed >= RUN_BEFORE_S:
                break
            if elapsed > START_WITHIN_S:
                pytest.fail(f"simgrip {command}: {workers} worker processes after {START_WITHIN_S} s")
            time.sleep(0.1)
        time.sleep(0.5)  # let the workers take up their tasks
        sent = time.monotonic()
        if how == "Ctrl-C":
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM if how == "SIGTERM" else signal.SIGINT)
        try:
            stdout, stderr = proc.communicate(timeout=EXIT_WITHIN_S)
        except subprocess.TimeoutExpired:
            pytest.fail(f"simgrip {command} still running {EXIT_WITHIN_S} s after {how}")
        while session_processes(proc.pid) and time.monotonic() - sent < EXIT_WITHIN_S:
            time.sleep(0.05)
        took = time.monotonic() - sent
        left = session_processes(proc.pid)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()  # reap it and close the pipes
        for pid in session_processes(proc.pid):  # only processes of the session this test started
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    assert proc.returncode == 130, stderr
    assert took < EXIT_WITHIN_S, f"{took:.1f} s"
    assert not left, f"processes left after {how}: {left}"
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines == [f"simgrip {command}: interrupted"], stderr
    assert_no_partial_files(out)


# --- inside one long solve: the model's compile (one long C call) and the settle ---------------------------

#: Seconds from the signal to the exit of ``simulate`` inside one long compile or settle: a hang guard only
#: (issue 22, item 8).  The promise is 2 s: the main thread takes a signal at its next bytecode, or, inside a C
#: call, the watchdog acts after simgrip.interrupt.GRACE_S = 1 s and its clean-up and os._exit take < 0.4 s;
#: a shared machine may stretch that many-fold, so it is not timed here.  That the watchdog acts on a main
#: thread stuck in a C call is tested without a clock in tests/test_progress.py (a mutex the test holds).
SOLVE_EXIT_WITHIN_S = 30.0

#: phase -> (simulate's options, the progress line that says the phase started, seconds to wait after it).
#: 8 fingers x 350 links: the Python spec takes < 0.5 s, then MuJoCo's compile (work ~ fingers x links^3,
#: ~7 s on the 2-core test machine) runs in one C call, so 1.5 s after the line the signal finds the
#: main thread inside spec.compile().  700 links, dynamics: the settle runs ~4 s, < 0.1 s a step.
PHASES = {
    "compile": (["--links", "350", "--fingers", "8"], "building the model (8 fingers x 350 links) ...", 1.5),
    "settle": (["--links", "700", "--method", "dynamics"], "settling ...", 1.0),
}
PROGRESS_LINE = re.compile(r"^simgrip simulate: (building the model|settling)\b")


@pytest.mark.parametrize("phase, how", [("compile", "Ctrl-C"), ("settle", "SIGTERM")])
def test_interrupt_inside_one_long_solve(tmp_path, phase, how):
    options, marker, wait_s = PHASES[phase]
    argv = [sys.executable, "-m", "simgrip.cli", "simulate", "I", "--kappa", "-6", *options, "--json"]
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            cwd=tmp_path, start_new_session=True)
    lines: list[str] = []
    started = threading.Event()

    def read_stderr():
        for line in proc.stderr:
            lines.append(line.rstrip("\n"))
            if line.rstrip("\n").endswith(marker):
                started.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    try:
        if not started.wait(START_WITHIN_S):
            pytest.fail(f"no {marker!r} on stderr within {START_WITHIN_S} s: {lines}")
        time.sleep(wait_s)
        done = marker.removesuffix(" ...") + ": done in"
        if proc.poll() is not None or any(done in line for line in lines):
            pytest.fail(f"the {phase} ended before the signal: {lines}")
        sent = time.monotonic()
        if how == "Ctrl-C":
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=SOLVE_EXIT_WITHIN_S)
        except subprocess.TimeoutExpired:
            pytest.fail(f"simulate still running {SOLVE_EXIT_WITHIN_S} s after {how} in the {phase}")
        took = time.monotonic() - sent
        stdout = proc.stdout.read()
        reader.join(timeout=5.0)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()
    assert proc.returncode == 130, lines
    assert took < SOLVE_EXIT_WITHIN_S, f"{took:.1f} s"
    assert stdout == "", stdout  # no partial JSON on stdout
    assert lines[-1] == "simgrip simulate: interrupted", lines
    assert all(PROGRESS_LINE.match(line) for line in lines[:-1]), lines  # progress lines only: no traceback
    assert not session_processes(proc.pid)


def test_run_main_ends_an_interrupt_as_one_line_and_130(capfd):
    """:func:`simgrip.interrupt.run_main`, the learning commands' entry: a KeyboardInterrupt, or what a signal
    became on its way up (an import cut short raises ImportError), is one line and 130; a signal during the
    run comes as KeyboardInterrupt; anything else is the command's own; a status that is not an int is 0."""
    from simgrip.interrupt import run_main

    def raises(exc):
        def main(argv):
            raise exc
        return main

    assert run_main(raises(KeyboardInterrupt()), "cmd") == 130
    assert capfd.readouterr().err == "cmd: interrupted\n"

    def signalled(argv):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5)  # the handler raises in this thread before the sleep ends
        return 0

    assert run_main(signalled, "cmd") == 130
    assert capfd.readouterr().err == "cmd: interrupted\n"

    def import_cut_short(argv):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except KeyboardInterrupt:
            raise ImportError("partially initialised module") from None

    assert run_main(import_cut_short, "cmd") == 130
    assert capfd.readouterr().err == "cmd: interrupted\n"
    with pytest.raises(ImportError):  # no signal: an ImportError is the command's own
        run_main(raises(ImportError("x")), "cmd")
    with pytest.raises(SystemExit):  # argparse's exit 2 stays argparse's
        run_main(raises(SystemExit(2)), "cmd")
    assert run_main(lambda argv: {"success_rate": 1.0}, "cmd") == 0
    assert run_main(lambda argv: 1, "cmd") == 1
    assert run_main(lambda argv: argv, "cmd", ["--x"]) == 0
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handlers restored
    assert capfd.readouterr().err == ""


#: The ``simgrip`` console script's shape (pip writes ``from simgrip.cli import main`` then ``sys.exit(main())``),
#: with a hook that sends the process SIGINT while ``simgrip.params`` (NumPy) is being imported: a Ctrl-C in the
#: command's first ~0.3 s, before :func:`simgrip.cli.main` takes the signals over.
EARLY_SCRIPT = """
import os, signal, sys

class InterruptOnImport:
    def find_spec(self, name, path=None, target=None):
        if name == "simgrip.params":
            os.kill(os.getpid(), signal.SIGINT)
        return None

sys.meta_path.insert(0, InterruptOnImport())
from simgrip.cli import main
sys.exit(main(["--help"]))
"""


@pytest.mark.parametrize("name", ["simgrip", "my_script.py"])
def test_a_ctrl_c_while_the_command_imports_is_one_line_too(tmp_path, name):
    """A Ctrl-C while ``simgrip`` was still importing printed a ``KeyboardInterrupt`` traceback (a known leftover
    of issue 18's audit): now the command's one line and 130.  A program of the user's that imports simgrip keeps
    Python's ``KeyboardInterrupt`` (the control case: the hook does interrupt the import)."""
    script = tmp_path / name
    script.write_text(EARLY_SCRIPT)
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    if name == "simgrip":
        assert (r.returncode, r.stderr, r.stdout) == (130, "simgrip: interrupted\n", "")
    else:
        # (Python ends an uncaught KeyboardInterrupt by SIGINT itself: status -2)
        assert r.returncode == -signal.SIGINT and r.stderr.rstrip().endswith("KeyboardInterrupt")


SPAWNING_SCRIPT = """
import multiprocessing as mp
import signal


def probe(q):
    import simgrip  # noqa: F401
    q.put(signal.getsignal(signal.SIGINT) is signal.default_int_handler)


if __name__ == "__main__":
    import simgrip  # noqa: F401
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=probe, args=(q,))
    p.start()
    print(signal.getsignal(signal.SIGINT) is signal.default_int_handler, q.get())
    p.join()
"""


def test_a_process_the_command_spawns_keeps_pythons_interrupt(tmp_path):
    """A process spawned by the command (a Dask worker) runs the command's script as ``__mp_main__``: it must keep
    Python's ``KeyboardInterrupt`` (its own shutdown), not the command's early one-line exit (found in review)."""
    script = tmp_path / "simgrip"
    script.write_text(SPAWNING_SCRIPT)
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["False", "True"]  # the command's own process: the early handler; the child: Python's
