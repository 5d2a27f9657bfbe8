"""Figures: files are written, readable and not blank; the numbers behind them say what the figures claim.

The elastica physics itself is tested in ``test_elastica.py``; here we check that
each figure shows what its caption says (shaded region = feasibility criterion,
heights and shapes consistent, overlays drawn), and the plumbing (lazy
matplotlib, atomic PNGs, determinism across ``jobs``).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from simgrip import STANDARD, Uniform, figures

CHEAP = ["fig06", "fig12"]


@pytest.fixture(scope="module")
def fig07():
    return figures.figure_data("fig07")


@pytest.fixture(scope="module")
def fig09():
    return figures.figure_data("fig09")


def test_import_does_not_import_matplotlib():
    code = "import sys, simgrip, simgrip.figures; assert 'matplotlib' not in sys.modules, 'matplotlib imported'"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_names_are_normalised_and_checked(tmp_path):
    assert figures._name(7) == figures._name("fig7") == figures._name("FIG07") == "fig07"
    with pytest.raises(ValueError, match="fig10"):
        figures.figure_data("fig10")
    with pytest.raises(ValueError, match="unknown figure"):
        figures.make_figures(tmp_path, which=["fig99"], progress=False)
    with pytest.raises(ValueError, match="jobs"):
        figures.make_figures(tmp_path, which=CHEAP, jobs=0, progress=False)


def _check_png(path):
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 300
    gray = img[..., :3].mean(axis=-1)
    assert gray.std() > 0.05, f"{path.name} looks blank"
    assert (gray < 0.5).mean() > 0.005, f"{path.name} has almost no ink"


def test_smoke_two_figures_any_jobs(tmp_path):
    one = figures.make_figures(tmp_path / "j1", which=CHEAP, jobs=1, progress=False)
    two = figures.make_figures(tmp_path / "j2", which=["fig12", 6], jobs=2, progress=False)
    assert [p.name for p in one] == ["fig06.png", "fig12.png"]
    assert [p.name for p in two] == ["fig12.png", "fig06.png"]
    for p in one:
        _check_png(p)
        assert p.read_bytes() == (tmp_path / "j2" / p.name).read_bytes(), "result depends on jobs"
    # atomic writes leave no temporary files behind
    assert sorted(x.name for x in (tmp_path / "j1").iterdir()) == ["fig06.png", "fig12.png"]
    # no pyplot state: figures are never registered with pyplot
    if "matplotlib.pyplot" in sys.modules:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == []


def test_fig06_shapes():
    d = figures.figure_data("fig06")
    s = np.linspace(0.0, 1.0, d["x_a"].shape[1])
    for k, x, z in zip(d["kappa"], d["x_a"], d["z_a"]):
        if k == 0:  # straight without gravity
            np.testing.assert_allclose(x, s, atol=1e-7)
            np.testing.assert_allclose(z, 0.0, atol=1e-7)
        else:  # (a) circular arcs of radius 1/|k| centred at (0, 1/k)
            np.testing.assert_allclose(np.hypot(x, z - 1.0 / k), 1.0 / abs(k), atol=1e-6)
    # (b) the weight bends the straight rod down, and unit arc length is kept
    i0 = int(np.flatnonzero(d["kappa"] == 0)[0])
    assert d["z_b"][i0, -1] < -0.05
    length = np.hypot(np.diff(d["x_b"], axis=1), np.diff(d["z_b"], axis=1)).sum(axis=1)
    np.testing.assert_allclose(length, 1.0, atol=1e-3)


def test_fig07_shading_is_the_friction_criterion(fig07):
    d = fig07
    assert d["success"].all()
    np.testing.assert_allclose(d["required"], STANDARD.M)          # |F_f| = M
    np.testing.assert_allclose(d["available"], STANDARD.mu_s * d["N"])
    np.testing.assert_array_equal(d["feasible"], (d["N"] > 0) & (d["available"] >= STANDARD.M))
    np.testing.assert_array_equal(d["feasible"], d["solver_feasible"])
    # one shaded interval, at the strongly curved end of [0, -6]
    f = np.flatnonzero(d["feasible"])
    assert f.size > 3 and np.all(np.diff(f) == 1) and f[-1] == len(d["kappa"]) - 1
    # tips on the workpiece's side, heights = the shapes' tips
    np.testing.assert_allclose(d["shape_x"][:, -1], STANDARD.b / 2, atol=1e-7)
    np.testing.assert_allclose(d["shape_z"][:, -1], d["h"], atol=1e-12)
    # the paper's remark: in the feasible region h is nearly linear in kappa
    k, h = d["kappa"][f], d["h"][f]
    resid = h - np.polyval(np.polyfit(k, h, 1), k)
    assert np.abs(resid).max() < 0.02 * np.ptp(h)


def test_fig09_shading_and_heights(fig09):
    d = fig09
    g = STANDARD.gamma
    np.testing.assert_array_equal(d["tip_below_contact"], d["h"] < d["h_gamma"])
    np.testing.assert_array_equal(
        d["feasible"], (d["n"] > 0) & (np.abs(d["f"]) <= STANDARD.mu_s * d["n"]) & (d["h"] < d["h_gamma"]))
    np.testing.assert_array_equal(d["feasible"], d["solver_feasible"])
    assert d["feasible"].any() and not d["feasible"].all()
    # h_gamma is the shape's height at s = gamma, where x = b/2
    i = int(round(g * (d["shape_z"].shape[1] - 1)))
    np.testing.assert_allclose(d["shape_z"][:, i], d["h_gamma"], atol=1e-9)
    np.testing.assert_allclose(d["shape_x"][:, i], STANDARD.b / 2, atol=1e-7)
    # the paper's remark: a kappa where (almost) no friction is needed, inside the feasible range
    j = int(np.nanargmin(np.where(d["n"] > 0, d["required"] / d["n"], np.inf)))
    assert d["feasible"][j] and d["required"][j] < 0.05 * d["available"][j]


def test_overlay_draws_simulated_points(fig07, fig09):
    base = figures.plot_figure("fig07", fig07)
    over = {"kappa": [-5.0, -6.0], "muN": [5.4, 7.9], "h": [-0.70, -0.65], "label": "MuJoCo",
            "shapes": [(fig07["shape_x"][-1], fig07["shape_z"][-1])]}
    fig = figures.plot_figure("fig07", fig07, overlay=over)
    n_base = sum(len(ax.lines) for ax in base.axes)
    assert sum(len(ax.lines) for ax in fig.axes) == n_base + 3
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert any("MuJoCo" in t for t in labels)
    fig9 = figures.plot_figure("fig09", fig09, overlay={"kappa": [-4.0], "f": [1.0], "mu_n": [7.0],
                                                        "h": [-0.6], "h_gamma": [-0.58]})
    assert sum(len(ax.lines) for ax in fig9.axes) == sum(len(ax.lines) for ax in figures.plot_figure("fig09", fig09).axes) + 4
    with pytest.raises(ValueError, match="kappa"):
        figures.plot_figure("fig07", fig07, overlay={"h": [0.1]})
    with pytest.raises(ValueError, match="fig06-fig09"):
        figures.plot_figure("fig12", {}, overlay={"kappa": [1.0]})


def test_fig16_matches_fig07(fig07):
    d = figures.figure_data("fig16")
    np.testing.assert_allclose(d["kappa_I"], fig07["kappa"])
    lm = d["least_mu_I"]
    # (a) least mu_s <= 1 exactly where Fig. 7 shades (mu_s = 1)
    np.testing.assert_array_equal(np.nan_to_num(lm, nan=np.inf) <= 1.0, fig07["feasible"])
    # (b) the largest load held at mu_s = 1 exceeds M = 5 exactly where Fig. 7 holds M = 5
    sel = np.searchsorted(-d["kappa_I"], -d["kappa_load_I"])
    np.testing.assert_array_equal(d["max_load_I"] >= STANDARD.M, fig07["feasible"][sel])
    # and agrees with the elastica's own search
    from simgrip import elastica

    i = int(np.flatnonzero(d["kappa_load_I"] == -5.0)[0])
    ref = elastica.max_load("I", STANDARD, Uniform(-5.0), tol=1e-6)
    assert d["max_load_I"][i] == pytest.approx(ref, rel=2e-3)
    # Grip III carries the most at the strongest curvature of each range
    assert d["max_load_III"][-1] > max(d["max_load_I"][-1], d["max_load_II"][-1])


def test_fig13_concentrating_curvature_does_not_help():
    d = figures.figure_data("fig13")
    assert d["success"].all()
    np.testing.assert_allclose(d["capacity"], STANDARD.mu_s * d["N"])
    # the paper's conclusion: any alpha in [1, 3] holds less than the uniform profile of the same peak
    assert np.all(d["capacity"] < d["uniform_capacity"])
    assert np.all(np.diff(d["capacity"]) < 0)
    assert np.all(d["lambda_min"] > 0)
