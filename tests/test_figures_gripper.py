"""K-finger figures (simgrip.figures.gripper): N per finger on the BVP curve, and the rendered grasps.

Tolerance of the force plot.  A cylinder held by K fingers puts every finger in
the paper's planar Grip I problem (``test_settle_gripper.py``), so each
finger's ``N`` is the planar chain's up to the stop test's residual (``tol``
times the chain's sensitivity: ~1e-5 relative).  The planar chain is second
order in ``ds``, documented at ``n = 32`` as ``N`` within 0.5 % of the BVP
solved with the settle's own tip couple (``test_settle.py``; the K-finger test
uses 4 x that at ``n = 16``).  The plotted curve is the point-contact BVP: a
point lies on it within that 0.5 % plus the shift the tip couple makes, which
the test computes (the BVP with and without the couple), not tunes.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from simgrip import STANDARD, Uniform, figures
from simgrip.figures import gripper as fg
from simgrip.figures.catalog import FIGURES, GRIPPER_FIGURES, RENDERED_FIGURES
from simgrip.reference import elastica
from simgrip.gripper.settle import settle_gripper
from simgrip.gripper.scene import build_gripper

#: Few points: dropped well below the feasible window (mu_s N = 0.90 M at -4.5), held inside it.
KAPPAS = (-4.5, -5.5, -6.0)
SMALL_N = 8  # links of the render tests


@pytest.fixture(scope="module")
def forces():
    return fg.gripper_force_data(fingers=(3, 4), kappas=KAPPAS, links=32)


def test_names_are_in_the_catalog():
    assert set(GRIPPER_FIGURES) <= set(FIGURES) and set(RENDERED_FIGURES) == set(fg.GRASPS) | {"wrap_grasp"}
    for name in GRIPPER_FIGURES:
        assert figures.figure_key(name) == name and figures.figure_key(name.upper()) == name
        with pytest.raises(ValueError, match="simgrip.figures.gripper"):
            figures.figure_data(name)
    with pytest.raises(ValueError, match="unknown gripper figure"):
        fg.make_gripper_figure("fig07", "unused")


def test_curve_is_the_point_contact_bvp(forces):
    k = forces["kappa"]
    assert k[0] == 0.0 and k[-1] == -6.0 and np.all(np.isfinite(forces["N"][k <= -2.0]))
    for kk in (-3.0, -5.0, -6.0):
        i = int(np.argmin(np.abs(k - kk)))
        ref = elastica.solve("I", STANDARD, Uniform(kk))
        assert forces["N"][i] == pytest.approx(ref.N1, rel=1e-6)
        assert bool(forces["feasible"][i]) == bool(STANDARD.mu_s * ref.N1 >= STANDARD.M)


@pytest.mark.parametrize("K", [3, 4])
def test_every_finger_lies_on_the_bvp(forces, K):
    held, N = forces[f"held_{K}"], forces[f"N_{K}"]
    assert N.shape == (len(KAPPAS), K)
    for i, k in enumerate(KAPPAS):
        point = elastica.solve("I", STANDARD, Uniform(k))
        # held iff mu_s N >= M (these kappas are 10 % or more from the criterion's edge)
        assert held[i] == (STANDARD.mu_s * point.N1 >= STANDARD.M), k
        if not held[i]:
            assert np.all(np.isnan(N[i])) and np.isnan(forces[f"ref_{K}"][i])
            continue
        own = elastica.solve("I", STANDARD, Uniform(k), contact_moment=forces[f"couple_{K}"][i])
        assert abs(forces[f"couple_{K}"][i]) < 2e-3 * 1.01 * STANDARD.M  # r_tip x the friction M, at most
        assert forces[f"ref_{K}"][i] == pytest.approx(own.N1, rel=1e-6)
        # the chain's n = 32 error against the BVP with the settle's couple
        assert np.all(np.abs(N[i] / own.N1 - 1.0) < fg.N_REL_32), (k, N[i], own.N1)
        assert forces[f"rel_{K}"][i] == pytest.approx(np.max(np.abs(N[i] / own.N1 - 1.0)), rel=1e-9)
        # on the plotted (point-contact) curve, within that plus the couple's computed shift
        shift = abs(own.N1 / point.N1 - 1.0)
        assert np.all(np.abs(N[i] / point.N1 - 1.0) < fg.N_REL_32 + shift)


def test_the_force_plot_draws(forces, tmp_path):
    from simgrip.figures.plot import save_figure

    fig = fg.plot_gripper_forces(forces)
    a, b = fig.axes
    assert len(a.lines) >= 4 and len(b.lines) >= 3  # curve, M/mu line, points per K (held, dropped); deviations
    path = save_figure(fig, tmp_path / "grip_forces.png")
    _check_png(path)
    curve_only = fg.gripper_force_data(simulate=False, kappas=KAPPAS)
    assert "held_3" not in curve_only
    _check_png(save_figure(fg.plot_gripper_forces(curve_only), tmp_path / "curve.png"))


def _check_png(path):
    from PIL import Image

    with Image.open(path) as im:
        img = np.asarray(im.convert("RGB"), dtype=float) / 255.0
    assert img.shape[0] > 200 and img.shape[1] > 300
    gray = img.mean(axis=-1)
    assert gray.std() > 0.05 and (gray < 0.5).mean() > 0.005, f"{path} looks blank"


# ---------------------------------------------------------------------------
# rendering


@pytest.fixture(scope="module")
def small_grasps():
    out = {}
    for K, shape in fg.GRASPS.values():
        sc = build_gripper("I", STANDARD, Uniform(-6.0), SMALL_N, fingers=K, workpiece=shape)
        out[K] = sc, settle_gripper(sc, method="dynamics")
    return out


def _colours(img):
    """Fractions of pixels in the fingers' orange and the workpiece's blue (sky, floor and palm are neither)."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return ((r > g + 40) & (r > b + 60)).mean(), ((b > r + 60) & (b > g + 20)).mean()


@pytest.mark.parametrize("K", [3, 4])
def test_render_shows_the_fingers_and_the_workpiece(small_grasps, K):
    sc, st = small_grasps[K]
    assert st.held
    nq, q = sc.model.nq, sc.data.qpos.copy()
    img = fg.render_gripper(sc, width=96, height=72)
    assert img.shape == (72, 96, 3) and img.dtype == np.uint8
    assert img.std() > 10  # not blank
    fingers, workpiece = _colours(img)
    assert fingers > 0.002 and workpiece > 0.02, (fingers, workpiece)  # measured: 0.006-0.011, 0.04-0.06
    # the simulated scene is untouched: same model, same state
    assert sc.model.nq == nq and np.array_equal(sc.data.qpos, q)
    # drawing the settled state passed in is the same picture, also after the scene moved
    sc.data.qpos[sc.joint_qpos] = 0.0
    assert np.array_equal(fg.render_gripper(sc, st, width=96, height=72), img)


def test_render_checks_its_arguments(small_grasps, tmp_path):
    sc, st = small_grasps[3]
    for kw, name in [(dict(width=0), "width"), (dict(height=5000), "height"), (dict(width=64.0), "width"),
                     (dict(elevation=95), "elevation"), (dict(azimuth="x"), "azimuth"),
                     (dict(draw_radius=0), "draw_radius"), (dict(draw_height=float("nan")), "draw_height")]:
        with pytest.raises(ValueError, match=name):
            fg.render_gripper(sc, **kw)
    with pytest.raises(ValueError, match="scene"):
        fg.render_gripper(st)
    with pytest.raises(ValueError, match="state"):
        fg.render_gripper(sc, small_grasps[4][1])
    with pytest.raises(ValueError, match="image"):
        fg.write_png(np.zeros((4, 4)), tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()


def test_renders_headless_in_a_fresh_process(tmp_path):
    """No display, no MUJOCO_GL: simgrip picks EGL, then OSMesa, and writes the PNG whole."""
    code = (
        "import sys; from simgrip.figures.gripper import grasp_picture, write_png\n"
        f"img, st = grasp_picture(4, 'box', links={SMALL_N}, width=80, height=60)\n"
        "assert st.held and img.shape == (60, 80, 3) and img.std() > 10\n"
        "write_png(img, sys.argv[1])\n"
    )
    import simgrip

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL",
                                                             "PYOPENGL_PLATFORM")}
    env["PYTHONPATH"] = os.path.dirname(os.path.dirname(simgrip.__file__))  # this checkout's simgrip
    out = tmp_path / "grasp.png"
    proc = subprocess.run([sys.executable, "-c", code, str(out)], env=env, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (80, 60)


def test_make_figures_writes_the_gripper_figures(tmp_path):
    paths = figures.make_figures(tmp_path, which=["grasp4", "GRASP3"], jobs=1, progress=False)
    assert [p.name for p in paths] == ["grasp4.png", "grasp3.png"]
    for p in paths:
        _check_png(p)


def test_without_opengl_all_figures_skip_the_renders_but_named_renders_fail(tmp_path, monkeypatch, capsys):
    import simgrip.figures.make as make
    import simgrip.sim.gl as gl

    def no_backend():
        raise gl.RenderingUnavailable("no OpenGL backend works here (tried egl, osmesa)")

    monkeypatch.setattr(gl, "choose_backend", no_backend)
    monkeypatch.setattr(make, "FIGURES", {"fig12": "", "grasp3": ""})  # "all" = one cheap curve and one render
    paths = make.make_figures(tmp_path, jobs=1, progress=False, simulate=False)
    assert [p.name for p in paths] == ["fig12.png"]
    assert "skipping the renders" in capsys.readouterr().err
    with pytest.raises(gl.RenderingUnavailable):
        make.make_figures(tmp_path, which=["grasp3"], jobs=1, progress=False)
