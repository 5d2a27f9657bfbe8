"""A blocking call run in a daemon helper thread while the calling thread waits, interruptibly and with a deadline.

distributed's blocking calls (starting a ``LocalCluster``, making a ``Client``)
wait inside C-level locks and event loops that may not return for a long
time, or at all (a server that accepts a connection and never answers).  Run
through :func:`call_in_helper`, the calling thread only waits in short
``join`` steps: a ``KeyboardInterrupt`` (Ctrl-C, or SIGTERM turned into one by
the command) is raised at once, and a deadline ends the wait with
:class:`HelperTimeout`.  The helper thread is then left to finish on its own:
it is a daemon thread (process exit never waits for it), and whatever it
produces after the caller gave up is handed to ``discard`` in that thread, so
that nothing it made (a cluster, a client) is left open.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from typing import Callable

__all__ = ["HelperTimeout", "call_in_helper"]

#: Seconds between the waiting thread's checks (signals are handled between them).
POLL_S = 0.05


_MISSING = object()


def _quietly(fn, value) -> None:
    with contextlib.suppress(BaseException):  # a clean-up nobody waits for must not print a traceback
        fn(value)


class HelperTimeout(TimeoutError):
    """The helper did not finish before the deadline (it is left running, as a daemon thread)."""


def call_in_helper(fn: Callable, *, name: str, timeout: float | None = None, block_sigint: bool = False,
                   discard: Callable | None = None, on_give_up: Callable | None = None, settle: float = 0.0):
    """Return ``fn()``, run in a daemon thread named ``name``; this thread waits in :data:`POLL_S` steps.

    Parameters
    ----------
    fn : callable
        The blocking call (no arguments).
    name : str
        The helper thread's name.
    timeout : float, optional
        Seconds to wait (``None``: no deadline).
    block_sigint : bool
        Block SIGINT in the helper thread; threads and processes it starts
        inherit the block (a terminal's Ctrl-C, sent to the whole process
        group, then reaches only this process's main thread).
    discard : callable, optional
        Called in the helper thread with ``fn``'s result if it arrives after
        the caller stopped waiting (deadline or interrupt); and in a new daemon
        thread if the result arrived in the instant the caller was interrupted.
    on_give_up : callable, optional
        Called (no arguments) in this thread when it stops waiting (e.g. kill
        the processes the helper started), then again after up to ``settle``
        seconds spent waiting for the helper to end.
    settle : float
        See ``on_give_up``.

    Raises
    ------
    HelperTimeout
        ``fn`` did not return within ``timeout``.
    BaseException
        Whatever ``fn`` raised (in this thread), or the ``KeyboardInterrupt``
        that interrupted the wait.
    """
    lock = threading.Lock()
    box: dict = {}

    def target():
        if block_sigint and hasattr(signal, "pthread_sigmask"):
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            value = fn()
        except BaseException as exc:  # handed to the waiting thread (dropped if it has gone)
            with lock:
                if not box.get("gone"):
                    box["error"] = exc
            return
        with lock:
            if not box.get("gone"):
                box["value"] = value
                return
        if discard is not None:
            _quietly(discard, value)

    helper = threading.Thread(target=target, name=name, daemon=True)
    deadline = None if timeout is None else time.monotonic() + timeout
    helper.start()
    try:
        while helper.is_alive():
            if deadline is not None and time.monotonic() >= deadline:
                raise HelperTimeout(f"{name} did not finish within {timeout:g} s")
            helper.join(POLL_S)
    except BaseException:
        with lock:
            box["gone"] = True
            late = box.pop("value", _MISSING)
        if late is not _MISSING and discard is not None:
            threading.Thread(target=_quietly, args=(discard, late), name=f"{name}-discard", daemon=True).start()
        if on_give_up is not None:
            on_give_up()
            end = time.monotonic() + settle
            while helper.is_alive() and time.monotonic() < end:
                helper.join(POLL_S)
            on_give_up()
        raise
    if "error" in box:
        raise box.pop("error")
    return box.pop("value")
