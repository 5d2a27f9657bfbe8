"""Offscreen GL backend choice: the user's MUJOCO_GL wins, headless machines get EGL then OSMesa, failures say why."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from simgrip.sim import gl


@pytest.fixture
def headless(monkeypatch):
    """A headless Linux machine's environment, as a private dict (probes are replaced per test).

    ``choose_backend`` reads and records its choice in the mapping it is given:
    the tests give it this dict, so no backend is ever written into the test
    process's own environment (where it would bind every later render to it).
    """
    monkeypatch.setattr(gl.platform, "system", lambda: "Linux")
    return {"PATH": os.environ.get("PATH", "")}


def test_the_users_backend_is_kept_without_probing(headless, monkeypatch):
    headless["MUJOCO_GL"] = "users-own"
    monkeypatch.setattr(gl, "probe", lambda b: pytest.fail("probed although MUJOCO_GL is set"))
    assert gl.choose_backend(headless) == "users-own"


def test_a_display_keeps_mujocos_default(headless, monkeypatch):
    headless["DISPLAY"] = ":0"
    monkeypatch.setattr(gl, "probe", lambda b: pytest.fail("probed although there is a display"))
    assert gl.choose_backend(headless) is None


def test_headless_takes_the_first_backend_that_works_and_records_it(headless, monkeypatch):
    tried = []

    def probe(backend):
        tried.append(backend)
        return "libEGL not found" if backend == "egl" else None

    monkeypatch.setattr(gl, "probe", probe)
    before = {k: os.environ.get(k) for k in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    assert gl.choose_backend(headless) == "osmesa"
    assert tried == ["egl", "osmesa"]
    assert headless["MUJOCO_GL"] == "osmesa" and headless["PYOPENGL_PLATFORM"] == "osmesa"
    assert {k: os.environ.get(k) for k in before} == before  # the process's own environment is untouched


def test_no_backend_says_what_it_tried_and_why(headless, monkeypatch):
    monkeypatch.setattr(gl, "probe", lambda b: f"lib{b} missing")
    with pytest.raises(gl.RenderingUnavailable) as info:
        gl.choose_backend(headless)
    msg = str(info.value)
    assert "egl: libegl missing" in msg and "osmesa: libosmesa missing" in msg and "MUJOCO_GL" in msg
    assert "MUJOCO_GL" not in headless


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
