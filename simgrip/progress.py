"""Progress lines on stderr for the phases of one long job (model build, settle).

Library functions that build and settle a model (:func:`simgrip.compare.simulate`,
:func:`simgrip.gripper.simulate_gripper`) take ``progress``: None (silent, the
default), or a callable that takes a phase's description and returns a context
manager entered for the phase's duration.  :class:`StderrProgress` is the
command line's: a line when a phase starts, lines while it lasts (after
``every_s`` seconds, then at gaps that double up to :data:`MOST_EVERY_S`: 5, 10, 20,
40, 70, 100 s, ...; from a thread, so it also ticks while the main thread is inside one
long C call such as MuJoCo's compile, which releases the GIL), and one when it
ends with its duration.  Nothing goes to stdout.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time

__all__ = ["EVERY_S", "MOST_EVERY_S", "StderrProgress", "phase"]

#: Seconds to the first "still running" line of a phase (the gap then doubles).
EVERY_S = 5.0
#: Largest gap between two "still running" lines [s] (a compile of minutes prints a line a half-minute).
MOST_EVERY_S = 30.0


def phase(progress, what: str):
    """The context manager of phase ``what`` from ``progress`` (a no-op one when ``progress`` is None)."""
    return contextlib.nullcontext() if progress is None else progress(what)


class StderrProgress:
    """Phase lines ``<prefix>: <what> ...``, ``<prefix>: <what>: 5 s ...``, ``<prefix>: <what>: done in 7.3 s``
    (see the module docstring for when).

    ``stream`` defaults to ``sys.stderr`` (read when a line is written).  A
    phase left by an exception (e.g. ``KeyboardInterrupt``) prints no end line.
    """

    def __init__(self, prefix: str, every_s: float = EVERY_S, stream=None):
        self.prefix = prefix
        self.every_s = float(every_s)
        self.stream = stream

    def _say(self, text: str) -> None:
        stream = self.stream if self.stream is not None else sys.stderr
        with contextlib.suppress(OSError, ValueError):
            stream.write(f"{self.prefix}: {text}\n")
            stream.flush()

    @contextlib.contextmanager
    def __call__(self, what: str):
        t0 = time.monotonic()
        done = threading.Event()

        def tick():
            gap = self.every_s
            while not done.wait(gap):
                elapsed = time.monotonic() - t0
                self._say(f"{what}: {elapsed:.0f} s ...")
                gap = min(max(self.every_s, elapsed), max(self.every_s, MOST_EVERY_S))

        self._say(f"{what} ...")
        ticker = threading.Thread(target=tick, name="simgrip-progress", daemon=True)
        ticker.start()
        try:
            yield
        finally:
            done.set()
            ticker.join(timeout=1.0)
        self._say(f"{what}: done in {time.monotonic() - t0:.1f} s")
