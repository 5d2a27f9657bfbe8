"""Choose an OpenGL backend for offscreen rendering, so that pictures work on a machine without a display.

MuJoCo picks its GL backend once, when ``mujoco`` is imported, from the
environment variable ``MUJOCO_GL`` (``glfw`` when unset, which needs a
display; ``egl`` and ``osmesa`` render offscreen).  PyOpenGL likewise fixes its
platform (``PYOPENGL_PLATFORM``) when ``OpenGL`` is first imported, so a
backend that fails cannot be swapped for another in the same process.

:func:`choose_backend` therefore decides before the first GL context:

* ``MUJOCO_GL`` set by the user: that backend, untouched, once its library is
  found (``egl``: libEGL, ``osmesa``: libOSMesa; else :class:`RenderingUnavailable`
  names ``MUJOCO_GL`` and the missing library, where MuJoCo's own import would
  fail deep inside PyOpenGL with an ``AttributeError``);
* a display (``DISPLAY`` or ``WAYLAND_DISPLAY``) or not Linux: MuJoCo's default;
* otherwise (headless Linux): the first of ``egl`` and ``osmesa`` that can
  make a context, each tried in a fresh interpreter.  The choice is written to
  ``MUJOCO_GL`` and ``PYOPENGL_PLATFORM`` (so worker processes inherit it and
  nothing is probed twice).  When none works, :class:`RenderingUnavailable`
  says what was tried and why each failed.

:func:`make_renderer` builds a :class:`mujoco.Renderer` on the chosen backend.
It refuses GLFW without a display before touching it, and a backend that has
already failed in this process is refused with its first error without being
tried again: GLFW's second attempt after a failed one aborts the interpreter
inside MuJoCo's C++ (``libc++abi``), which no ``except`` can catch.

:func:`import_mujoco` imports ``mujoco`` for the commands that do not render:
a ``MUJOCO_GL`` whose library is missing makes MuJoCo's import itself fail, so
it retries once without it (rendering is not needed) and says so.
If ``mujoco`` was imported before the choice (its GL context class then is
GLFW's, which cannot work without a display), the context class MuJoCo's
renderer uses is pointed at the chosen backend's.
"""

from __future__ import annotations

import ctypes.util
import importlib
import os
import platform
import subprocess
import sys

__all__ = ["HEADLESS_BACKENDS", "RenderingUnavailable", "choose_backend", "has_display", "import_mujoco",
           "make_renderer", "probe"]

#: Offscreen backends tried in order on a headless Linux machine.
HEADLESS_BACKENDS = ("egl", "osmesa")
#: The values of ``MUJOCO_GL`` MuJoCo accepts (any other makes ``import mujoco`` raise).
MUJOCO_BACKENDS = ("glfw", "egl", "osmesa")
_LIBRARIES = {"egl": "EGL", "osmesa": "OSMesa"}

_PROBE = """
import mujoco
from mujoco.rendering.classic.gl_context import GLContext
ctx = GLContext(16, 16)
ctx.make_current()
ctx.free()
"""


class RenderingUnavailable(RuntimeError):
    """No OpenGL backend can render offscreen on this machine."""


#: Backends whose renderer failed in this process, with the error: a process-wide fact (the GL library's own
#: state is process-wide), so it is kept per process, not per call.  Never retried: see the module's docstring.
_FAILED: dict[str, str] = {}


def missing_library(backend: str) -> str | None:
    """``"libEGL"`` / ``"libOSMesa"`` when ``backend``'s library cannot be found by ``ctypes`` (as PyOpenGL looks), else None."""
    library = _LIBRARIES.get(backend)
    if library and ctypes.util.find_library(library) is None:
        return f"lib{library}"
    return None


def has_display(environ=None) -> bool:
    """Whether a window system is reachable (``DISPLAY`` or ``WAYLAND_DISPLAY``), or the OS is not Linux.

    ``environ``: the environment to read (default ``os.environ``).
    """
    if platform.system() != "Linux":
        return True
    env = os.environ if environ is None else environ
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def probe(backend: str, timeout: float = 60.0) -> str | None:
    """Make a 16x16 GL context with ``backend`` in a fresh interpreter: None if it works, else why not."""
    env = dict(os.environ, MUJOCO_GL=backend, PYOPENGL_PLATFORM=backend)
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"no context within {timeout:g} s"
    if proc.returncode == 0:
        return None
    missing = missing_library(backend)
    if missing:
        return f"{missing} not found"
    lines = [ln.strip() for ln in proc.stderr.splitlines() if ln.strip()]
    return lines[-1] if lines else f"exit status {proc.returncode}"


def choose_backend(environ=None) -> str | None:
    """The GL backend rendering will use (``"egl"``, ``"osmesa"``, the user's ``MUJOCO_GL``), or None for MuJoCo's default.

    On headless Linux without ``MUJOCO_GL`` the backends of
    :data:`HEADLESS_BACKENDS` are probed in order and the first that works is
    set in ``MUJOCO_GL`` / ``PYOPENGL_PLATFORM`` of ``environ`` (default
    ``os.environ``, so that worker processes inherit the choice);
    :class:`RenderingUnavailable` when none does.
    """
    env = os.environ if environ is None else environ
    user = env.get("MUJOCO_GL", "").strip().lower()
    if user:
        if user not in MUJOCO_BACKENDS:
            raise RenderingUnavailable(f"MUJOCO_GL={user} is not a backend MuJoCo knows ({', '.join(MUJOCO_BACKENDS)}); "
                                       f"set one of them or unset MUJOCO_GL")
        missing = missing_library(user)
        if missing:
            raise RenderingUnavailable(
                f"MUJOCO_GL={user}: {missing} not found on this machine; install it, set MUJOCO_GL to a backend "
                f"that works, or unset MUJOCO_GL (then simgrip tries {', '.join(HEADLESS_BACKENDS)} itself)")
        return user
    if has_display(env):
        return None
    platform_ = env.get("PYOPENGL_PLATFORM", "").strip().lower()
    candidates = [platform_] if platform_ in HEADLESS_BACKENDS else list(HEADLESS_BACKENDS)
    failures = []
    for backend in candidates:
        why = probe(backend)
        if why is None:
            env["MUJOCO_GL"] = backend
            env["PYOPENGL_PLATFORM"] = backend
            return backend
        failures.append(f"{backend}: {why}")
    raise RenderingUnavailable(
        "no OpenGL backend can render offscreen on this machine (no display; tried "
        + "; ".join(failures)
        + "). Install EGL (e.g. libegl1) or OSMesa (e.g. libosmesa6), or set MUJOCO_GL to a backend that works."
    )


def make_renderer(model, height: int, width: int):
    """A :class:`mujoco.Renderer` of ``model`` (``height`` x ``width`` pixels) on :func:`choose_backend`'s backend."""
    backend = choose_backend()
    name = backend or "glfw"
    if name in _FAILED:
        raise RenderingUnavailable(_FAILED[name])
    if name == "glfw" and not has_display():
        _FAILED[name] = ("cannot render with MUJOCO_GL=glfw: no display (DISPLAY and WAYLAND_DISPLAY are unset); "
                         "unset MUJOCO_GL to render offscreen with EGL or OSMesa")
        raise RenderingUnavailable(_FAILED[name])
    try:
        import mujoco
        from mujoco.rendering.classic import gl_context
    except Exception as exc:  # MuJoCo's import fails inside PyOpenGL when the backend's library cannot load
        _FAILED[name] = f"cannot render with MUJOCO_GL={name}: mujoco cannot load this backend ({exc})"
        raise RenderingUnavailable(_FAILED[name]) from exc

    if backend in HEADLESS_BACKENDS:
        wanted = importlib.import_module(f"mujoco.{backend}").GLContext
        if getattr(gl_context, "GLContext", None) is not wanted:
            # mujoco was imported before MUJOCO_GL was chosen: its renderer would use GLFW (no display)
            gl_context.GLContext = wanted
    # the offscreen framebuffer the size asked for (the models' own: 640 x 480 or 1280 x 960; an env's width of
    # 800 failed at the first render with MuJoCo's "Image width 800 > framebuffer width 640"): rendering only
    glob = model.vis.global_
    glob.offwidth, glob.offheight = max(int(glob.offwidth), int(width)), max(int(glob.offheight), int(height))
    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:
        if isinstance(exc, ValueError) and "framebuffer" in str(exc):
            raise  # a size the model's offscreen buffer cannot hold: MuJoCo's own message says which
        _FAILED[name] = f"cannot render with MUJOCO_GL={name}: {exc}"
        raise RenderingUnavailable(_FAILED[name]) from exc


def import_mujoco(environ=None, warn=None):
    """Import and return ``mujoco`` for work that does not render, whatever ``MUJOCO_GL`` says.

    MuJoCo binds its GL backend when it is imported, and the import itself
    fails (``AttributeError`` inside PyOpenGL) when ``MUJOCO_GL`` names a
    backend whose library is missing.  Nothing but rendering needs that
    backend, so the import is retried once with ``MUJOCO_GL`` and
    ``PYOPENGL_PLATFORM`` removed from ``environ`` (default ``os.environ``; the
    modules of the failed import are dropped first); ``warn`` (default: one
    line on stderr) is told why.  A second failure is raised as it is.
    """
    env = os.environ if environ is None else environ
    try:
        import mujoco
        return mujoco
    except Exception as exc:
        user = env.get("MUJOCO_GL")
        if not user:
            raise
        reason = f"MUJOCO_GL={user} cannot be loaded ({type(exc).__name__}: {exc}); continuing without it " \
                 f"(only rendering needs it)"
    env.pop("MUJOCO_GL", None)
    env.pop("PYOPENGL_PLATFORM", None)
    for name in [m for m in sys.modules if m == "OpenGL" or m.startswith("OpenGL.") or m == "mujoco"
                 or (m.startswith("mujoco.") and not m.startswith("mujoco._"))]:
        del sys.modules[name]
    (warn or (lambda text: print(f"simgrip: warning: {text}", file=sys.stderr)))(reason)
    import mujoco
    return mujoco
