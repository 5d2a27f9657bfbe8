"""Choose an OpenGL backend for offscreen rendering, so that pictures work on a machine without a display.

MuJoCo picks its GL backend once, when ``mujoco`` is imported, from the
environment variable ``MUJOCO_GL`` (``glfw`` when unset, which needs a
display; ``egl`` and ``osmesa`` render offscreen).  PyOpenGL likewise fixes its
platform (``PYOPENGL_PLATFORM``) when ``OpenGL`` is first imported, so a
backend that fails cannot be swapped for another in the same process.

:func:`choose_backend` therefore decides before the first GL context:

* ``MUJOCO_GL`` set by the user: that backend, untouched;
* a display (``DISPLAY`` or ``WAYLAND_DISPLAY``) or not Linux: MuJoCo's default;
* otherwise (headless Linux): the first of ``egl`` and ``osmesa`` that can
  make a context, each tried in a fresh interpreter.  The choice is written to
  ``MUJOCO_GL`` and ``PYOPENGL_PLATFORM`` (so worker processes inherit it and
  nothing is probed twice).  When none works, :class:`RenderingUnavailable`
  says what was tried and why each failed.

:func:`make_renderer` builds a :class:`mujoco.Renderer` on the chosen backend.
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

__all__ = ["HEADLESS_BACKENDS", "RenderingUnavailable", "choose_backend", "has_display", "make_renderer", "probe"]

#: Offscreen backends tried in order on a headless Linux machine.
HEADLESS_BACKENDS = ("egl", "osmesa")
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
    library = _LIBRARIES.get(backend)
    if library and ctypes.util.find_library(library) is None:
        return f"lib{library} not found"
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
    import mujoco
    from mujoco.rendering.classic import gl_context

    if backend in HEADLESS_BACKENDS:
        wanted = importlib.import_module(f"mujoco.{backend}").GLContext
        if getattr(gl_context, "GLContext", None) is not wanted:
            # mujoco was imported before MUJOCO_GL was chosen: its renderer would use GLFW (no display)
            gl_context.GLContext = wanted
    try:
        return mujoco.Renderer(model, height=height, width=width)
    except Exception as exc:
        if isinstance(exc, ValueError) and "framebuffer" in str(exc):
            raise  # a size the model's offscreen buffer cannot hold: MuJoCo's own message says which
        raise RenderingUnavailable(f"cannot render with MUJOCO_GL={backend or 'glfw'}: {exc}") from exc
