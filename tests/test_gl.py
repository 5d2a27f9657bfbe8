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
    headless["MUJOCO_GL"] = "EGL"
    monkeypatch.setattr(gl, "missing_library", lambda b: None)
    monkeypatch.setattr(gl, "probe", lambda b: pytest.fail("probed although MUJOCO_GL is set"))
    assert gl.choose_backend(headless) == "egl"


def test_the_users_backend_without_its_library_is_named(headless, monkeypatch):
    """A user's MUJOCO_GL whose library is missing (osmesa without libOSMesa makes MuJoCo's own import die in
    PyOpenGL; egl without libEGL likewise): ours names it.  Only this dict is set, never a process's backend."""
    headless["MUJOCO_GL"] = "egl"
    monkeypatch.setattr(gl.ctypes.util, "find_library", lambda name: None)
    with pytest.raises(gl.RenderingUnavailable, match=r"MUJOCO_GL=egl: libEGL not found"):
        gl.choose_backend(headless)


def test_an_unknown_users_backend_is_named(headless):
    headless["MUJOCO_GL"] = "bogus"
    with pytest.raises(gl.RenderingUnavailable, match=r"MUJOCO_GL=bogus is not a backend MuJoCo knows"):
        gl.choose_backend(headless)


_TWICE = """
import warnings
warnings.simplefilter("ignore")
from simgrip import STANDARD, Uniform
from simgrip.sim.gl import RenderingUnavailable, make_renderer
from simgrip.sim.scene import build_scene
sc = build_scene("I", STANDARD, Uniform(-6.0), 8, render=True)
for attempt in range(3):
    try:
        make_renderer(sc.model, 60, 80)
        print("rendered")
    except RenderingUnavailable as exc:
        print("unavailable", exc)
"""


@pytest.mark.parametrize("display", [None, ":97"], ids=["no-display", "unreachable-display"])
def test_glfw_without_a_working_display_fails_by_name_every_time(display):
    """GLFW's second try after a failed one aborted the interpreter (libc++abi, rc 134): refused by name instead."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")}
    env["MUJOCO_GL"] = "glfw"
    if display:
        env["DISPLAY"] = display
    proc = subprocess.run([sys.executable, "-c", _TWICE], env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    assert len(lines) == 3 and all(ln.startswith("unavailable cannot render with MUJOCO_GL=glfw") for ln in lines), lines
    assert len(set(lines)) == 1  # the later attempts repeat the first error without touching GLFW again


def test_commands_that_do_not_render_ignore_a_broken_mujoco_gl(tmp_path):
    """``MUJOCO_GL=bogus`` makes ``import mujoco`` raise (as osmesa without libOSMesa does, inside PyOpenGL): simulate
    warns and works.  The value is one no machine has, so the test never forces a backend that may work or not."""
    value = "bogus"
    env = {k: v for k, v in os.environ.items() if k not in ("PYOPENGL_PLATFORM",)}
    env["MUJOCO_GL"] = value
    for args in (["simulate", "I", "--kappa", "-6", "--links", "8"], ["solve", "I", "--kappa", "-6"]):
        # (solve too: its validity check builds the simulation's solids, and once died here with a traceback)
        proc = subprocess.run([sys.executable, "-m", "simgrip.cli", *args, "--json"], env=env, capture_output=True,
                              text=True, timeout=120, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert json.loads(proc.stdout)["grip"] == "I"
        assert proc.stderr.strip().splitlines() == [next(
            ln for ln in proc.stderr.splitlines() if ln.startswith(f"simgrip: warning: MUJOCO_GL={value} cannot be loaded"))]
    proc = subprocess.run([sys.executable, "-m", "simgrip.cli", "render", "--png", "g.png", "--gif", "p.gif"],
                          env=env, capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith(f"simgrip render: failed: RenderingUnavailable: MUJOCO_GL={value}")
    assert not list(tmp_path.iterdir())


def test_a_display_keeps_mujocos_default(headless, monkeypatch):
    headless["DISPLAY"] = ":0"
    monkeypatch.setattr(gl, "probe", lambda b: pytest.fail("probed although there is a display"))
    assert gl.choose_backend(headless) is None


def test_headless_takes_the_first_backend_that_works_and_records_it(headless, monkeypatch):
    tried = []

    first, second = gl.HEADLESS_BACKENDS[:2]  # the order is simgrip's; no backend is named (or set) here

    def probe(backend):
        tried.append(backend)
        return f"lib{backend} not found" if backend == first else None

    monkeypatch.setattr(gl, "probe", probe)
    before = {k: os.environ.get(k) for k in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    assert gl.choose_backend(headless) == second
    assert tried == [first, second]
    assert headless["MUJOCO_GL"] == second and headless["PYOPENGL_PLATFORM"] == second  # the private dict only
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
        # skipped only where the machine has no offscreen library at all: with one, giving up is a failure
        installed = [b for b in gl.HEADLESS_BACKENDS if gl.missing_library(b) is None]
        assert not installed, f"{installed} installed, yet simgrip found no backend: {out['skip']}"
        pytest.skip(out["skip"])
    assert out["shape"] == [60, 80, 3] and out["spread"] > 1.0  # not a blank frame
