"""SIGINT and SIGTERM that stop a command within a bounded time, even inside one long C call.

Python runs a signal handler only in the main thread, between two bytecodes.
A long C call in the main thread therefore defers it until the call returns:
``simgrip simulate I --kappa -6 --links 1000 --fingers 8`` spends minutes in
MuJoCo's ``spec.compile()`` (``mj_setConst`` solves the mass matrix once per
body, O(links^3) per finger for a chain), and a Ctrl-C waited for all of it.
MuJoCo's bindings release the GIL in those calls (``spec.compile``,
``mj_forward``, ``mj_step``), so another Python thread can still run.

:func:`signals_as_interrupt` therefore does two things:

* SIGINT and SIGTERM raise ``KeyboardInterrupt`` in the main thread (as
  before), and each handler run marks the signal *handled*;
* the C-level handler also writes the signal to a socket
  (:func:`signal.set_wakeup_fd`) that a watchdog thread reads at once.  If
  the main thread has not run the handler within ``grace_s`` of a signal, it
  is stuck in a C call, and the watchdog calls ``on_stuck(signum)`` (the
  command line cleans up, prints its one line and ends the process with
  :func:`os._exit`: see :func:`simgrip.cli.main`).

:class:`Finish` lets exactly one of the two (the main thread's
``except KeyboardInterrupt`` or the watchdog) do the clean-up and print.

A handler installed inside the block replaces ours for its signal: it
should call ours first (as :func:`simgrip.parallel.runner` does for
SIGTERM) so that the signal counts as handled; the watchdog leaves a signal
whose handler is not ours alone.

Limitation: a C call that *holds* the GIL blocks the watchdog thread too;
then the signal waits for the call (none of simgrip's long calls does).
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import sys
import threading
from pathlib import Path
from typing import Callable

__all__ = ["GRACE_S", "Finish", "kill_descendants", "run_main", "signals_as_interrupt"]

#: Seconds the main thread gets to run the handler of a signal before the watchdog acts.  Python
#: runs pending handlers at its next bytecode (microseconds when the main thread runs Python, some
#: ms of GIL hand-over and scheduling on a loaded machine), so 1 s means "inside a C call"; the
#: hard exit then takes ~0.3 s (freeing a model of 8000 bodies), within 2 s of the signal with
#: room for a loaded machine (measured 1.65-1.83 s with a 1.5 s grace at load 7 on 2 cores).
GRACE_S = 1.0

_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Received:
    """What :func:`signals_as_interrupt` yields: ``signum`` is the first signal whose handler ran (else None).

    A ``KeyboardInterrupt`` raised inside an import or a library that turns it into another exception (an
    ``ImportError`` of a module cut short) is still an interrupt: the caller asks ``received``.
    """

    def __init__(self):
        self.signum: int | None = None


class Finish:
    """Who ends an interrupted run: the first caller of :meth:`claim` gets True, every later one False."""

    def __init__(self):
        self._lock = threading.Lock()

    def claim(self) -> bool:
        """True for the first caller only (thread-safe, never blocks)."""
        return self._lock.acquire(blocking=False)


class _Watchdog:
    """Reads the wakeup socket; calls ``on_stuck`` when a signal's handler has not run within ``grace_s``."""

    def __init__(self, on_stuck: Callable[[int], None], grace_s: float):
        self.on_stuck = on_stuck
        self.grace_s = float(grace_s)
        self.handler = None  # the Python handler of SIGINT and SIGTERM that sets handled
        self.handled = threading.Event()
        self.closed = threading.Event()
        self.read_end, self.write_end = socket.socketpair()
        self.write_end.setblocking(False)  # set_wakeup_fd needs a non-blocking fd
        self.thread = threading.Thread(target=self._run, name="simgrip-interrupt-watchdog", daemon=True)

    def _drain(self) -> None:
        self.read_end.setblocking(False)
        with contextlib.suppress(OSError):
            while self.read_end.recv(256):
                pass
        self.read_end.setblocking(True)

    def _run(self) -> None:
        while not self.closed.is_set():
            self.handled.clear()
            try:
                data = self.read_end.recv(256)  # blocks (without the GIL) until a signal arrives
            except OSError:
                return
            if not data or self.closed.is_set():
                return
            # The C handler writes the byte before the Python handler runs, so a handler run after the
            # clear() above answers this signal; several signals before one run coalesce into that run.
            if self.handled.wait(self.grace_s):
                self._drain()
                continue
            if self.closed.is_set():
                return
            if signal.getsignal(data[-1]) is not self.handler:
                continue  # a handler installed later that does not chain to ours is in charge of this signal
            self.on_stuck(data[-1])
            return

    def close(self) -> None:
        self.closed.set()
        with contextlib.suppress(OSError):
            self.write_end.send(b"\0")  # wakes the thread, which sees closed
        self.thread.join(timeout=1.0)
        self.read_end.close()
        self.write_end.close()


@contextlib.contextmanager
def signals_as_interrupt(on_stuck: Callable[[int], None] | None = None, grace_s: float = GRACE_S):
    """Within the block, SIGINT and SIGTERM raise ``KeyboardInterrupt`` in the main thread.

    SIGINT gets a raising handler even when the process started with SIGINT
    ignored (as commands started in the background by a non-interactive shell
    are, e.g. under ``timeout -s INT``): an interrupt must always stop the run.

    With ``on_stuck``, a watchdog thread calls ``on_stuck(signum)`` when the
    main thread has not run a signal's handler within ``grace_s`` seconds (it
    is inside a long C call); ``on_stuck`` should end the process
    (:func:`os._exit`).  Outside the main thread the block runs unchanged
    (signal handlers can only be set there).  Handlers and the wakeup fd are
    restored on exit.  Yields a :class:`Received` that records the signal.
    """
    received = Received()
    if threading.current_thread() is not threading.main_thread():
        yield received
        return
    dog = _Watchdog(on_stuck, grace_s) if on_stuck is not None else None

    def _raise(signum, frame):
        received.signum = signum
        if dog is not None:
            dog.handled.set()
        raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, _raise) for sig in _SIGNALS}
    if dog is not None:
        dog.handler = _raise
    previous_fd = None
    try:
        if dog is not None:
            previous_fd = signal.set_wakeup_fd(dog.write_end.fileno(), warn_on_full_buffer=False)
            dog.thread.start()
        yield received
    finally:
        if dog is not None:
            signal.set_wakeup_fd(previous_fd if previous_fd is not None else -1)
            dog.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def kill_descendants() -> list[int]:
    """SIGKILL every descendant process of this one (found through ``/proc``; Linux), deepest first.

    For a hard exit that cannot wait for a worker pool's own shutdown.  Returns
    the process ids signalled; nothing where ``/proc`` is unavailable.
    """
    children: dict[int, list[int]] = {}
    proc = Path("/proc")
    if not proc.is_dir():
        return []
    for entry in proc.iterdir():
        if not entry.name.isdigit():
            continue
        try:
            text = (entry / "stat").read_text()
            ppid = int(text[text.rindex(")") + 2:].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        children.setdefault(ppid, []).append(int(entry.name))
    order, todo = [], [os.getpid()]
    while todo:
        for child in children.get(todo.pop(), []):
            order.append(child)
            todo.append(child)
    for pid in reversed(order):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    return order


def run_main(main: Callable, prefix: str, argv=None) -> int:
    """Run a command line's ``main(argv)`` with SIGINT and SIGTERM as ``KeyboardInterrupt``; returns its status.

    An interrupt, whatever it became on its way up (an import cut short raises ``ImportError``), ends as the
    one line ``{prefix}: interrupted`` on stderr and status 130, without a traceback; a second signal during
    that is ignored.  Output piped into a reader that stopped (``| head``) ends quietly with status 0 (stdout
    pointed at ``/dev/null``, so that the interpreter's last flush stays quiet).  Any other exception
    propagates.  A status that is not an int (a ``main`` that returns its results) counts as 0.  For commands
    whose children stop with them (none, or their own clean-up in ``main``); the ``simgrip`` command has its
    own, with a watchdog (:func:`simgrip.cli.main`).
    """
    with signals_as_interrupt() as received:
        try:
            code = main(argv)
        except BrokenPipeError:
            with contextlib.suppress(OSError, ValueError):
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
        except BaseException as exc:
            if not isinstance(exc, KeyboardInterrupt) and (received.signum is None or isinstance(exc, SystemExit)):
                raise
            for sig in _SIGNALS:
                signal.signal(sig, signal.SIG_IGN)
            with contextlib.suppress(OSError, ValueError):
                os.write(2, f"{prefix}: interrupted\n".encode())
            return 130
    return code if isinstance(code, int) and not isinstance(code, bool) else 0
