"""Fixtures shared by several test modules, and how many processes the suite uses."""

import os
from pathlib import Path

import pytest

from simgrip import STANDARD, Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from settle_cases import KAPPA


def pytest_xdist_auto_num_workers(config):
    """``-n auto`` (``pyproject.toml``'s ``addopts``, capped at 4 by ``--maxprocesses``): one worker a core this
    process may run on, and no more workers than the test files asked for by name (``pytest tests/test_x.py``);
    where that is one, the tests run in this process with no worker at all (0)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    files = {str(arg).split("::")[0] for arg in config.args}
    if files and all(Path(f).is_file() for f in files):
        cores = min(cores, len(files))
    return cores if cores > 1 else 0


@pytest.fixture(scope="session")
def surface_states():
    """Grips I-III at n = 16, 32 settled with the friction at MuJoCo's contact point (``contact="surface"``: the
    tip couple); computed once for the settle and dynamics tests."""
    out = {}
    for grip in ("I", "II", "III"):
        for n in (16, 32):
            out[grip, n] = settle(build_scene(grip, STANDARD, Uniform(KAPPA[grip]), n), contact="surface")
    return out


# ---------------------------------------------------------------------------
# offscreen rendering: whether the render tests must run is decided here, not by the code under test


def offscreen_libraries() -> list[str]:
    """The offscreen GL backends whose library this machine has (``egl``: libEGL, ``osmesa``: libOSMesa), found by
    ``ctypes`` as PyOpenGL looks for them, independently of :func:`simgrip.sim.gl.choose_backend`."""
    import ctypes.util

    return [b for b, lib in (("egl", "EGL"), ("osmesa", "OSMesa")) if ctypes.util.find_library(lib)]


def _window_system() -> bool:
    import os
    import platform

    return platform.system() != "Linux" or bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def pytest_report_header(config):
    """Say up front whether the render tests will run, and on what (issue 22, item 7)."""
    import os

    libs = offscreen_libraries()
    user = os.environ.get("MUJOCO_GL", "")
    where = f"MUJOCO_GL={user}" if user else ("a display" if _window_system() else
                                             ("libraries: " + ", ".join(libs) if libs else "no display, no libEGL or libOSMesa"))
    must = bool(user or libs or _window_system())
    return f"simgrip rendering: {where}; render tests {'must run (a backend failure fails them)' if must else 'skip'}"


@pytest.fixture(scope="session")
def render_backend(request):
    """The GL backend the render tests use (``choose_backend``'s choice, set in this process's environment so the
    subprocesses they start inherit it), recorded for the terminal summary.

    Skips only on a machine with no display, no ``MUJOCO_GL`` and neither libEGL nor libOSMesa: whether rendering
    can work is read from the machine here, so a ``choose_backend`` that wrongly gives up fails the render tests
    instead of skipping them."""
    import os

    from simgrip.sim.gl import RenderingUnavailable, choose_backend

    if not (os.environ.get("MUJOCO_GL") or offscreen_libraries() or _window_system()):
        request.config.stash[_BACKEND_KEY] = "none (no display, no libEGL or libOSMesa: render tests skipped)"
        pytest.skip("no display, MUJOCO_GL unset, and neither libEGL nor libOSMesa on this machine")
    try:
        backend = choose_backend()
    except RenderingUnavailable as exc:
        request.config.stash[_BACKEND_KEY] = f"FAILED ({exc})"
        pytest.fail(f"an offscreen GL library is installed ({', '.join(offscreen_libraries()) or 'MUJOCO_GL'}) "
                    f"but simgrip found no backend that renders: {exc}")
    request.config.stash[_BACKEND_KEY] = backend or "MuJoCo's default (a display)"
    return backend


_BACKEND_KEY = pytest.StashKey[str]()


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    backend = config.stash.get(_BACKEND_KEY, None)
    if backend is not None:
        terminalreporter.write_line(f"simgrip render tests ran on: {backend}")


def pytest_configure(config):
    """Ctrl-C reaches the processes the suite starts, as from a terminal.

    A shell that runs a job in the background without job control (``cmd &`` in a script, some CI runners)
    starts it with SIGINT ignored, and an ignored signal stays ignored across ``exec``: every process the
    tests start would then ignore the SIGINT they send it (Python installs its ``KeyboardInterrupt`` handler
    only where SIGINT is at its default).  Restore the default handler here, once, so the interrupt tests test
    simgrip and not how the suite was launched.
    """
    import signal

    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
