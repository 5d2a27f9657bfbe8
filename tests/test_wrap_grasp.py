"""The rendered wrap grasp (issue 17 s.5, simgrip.figures.wrap_grasp): three fingers around a sphere, full contact.

The state drawn must be a valid wrap: held, converged, no contact deeper than 1e-3 l, no finger crossing
itself or entering the sphere (recomputed from the link angles), each finger touching the sphere along its
length as well as at its tip.  The render runs at low resolution and n = 16 (the wrap's contact set, mid-finger
and tip, is the same as at n = 32: links 7 | 15 and 15 | 31); it is skipped only where no OpenGL library is
installed at all (as tests/test_gl.py).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simgrip.figures import wrap_grasp as wg

SMALL_N = 16


@pytest.fixture(scope="module")
def wrap():
    from simgrip.gripper.settle import settle_gripper

    scene = wg.wrap_scene(SMALL_N)
    return scene, settle_gripper(scene, contact="full")


def test_the_settled_wrap_is_valid(wrap):
    scene, state = wrap
    assert wg.wrap_violations(scene, state) == []
    assert state.held and state.converged and state.penetration <= wg.MAX_PENETRATION
    on = [c for c in state.contact_set if c["with"] == "workpiece"]
    for k in range(wg.WRAP["fingers"]):
        links = {c["link"] for c in on if c["finger"] == k}
        assert SMALL_N - 1 in links and min(links) < SMALL_N // 2 + 2, (k, links)  # the tip and mid-finger
    # every finger the same (the scene is symmetric): the wrap, not one finger doing the work
    forces = [sum(c["normal_force"] for c in on if c["finger"] == k) for k in range(3)]
    assert max(forces) - min(forces) <= 1e-3 * max(forces)


def test_the_check_sees_an_invalid_state(wrap):
    """Curled tighter by hand, finger 0 enters the sphere; four times its curvature, it crosses itself."""
    scene, state = wrap
    q = np.array(state.link_angles, dtype=float)
    deeper = q.copy()
    deeper[0] *= 1.3
    bad = wg.wrap_violations(scene, dataclasses.replace(state, link_angles=deeper))
    assert any("finger 0 enters the sphere" in b for b in bad), bad
    loops = q.copy()
    loops[0] *= 4.0
    bad = wg.wrap_violations(scene, dataclasses.replace(state, link_angles=loops))
    assert any("finger 0 crosses itself" in b for b in bad), bad
    bad = wg.wrap_violations(scene, dataclasses.replace(state, held=False, contact_set=[]))
    assert "the sphere was dropped" in bad and any("tip only" in b for b in bad)


def _render_or_skip(fn):
    from simgrip.sim import gl

    try:
        return fn()
    except gl.RenderingUnavailable as exc:
        installed = [b for b in gl.HEADLESS_BACKENDS if gl.missing_library(b) is None]
        assert not installed, f"{installed} installed, yet simgrip found no backend: {exc}"
        pytest.skip(str(exc))


def test_the_render_shows_fingers_around_the_sphere(wrap):
    from simgrip.figures.gripper import render_gripper

    scene, state = wrap
    img = _render_or_skip(lambda: render_gripper(scene, state, width=96, height=72, elevation=-15.0))
    assert img.shape == (72, 96, 3) and img.dtype == np.uint8 and img.std() > 10
    r, g, b = (img[..., i].astype(int) for i in range(3))
    orange = (r > g + 40) & (r > b + 60)
    blue = (b > r + 60) & (b > g + 20)
    assert orange.mean() > 0.002 and blue.mean() > 0.02, (orange.mean(), blue.mean())
    # wrapped: finger pixels on both sides of the sphere and below its widest row (curled under it)
    rows, cols = np.nonzero(blue)
    mid = int(np.median(rows))
    fr, fc = np.nonzero(orange)
    assert np.any(fc < cols.min() + 3) and np.any(fc > cols.max() - 3)
    assert np.any(fr > mid + 0.3 * (rows.max() - mid))


def test_figures_command_writes_wrap_grasp(tmp_path, monkeypatch):
    from PIL import Image

    from simgrip.figures import make_figures

    monkeypatch.setattr(wg, "LINKS", SMALL_N)  # the figure's own n = 32 takes ~3 x longer
    paths = _render_or_skip(lambda: make_figures(tmp_path, which=["wrap_grasp"], jobs=1, progress=False))
    assert [p.name for p in paths] == ["wrap_grasp.png"]
    with Image.open(paths[0]) as im:
        assert im.size == (800, 600)
