"""What guards one stress case (:mod:`simgrip.harness.stress`, :mod:`simgrip.harness.stress_gripper`).

:func:`deadline` stops a case that runs past its wall-clock budget (raising
:class:`CaseTimeout` in the case's own thread); :func:`names_an_input` says
whether an error message names one of :data:`INPUT_NAMES` (a rejection, not
a failure).  Both kinds of case use them, so they sit here, below both.
"""

from __future__ import annotations

import contextlib
import ctypes
import re
import threading

__all__ = ["INPUT_NAMES", "CaseTimeout", "deadline", "names_an_input"]

#: Input names a rejection must mention to count as "rejected" (else it is a failure).
INPUT_NAMES = ("grip", "D", "M", "b", "mu_s", "gamma", "kappa", "profile", "links", "n_links", "initial_angles",
               "alpha", "params", "fingers", "r_tip", "r_link", "r_corner", "tol", "max_steps")


def names_an_input(message: str) -> bool:
    """Whether an error message names one of :data:`INPUT_NAMES` as a word."""
    return any(re.search(rf"(?<![A-Za-z_]){re.escape(k)}(?![A-Za-z_])", message) for k in INPUT_NAMES)


class CaseTimeout(Exception):
    """A case ran past its deadline (:func:`deadline`)."""


@contextlib.contextmanager
def deadline(seconds: float):
    """Raise :class:`CaseTimeout` in the calling thread if the block runs longer than ``seconds``.

    A timer thread injects the exception (``PyThreadState_SetAsyncExc``), so the
    guard works in any thread (a Dask worker runs tasks outside its main
    thread, where ``SIGALRM`` cannot be used).  It is raised at the next Python
    instruction: a single C call that never returns is not interrupted.
    """
    tid = threading.get_ident()
    lock = threading.Lock()
    state = {"active": True, "fired": False}

    def fire():
        with lock:
            if state["active"]:
                state["fired"] = True
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), ctypes.py_object(CaseTimeout))

    timer = threading.Timer(seconds, fire)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        with lock:
            state["active"] = False
            timer.cancel()
            if state["fired"]:  # fired but perhaps not raised yet: withdraw it
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid), None)
