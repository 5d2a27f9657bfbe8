"""Offscreen GL backend choice: the user's MUJOCO_GL wins, headless machines get EGL then OSMesa, failures say why."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from simgrip.sim import gl


_GL_VARIABLES = ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")


@pytest.fixture
def headless(monkeypatch):
    """A headless Linux machine without MUJOCO_GL / PYOPENGL_PLATFORM (probes are replaced per test).

    ``choose_backend`` records its choice in ``os.environ``; the variables are
    restored afterwards whether or not they were set before, so a backend
    chosen here (e.g. osmesa by a fake probe) never leaks into later tests.
    """
    saved = {name: os.environ.get(name) for name in _GL_VARIABLES}
    monkeypatch.setattr(gl.platform, "system", lambda: "Linux")
    for name in _GL_VARIABLES:
        os.environ.pop(name, None)
    yield monkeypatch
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def test_the_users_backend_is_kept_without_probing(headless):
    headless.setenv("MUJOCO_GL", "osmesa")
    headless.setattr(gl, "probe", lambda b: pytest.fail("probed although MUJOCO_GL is set"))
    assert gl.choose_backend() == "osmesa"


def test_a_display_keeps_mujocos_default(headless):
    headless.setenv("DISPLAY", ":0")
    headless.setattr(gl, "probe", lambda b: pytest.fail("probed although there is a display"))
    assert gl.choose_backend() is None


def test_headless_takes_the_first_backend_that_works_and_records_it(headless):
    tried = []

    def probe(backend):
        tried.append(backend)
        return "libEGL not found" if backend == "egl" else None

    headless.setattr(gl, "probe", probe)
    assert gl.choose_backend() == "osmesa"
    assert tried == ["egl", "osmesa"]
    assert os.environ["MUJOCO_GL"] == "osmesa" and os.environ["PYOPENGL_PLATFORM"] == "osmesa"


def test_no_backend_says_what_it_tried_and_why(headless):
    headless.setattr(gl, "probe", lambda b: f"lib{b} missing")
    with pytest.raises(gl.RenderingUnavailable) as info:
        gl.choose_backend()
    msg = str(info.value)
    assert "egl: libegl missing" in msg and "osmesa: libosmesa missing" in msg and "MUJOCO_GL" in msg
    assert "MUJOCO_GL" not in os.environ


def test_a_backend_that_cannot_load_is_reported_not_raised():
    why = gl.probe("no-such-backend")
    assert isinstance(why, str) and why


def test_renders_headless_with_mujoco_imported_first(tmp_path):
    """The real path on this machine: MUJOCO_GL unset, no display, mujoco imported before the choice."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")}
    code = """
        import json, mujoco
        from simgrip import STANDARD, Uniform
        from simgrip.sim.gl import RenderingUnavailable, make_renderer
        from simgrip.sim.scene import build_scene
        sc = build_scene("I", STANDARD, Uniform(-6.0), 8, render=True)
        try:
            r = make_renderer(sc.model, 60, 80)
        except RenderingUnavailable as exc:
            print(json.dumps({"skip": str(exc)}))
        else:
            r.update_scene(sc.data)
            img = r.render()
            r.close()
            print(json.dumps({"shape": list(img.shape), "spread": float(img.std())}))
    """
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    if "skip" in out:
        pytest.skip(out["skip"])
    assert out["shape"] == [60, 80, 3] and out["spread"] > 1.0  # not a blank frame
