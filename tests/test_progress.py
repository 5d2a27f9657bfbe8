"""Time and progress of one long job, and the interrupt watchdog's own logic (in process, fast).

* ``build_time_s`` (the model's build and compile) beside ``wall_time_s`` (the
  settle) in the records of ``simulate``, planar and K-finger;
* :class:`simgrip.progress.StderrProgress`: a line when a phase starts, one
  while it lasts, one when it ends; nothing for small models (the command line
  announces only models above :data:`simgrip.cli.SLOW_LINKS`);
* :func:`simgrip.interrupt.signals_as_interrupt`: a signal raises
  ``KeyboardInterrupt``; the watchdog calls ``on_stuck`` only when the main
  thread sits in a C call (a ``pthread_mutex_lock`` the test holds, which a
  signal does not interrupt) and not when the handler runs.
"""

from __future__ import annotations

import argparse
import ctypes
import io
import json
import os
import signal
import sys
import threading
import time

import pytest

from simgrip.cli import SLOW_LINKS, _progress, main
from simgrip.interrupt import Finish, signals_as_interrupt
from simgrip.progress import StderrProgress, phase

#: Bound for waits on another thread in these tests (never reached unless a test fails).
WAIT_S = 10.0


@pytest.mark.parametrize("options", [[], ["--fingers", "3"]])
def test_simulate_reports_build_time_beside_wall_time(capsys, options):
    assert main(["simulate", "I", "--kappa", "-6", "--links", "12", "--json", *options]) == 0
    captured = capsys.readouterr()
    rec = json.loads(captured.out)
    assert rec["build_time_s"] > 0.0 and rec["wall_time_s"] > 0.0
    assert captured.err == ""  # a small model: no progress lines


def test_only_large_models_get_progress_lines():
    def args(fingers=None):
        return argparse.Namespace(command="simulate", fingers=fingers)

    assert _progress(args(), SLOW_LINKS) is None
    assert isinstance(_progress(args(), SLOW_LINKS + 1), StderrProgress)
    assert _progress(args(8), SLOW_LINKS // 2) is None  # 8 fingers x 256^3 = 512^3: not above
    assert isinstance(_progress(args(8), SLOW_LINKS // 2 + 1), StderrProgress)


def test_progress_lines_start_tick_and_end():
    out = io.StringIO()
    progress = StderrProgress("simgrip simulate", every_s=0.01, stream=out)
    with progress("settling"):
        deadline = time.monotonic() + WAIT_S
        while "settling: " not in out.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
    lines = out.getvalue().splitlines()
    assert lines[0] == "simgrip simulate: settling ..."
    assert lines[1].startswith("simgrip simulate: settling: ") and lines[1].endswith(" s ...")
    assert lines[-1].startswith("simgrip simulate: settling: done in ") and lines[-1].endswith(" s")


def test_a_phase_left_by_an_exception_prints_no_end_line():
    out = io.StringIO()
    with pytest.raises(KeyboardInterrupt), StderrProgress("simgrip simulate", stream=out)("settling"):
        raise KeyboardInterrupt
    assert out.getvalue().splitlines() == ["simgrip simulate: settling ..."]
    with phase(None, "settling"):  # no progress: silent
        pass


def test_finish_is_claimed_once():
    finish = Finish()
    assert finish.claim() and not finish.claim()


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(), reason="signals need the main thread")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_handled_signal_raises_and_the_watchdog_stays_quiet(signum):
    stuck = []
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with pytest.raises(KeyboardInterrupt), signals_as_interrupt(stuck.append, grace_s=0.05):
        os.kill(os.getpid(), signum)
        time.sleep(WAIT_S)  # the handler interrupts this sleep
    time.sleep(0.2)  # 4 x grace_s: a watchdog that missed the handler would have fired
    assert stuck == []
    assert {s: signal.getsignal(s) for s in before} == before
    assert signal.set_wakeup_fd(-1) == -1  # restored (none was set)


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(), reason="signals need the main thread")
def test_the_watchdog_leaves_a_main_thread_that_runs_another_handler():
    """A handler installed later that does not chain to ours (the main thread still runs Python): no hard exit."""
    stuck = []

    def other(signum, frame):
        raise KeyboardInterrupt

    with signals_as_interrupt(stuck.append, grace_s=0.05):
        signal.signal(signal.SIGTERM, other)  # until the block ends (which restores the handlers)
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(WAIT_S)  # the handler interrupts this sleep
        except KeyboardInterrupt:
            time.sleep(0.2)  # 4 x grace_s: a watchdog that took the main thread for stuck would have fired
    assert stuck == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's pthread_mutex_t (Linux)")
@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(), reason="signals need the main thread")
def test_the_watchdog_acts_when_the_main_thread_sits_in_a_c_call():
    libc = ctypes.CDLL(None)  # a CDLL call releases the GIL, as MuJoCo's compile does
    mutex = ctypes.create_string_buffer(64)  # zeros: PTHREAD_MUTEX_INITIALIZER (40 bytes on x86-64 glibc)
    main_ident = threading.main_thread().ident
    locked, stuck = threading.Event(), threading.Event()
    calls, where = [], []  # where: the line of the main thread's blocking call

    def on_stuck(signum):
        calls.append(signum)
        stuck.set()

    def holder():  # holds the mutex, signals once the main thread waits for it, lets go after the watchdog
        libc.pthread_mutex_lock(mutex)
        locked.set()
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:  # the main thread on the line of its pthread_mutex_lock call
            frame = sys._current_frames().get(main_ident)
            if where and frame is not None and frame.f_lineno == where[0]:
                break
            time.sleep(0.005)
        time.sleep(0.2)  # into the C call (a futex wait, which the kernel resumes after a signal)
        os.kill(os.getpid(), signal.SIGTERM)
        stuck.wait(WAIT_S)
        libc.pthread_mutex_unlock(mutex)

    thread = threading.Thread(target=holder, daemon=True)
    interrupted_after_stuck = None
    with signals_as_interrupt(on_stuck, grace_s=0.1):
        try:
            thread.start()
            locked.wait(WAIT_S)
            where.append(sys._getframe().f_lineno + 1)
            libc.pthread_mutex_lock(mutex)  # blocks here until the holder lets go
            libc.pthread_mutex_unlock(mutex)
            time.sleep(WAIT_S)  # the pending handler runs before this sleep is done
        except KeyboardInterrupt:
            interrupted_after_stuck = stuck.is_set()
    thread.join(WAIT_S)
    assert calls == [signal.SIGTERM]
    assert interrupted_after_stuck is True  # the handler ran once the C call returned, after the watchdog


@pytest.mark.parametrize("becomes", [ImportError, RuntimeError, ValueError])
def test_an_interrupt_that_becomes_another_exception_is_still_an_interrupt(monkeypatch, capsys, becomes):
    """SIGTERM during ``import mujoco`` surfaced as an ImportError traceback, exit 1 (2 in 10 runs): an exception
    raised after a signal was received is the interrupt's, whatever its type (exit 130, the one line)."""
    import os
    import signal
    import time

    from simgrip import cli

    def command(args):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # the handler raises KeyboardInterrupt here
        except KeyboardInterrupt:
            raise becomes("partially initialized module 'mujoco' (most likely due to a circular import)") from None
        raise AssertionError("the signal was not delivered")

    monkeypatch.setitem(cli.COMMANDS, "solve", command)
    assert cli.main(["solve", "I", "--kappa", "-5"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["simgrip solve: interrupted"]
    # without a signal the same exceptions keep their meaning
    monkeypatch.setitem(cli.COMMANDS, "solve", lambda args: (_ for _ in ()).throw(ValueError("kappa: bad")))
    assert cli.main(["solve", "I", "--kappa", "-5"]) == 2
