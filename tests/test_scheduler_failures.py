"""Schedulers that are absent, wrong or empty (issue 16, section 3), and the local cluster's limits.

Every way ``--scheduler``/``--scheduler-file`` can fail ends ``simgrip sweep``
with one named line and exit status 2 within the connect timeout, with no
traceback at exit: a malformed address, an unknown scheme, a scheduler file
that is missing, not JSON, binary, without an address or a folder (all
refused before any work), nothing listening, an HTTP server, a listener that
accepts and never answers (at ``--connect-timeout 2`` and once at the default
10 s).  SIGTERM and SIGINT during the connect stop it within 2 s (exit 130).
A scheduler without workers fails after ``--worker-wait`` (exit 1).  The
local cluster never starts more processes than tasks or than
``MAX_WORKERS_PER_CORE`` per core, and an interrupt during its start is not
followed by distributed's exit handler closing it again (the atexit
``UnboundLocalError``).  Everything listens on 127.0.0.1, on ports picked by
binding port 0.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from helpers import alive

from simgrip.parallel.dask_cluster import MAX_WORKERS_PER_CORE, LocalDask, available_cores, worker_cap
from simgrip.parallel.remote import (
    DEFAULT_CONNECT_TIMEOUT_S,
    SchedulerError,
    WorkerWatch,
    check_address,
    check_seconds,
    read_scheduler_file,
)
from simgrip.parallel.runner import RunnerError, RunnerOptions, add_runner_arguments, runner_options

#: Seconds a ``simgrip sweep`` subprocess may spend starting (imports) and ending, beyond what it waits for: the
#: CLI starts in ~1-2 s; a shared 2-core machine under load needs several times that.  The failures it guards
#: against took >= 20 s (the 20 s ``Client.__del__`` wait) or hung for minutes.
STARTUP_S = 12.0
#: The issue's bound for SIGTERM/SIGINT at any point [s].
SIGNAL_S = 2.0
#: The connect timeout used by the fast tests [s].
FAST_TIMEOUT_S = 2.0


def sweep_cmd(out: Path, *args: str) -> list[str]:
    """``simgrip sweep`` of one Grip I point at 8 links (the work never starts in these tests)."""
    return [sys.executable, "-m", "simgrip.cli", "sweep", "I", "--kappa", "-7", "--links", "8", "--out", str(out),
            "--no-progress", *args]


def run_sweep_cli(out: Path, *args: str, limit: float = 120.0):
    """``(returncode, stderr, seconds)`` of a ``simgrip sweep`` subprocess."""
    t0 = time.monotonic()
    proc = subprocess.run(sweep_cmd(out, *args), capture_output=True, text=True, timeout=limit)
    return proc.returncode, proc.stderr, time.monotonic() - t0


def assert_one_named_line(err: str, *words: str, kind: str = "error") -> str:
    """stderr is exactly one line ``simgrip sweep: <kind>: ...`` holding ``words``, with no traceback; an
    error names the option first (``scheduler``, ``scheduler-file``, ``connect-timeout``)."""
    assert "Traceback" not in err and "Exception ignored" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"simgrip sweep: {kind}: "), err
    if kind == "error":
        assert lines[0].split(": ", 2)[2].startswith(("scheduler ", "scheduler-file ", "connect-timeout ")), err
    for w in words:
        assert w in lines[0], (w, err)
    return lines[0]


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on (bound to 0, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def silent_listener():
    """A socket on 127.0.0.1 that accepts connections (the kernel's backlog) and never sends a byte."""
    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(16)
        yield srv


@contextlib.contextmanager
def http_server(folder: Path):
    """``python -m http.server`` on 127.0.0.1 and a free port: a server that is not Dask."""
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1",
                             "--directory", str(folder)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert proc.poll() is None and time.monotonic() < deadline, "http.server did not start"
                time.sleep(0.05)
        yield port
    finally:
        proc.kill()
        proc.wait()


# checks without the network -------------------------------------------------------------------

@pytest.mark.parametrize("address, why", [
    ("garbage!!", "no port"),
    ("garbage!!:5", "not a host name"),
    ("tcp://127.0.0.1", "no port"),
    ("tcp://127.0.0.1:99999", "1 ... 65535"),
    ("tcp://:8786", "no host"),
    ("tcp://::1:8786", "brackets"),
    ("foo://1.2.3.4:5", "unknown address scheme 'foo'"),
    ("inproc://x", "only inside one Python process"),
    ("  ", "scheduler must be an address"),
])
def test_malformed_addresses_are_named(address, why):
    with pytest.raises(SchedulerError, match="scheduler") as exc:
        check_address(address)
    assert why in str(exc.value)
    assert isinstance(exc.value, ValueError) and isinstance(exc.value, RunnerError)


def test_good_addresses_pass_unchanged():
    for a in ("tcp://127.0.0.1:8786", "127.0.0.1:8786", "tls://sched.example.org:8786", "tcp://[::1]:8786",
              " tcp://localhost:1 "):
        assert check_address(a) == a.strip()


def test_scheduler_files_are_read_whole(tmp_path):
    good = tmp_path / "good.json"
    good.write_text('{"type": "Scheduler", "address": "tcp://127.0.0.1:8786"}')
    assert read_scheduler_file(good) == "tcp://127.0.0.1:8786"
    cases = {"missing.json": (None, "does not exist"), "text.json": (b"not json", "not JSON"),
             "binary.json": (b"\xff\xfe\x00", "not UTF-8"), "list.json": (b"[1, 2]", "holds no scheduler address"),
             "number.json": (b'{"address": 5}', "holds no scheduler address"),
             "bad.json": (b'{"address": "garbage!!"}', "no port")}
    for name, (data, words) in cases.items():
        if data is not None:
            (tmp_path / name).write_bytes(data)
        with pytest.raises(SchedulerError, match="scheduler-file") as exc:
            read_scheduler_file(tmp_path / name)
        assert words in str(exc.value), (name, exc.value)
    with pytest.raises(SchedulerError, match="not a regular file"):
        read_scheduler_file(tmp_path)


def test_timeouts_are_validated_and_only_with_a_scheduler():
    assert check_seconds(2, "connect-timeout", upper=3600) == 2.0
    for bad in (0, -1, float("nan"), float("inf"), 1e9, "5", True):
        with pytest.raises(ValueError, match="connect-timeout"):
            RunnerOptions(scheduler="tcp://127.0.0.1:8786", connect_timeout=bad)
    assert RunnerOptions(scheduler="tcp://127.0.0.1:8786", worker_wait=float("inf")).worker_wait == float("inf")
    for bad in (0, -3, float("nan")):
        with pytest.raises(ValueError, match="worker-wait"):
            RunnerOptions(scheduler="tcp://127.0.0.1:8786", worker_wait=bad)
    import argparse

    p = argparse.ArgumentParser()
    add_runner_arguments(p)
    o = runner_options(p.parse_args(["--scheduler", "tcp://127.0.0.1:8786", "--connect-timeout", "3",
                                     "--worker-wait", "inf"]))
    assert o.connect_timeout == 3.0 and o.worker_wait == float("inf")
    assert runner_options(p.parse_args(["--scheduler", "tcp://127.0.0.1:8786"])).connect_timeout == DEFAULT_CONNECT_TIMEOUT_S
    for opt in ("--connect-timeout", "--worker-wait"):
        with pytest.raises(ValueError, match=opt[2:] + " is used only with --scheduler"):
            runner_options(p.parse_args(["--jobs", "2", opt, "5"]))


@pytest.mark.parametrize("args, words", [
    (["--scheduler", "garbage!!"], ["scheduler", "no port"]),
    (["--scheduler", "foo://1.2.3.4:5"], ["scheduler", "unknown address scheme"]),
    (["--scheduler-file", "{missing}"], ["scheduler-file", "does not exist"]),
    (["--scheduler-file", "{text}"], ["scheduler-file", "not JSON"]),
    (["--scheduler-file", "{noaddress}"], ["scheduler-file", "holds no scheduler address"]),
    (["--scheduler-file", "{folder}"], ["scheduler-file", "not a regular file"]),
    (["--scheduler", "tcp://127.0.0.1:8786", "--connect-timeout", "0"], ["connect-timeout"]),
])
def test_cli_refuses_a_bad_scheduler_before_any_work(tmp_path, args, words):
    (tmp_path / "text.json").write_text("not json")
    (tmp_path / "noaddress.json").write_text('{"type": "Scheduler"}')
    names = {"missing": tmp_path / "missing.json", "text": tmp_path / "text.json",
             "noaddress": tmp_path / "noaddress.json", "folder": tmp_path}
    args = [a.format(**names) for a in args]
    if "--connect-timeout" not in args:
        args += ["--connect-timeout", "30"]
    out = tmp_path / "out"
    rc, err, seconds = run_sweep_cli(out, *args)
    assert rc == 2, err
    assert_one_named_line(err, *words)
    assert not out.exists()  # refused before any work: no output folder, no .partial
    assert seconds < STARTUP_S, seconds  # no connect was tried (it may take 30 s), nothing waited at exit


# the network ----------------------------------------------------------------------------------

@pytest.mark.parametrize("via", ["--scheduler", "--scheduler-file"])
def test_nothing_listening(tmp_path, via):
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    if via == "--scheduler":
        given, label = address, f"scheduler {address}"
    else:
        given = tmp_path / "sched.json"
        given.write_text(f'{{"type": "Scheduler", "address": "{address}"}}')
        label = f"scheduler-file '{given}' (address {address})"
    rc, err, seconds = run_sweep_cli(tmp_path / "o", via, str(given), "--connect-timeout", str(FAST_TIMEOUT_S))
    assert rc == 2, err
    assert_one_named_line(err, f"{label} cannot be reached", "nothing accepted a connection", "connection refused")
    assert FAST_TIMEOUT_S <= seconds < FAST_TIMEOUT_S + STARTUP_S, seconds  # refusals are retried to the deadline
    # nothing was saved, so nothing is left to resume: the same command (without --resume) is not refused later
    assert not (tmp_path / "o" / ".partial").exists()


def test_an_http_server_is_not_a_scheduler(tmp_path):
    with http_server(tmp_path) as port:
        rc, err, seconds = run_sweep_cli(tmp_path / "o", "--scheduler", f"tcp://127.0.0.1:{port}",
                                         "--connect-timeout", str(FAST_TIMEOUT_S))
    assert rc == 2, err
    assert_one_named_line(err, f"scheduler tcp://127.0.0.1:{port} is not a Dask scheduler")
    assert seconds < FAST_TIMEOUT_S + STARTUP_S, seconds  # was: a hang of minutes


def test_a_silent_listener_at_the_default_timeout(tmp_path):
    """Accepts and never answers: the one test at the real default (10 s)."""
    with silent_listener() as srv:
        port = srv.getsockname()[1]
        rc, err, seconds = run_sweep_cli(tmp_path / "o", "--scheduler", f"tcp://127.0.0.1:{port}")
    assert rc == 2, err
    assert_one_named_line(err, f"scheduler tcp://127.0.0.1:{port} is not a Dask scheduler",
                          f"no Dask answer within {DEFAULT_CONNECT_TIMEOUT_S:g} s")
    assert DEFAULT_CONNECT_TIMEOUT_S <= seconds < DEFAULT_CONNECT_TIMEOUT_S + STARTUP_S, seconds


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_the_connect_stops_within_2_s(tmp_path, sig):
    with silent_listener() as srv:
        port = srv.getsockname()[1]
        proc = subprocess.Popen(sweep_cmd(tmp_path / "o", "--scheduler", f"tcp://127.0.0.1:{port}",
                                          "--connect-timeout", "300"),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            srv.settimeout(60)
            conns = [srv.accept()[0] for _ in range(2)]  # the probe's TCP check, then Dask's connect: now waiting
            time.sleep(0.2)  # inside the handshake's wait
            t0 = time.monotonic()
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=30)
            seconds = time.monotonic() - t0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        for c in conns:
            c.close()
    assert proc.returncode == 130, err
    assert err.strip() == "simgrip sweep: interrupted", err  # one line, no traceback
    assert seconds < SIGNAL_S, seconds


def test_a_scheduler_without_workers(tmp_path):
    from simgrip.parallel.cli_cluster import dask_cli_cluster

    with dask_cli_cluster(0) as (address, scheduler_file, worker):
        assert worker is None
        rc, err, seconds = run_sweep_cli(tmp_path / "o", "--scheduler-file", scheduler_file, "--worker-wait", "2")
    assert rc == 1, err
    assert_one_named_line(err, "RunnerError", address, "has had no workers for 2 s", "--worker-wait", kind="failed")
    assert 2.0 <= seconds < 2.0 + STARTUP_S, seconds


class FakeClient:
    """Answers ``scheduler_info`` with the next worker count of ``counts`` (``None``: the question fails)."""

    def __init__(self, counts):
        self.counts = list(counts)

    def scheduler_info(self, n_workers=-1):
        n = self.counts.pop(0)
        if n is None:
            raise OSError("scheduler gone")
        return {"type": "Scheduler", "n_workers": n, "workers": {}}


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_worker_watch_counts_only_time_without_workers():
    clock = Clock()
    # no worker at the start, none later: fails once wait_s has passed, not before
    w = WorkerWatch(FakeClient([0] * 10), "tcp://x:1", 5.0, workers=0, clock=clock)
    for t in (1, 2, 3, 4, 4.9):
        clock.t = t
        w.check()
    clock.t = 5.0
    with pytest.raises(RunnerError, match="^tcp://x:1 has had no workers for 5 s: start workers"):
        w.check()
    # a worker that comes resets the wait; one that leaves starts it again
    clock = Clock()
    w = WorkerWatch(FakeClient([0, 1, 0, 0, 0]), "tcp://x:1", 3.0, workers=0, clock=clock)
    for t in (1, 2.5, 3.5, 4.5, 5.5):  # counts 0, 1 (reset), 0 (from 3.5), 0, 0
        clock.t = t
        w.check()
    clock.t = 6.5
    with pytest.raises(RunnerError):
        w.check()
    # a failed question is no answer, not "no workers"
    clock = Clock()
    w = WorkerWatch(FakeClient([None] * 10), "tcp://x:1", 1.0, workers=2, clock=clock)
    for t in range(1, 8):
        clock.t = t
        w.check()


# the local cluster ----------------------------------------------------------------------------

def test_worker_cap():
    cores = available_cores()
    assert worker_cap(1) == 1
    assert worker_cap(10**6) == MAX_WORKERS_PER_CORE * cores
    assert worker_cap(10**6, tasks=3) == min(3, MAX_WORKERS_PER_CORE * cores)
    assert worker_cap(4, tasks=0) == 1
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="jobs"):
            worker_cap(bad)
    assert RunnerOptions(jobs=10**5).local_workers == MAX_WORKERS_PER_CORE * cores


def test_local_cluster_starts_no_more_workers_than_tasks_or_cores():
    env = LocalDask(100000, tasks=3)
    try:
        assert env.workers == min(3, MAX_WORKERS_PER_CORE * available_cores())
        assert len(env.client.scheduler_info()["workers"]) == env.workers
        pids = env.spawned()
        assert len(pids) == env.workers  # one process per worker
        assert env.cluster.shutdown_on_close is False  # distributed's exit handler leaves it to stop()
    finally:
        env.stop(False)
    deadline = time.monotonic() + 10
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(p) for p in pids)


INTERRUPTED_START = """
import os, signal, sys, time
from distributed.deploy import spec
from simgrip.parallel.runner import RunnerOptions, run_tasks

where = sys.argv[1]
fired = []

if where == "slow-spawn":  # widen the window between multiprocessing's spawn and its write of the start-up data
    import multiprocessing.util as mp_util

    spawnv = mp_util.spawnv_passfds

    def slow_spawnv(*a, **k):
        pid = spawnv(*a, **k)
        time.sleep(0.3)
        return pid

    mp_util.spawnv_passfds = slow_spawnv
    where = "workers"


def fire():
    if not fired:  # once (the clean-up may call the patched function again)
        fired.append(time.time())
        print("fired", fired[0], flush=True)
        os.kill(os.getpid(), signal.SIGINT)


if where == "workers":  # while the cluster brings its workers up
    original = spec.SpecCluster._correct_state_internal

    async def patched(self):
        fire()
        return await original(self)

    spec.SpecCluster._correct_state_internal = patched
else:  # once the cluster is up, while its client connects
    from distributed import client as dclient

    original = dclient.Client.__init__

    def patched(self, *a, **k):
        fire()
        return original(self, *a, **k)

    dclient.Client.__init__ = patched

if __name__ == "__main__":
    try:
        run_tasks(abs, list(range(8)), options=RunnerOptions(jobs=2, progress=False))
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        sys.exit(130)
    sys.exit(3)
"""


@pytest.mark.parametrize("where", ["workers", "client", "slow-spawn"])
def test_ctrl_c_during_the_cluster_start_exits_at_once_and_quietly(tmp_path, where):
    """Was: distributed's exit handler closed the abandoned cluster again (up to 10 s at exit) while the start's
    own thread closed it; the one that finished first stopped the event loop under the other, whose wait ended
    in ``Exception ignored in atexit callback ... UnboundLocalError``.

    ``slow-spawn``: was, under load, a worker spawned while the process exited printed spawn's ``EOFError: Ran out
    of input`` traceback (the exit closed the pipe before its start-up data was written); 0.3 s between the
    spawn and the write made it fail 6 times in 12, now 0 in 12 (``LocalDask._kill_left``)."""
    script = tmp_path / "start.py"
    script.write_text(textwrap.dedent(INTERRUPTED_START))
    proc = subprocess.Popen([sys.executable, str(script), where], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=120)
        ended = time.time()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, (out, err)
    fired, at, word = out.split()
    assert (fired, word) == ("fired", "interrupted"), out
    assert ended - float(at) < SIGNAL_S, ended - float(at)  # signal to exit; was >= 10 s (close_clusters' wait)
    assert "Traceback" not in err and "Exception ignored" not in err, err


def slow_square(x):
    time.sleep(0.2)
    return x * x


def test_a_local_cluster_whose_workers_stay_dead_fails_named(monkeypatch):
    """A safety net (was: as_completed waited for ever): all workers killed and not restarted -> RunnerError."""
    import distributed.deploy.spec as spec

    from simgrip.parallel import runner
    from simgrip.parallel.dask_cluster import _kill

    monkeypatch.setattr(runner, "DEFAULT_WORKER_WAIT_S", 2.0)
    done = []

    def kill_all(i, res):  # after the first result: nannies told not to restart, their workers killed
        done.append(i)
        if len(done) == 1:
            for c in list(spec.SpecCluster._instances):
                for nanny in list(c.workers.values()):
                    nanny.close_gracefully()
                    _kill([nanny.process.process.pid])

    t0 = time.monotonic()
    with pytest.raises(RunnerError, match="^the local Dask cluster has had no workers for 2 s"):
        runner.run_tasks(slow_square, range(40), options=RunnerOptions(jobs=2, progress=False), batch_size=1,
                         on_result=kill_all)
    assert time.monotonic() - t0 < 60
