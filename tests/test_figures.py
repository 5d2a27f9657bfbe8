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
    assert figures.figure_key(7) == figures.figure_key("fig7") == figures.figure_key("FIG07") == "fig07"
    with pytest.raises(ValueError, match="fig10"):
        figures.figure_data("fig10")
    with pytest.raises(ValueError, match="which: unknown figure 'fig99'"):
        figures.make_figures(tmp_path, which=["fig99"], progress=False)
    with pytest.raises(ValueError, match="which"):
        figures.make_figures(tmp_path, which=3.5, progress=False)
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
    from simgrip.reference import capacity

    i = int(np.flatnonzero(d["kappa_load_I"] == -5.0)[0])
    ref = capacity.max_load("I", STANDARD, Uniform(-5.0), tol=1e-6)
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


# ---------------------------------------------------------------------------
# simulation overlay (MuJoCo hinge chain on Figs. 6-9)
#
# Tolerances.  The chain is a second-order discretisation of the elastica: on
# the free rod of Fig. 6 the tip error is 1.19e-3 l at n = 16 and 2.96e-4 l at
# n = 32 (ratio 4.0, checked below).  For the grips the n = 16 points differ
# from the figure's curves by (measured, n = 16 / 32 / 64):
#   * the chain error, second order against the reference solved for the
#     simulated state (simgrip.compare.reference_for): Grip I at kappa = -6,
#     dN = 2.5e-2 / 6.2e-3 / 1.5e-3, dh = 2.5e-3 / 6.2e-4 / 1.5e-4;
#   * an n-independent offset the curves leave out: the contact geoms' radius
#     (r_tip = r_link = 2e-3 l) moves the contact force off the centreline,
#     a couple ~ r M; it shifts N by 0.4 % (I) to 0.6 % (II), and Grip III's
#     f by 0.5 % of mu_s n (with gamma_sim - 0.8 ~ 5e-4).
# Largest n = 16 deviations from the curves: N 0.67 % of N, |f| 0.6 % and mu_s n
# 0.4 % of mu_s n, heights 3.0e-3 l (at n = 32: 1.1e-3, 1.6e-3, 0.7e-3 l for
# Grips I, II, III; 4 x those is 2.8e-3 -- 6.3e-3 l).  Bounds: forces 1e-2
# relative (the offset + 4 x the chain's n = 32 error), positions 5e-3 l.
# ---------------------------------------------------------------------------

FORCE_REL = 1e-2   # forces, relative to the available friction mu_s N (mu_s n)
POS_ABS = 5e-3     # tips and heights, over l
EDGE = 0.3         # hold/drop is compared this far (in kappa_bar0) from the feasible region's edges


@pytest.fixture(scope="module")
def fig08():
    return figures.figure_data("fig08")


@pytest.fixture(scope="module")
def sim16():
    return {k: figures.simulation_overlay(k, links=16) for k in ("fig06", "fig07", "fig08", "fig09")}


def _at(data, kappas):
    """Indices of ``kappas`` on the figure's kappa grid (the simulated kappas lie on it)."""
    idx = np.array([int(np.argmin(np.abs(data["kappa"] - k))) for k in kappas])
    np.testing.assert_allclose(data["kappa"][idx], kappas, atol=1e-12)
    return idx


def _away_from_edges(data, mask, kappas, margin=EDGE):
    """True where ``kappas`` is more than ``margin`` from every switch of ``mask`` along the grid."""
    k, m = np.asarray(data["kappa"]), np.asarray(mask, dtype=bool)
    edges = 0.5 * (k[1:] + k[:-1])[m[1:] != m[:-1]]
    return np.array([np.all(np.abs(edges - kk) > margin) for kk in kappas])


def _off_shape(x, z, xr, zr):
    """Largest distance of chain nodes ``(x, z)`` (at s = i/n) from the reference shape at the same s."""
    s, sr = np.linspace(0.0, 1.0, len(x)), np.linspace(0.0, 1.0, len(xr))
    return float(np.hypot(x - np.interp(s, sr, xr), z - np.interp(s, sr, zr)).max())


def test_fig06_overlay_is_second_order(sim16):
    d = figures.figure_data("fig06")
    o32 = figures.simulation_overlay("fig06", links=32)
    o16 = sim16["fig06"]
    assert o16["label"] == "MuJoCo chain, n = 16" and not o16["failed"].any()
    np.testing.assert_allclose(o16["kappa"], d["kappa"])
    for p in "ab":
        e16, e32 = (np.hypot(o[p]["tip_x"] - d[f"x_{p}"][:, -1], o[p]["tip_z"] - d[f"z_{p}"][:, -1])
                    for o in (o16, o32))
        assert e16.max() < POS_ABS / 2
        k = np.abs(d["kappa"]) > 0  # kappa = 0 without gravity is exact (straight rod)
        ratio = e16.max() / e32.max()
        assert 3.5 < ratio < 4.5, f"panel ({p}): error ratio n=16/n=32 is {ratio:.2f}, not ~4"
        assert np.all(e16[k] < 4.5 * e32[k] + 1e-12)
        # the shapes' nodes lie on the reference shapes (chain nodes at s = i/16)
        for (x, z), xr, zr in zip(o16[p]["shapes"], d[f"x_{p}"], d[f"z_{p}"]):
            assert _off_shape(x, z, xr, zr) < POS_ABS / 2
    # gravity off really is off: the straight rod stays straight, with gravity it sags
    i0 = int(np.flatnonzero(d["kappa"] == 0)[0])
    assert abs(o16["a"]["tip_z"][i0]) < 1e-9 and o16["b"]["tip_z"][i0] < -0.1


@pytest.mark.parametrize("name", ["fig07", "fig08"])
def test_grip_overlay_lies_on_the_curves(name, sim16, fig07, fig08):
    d = {"fig07": fig07, "fig08": fig08}[name]
    o = sim16[name]
    i = _at(d, o["kappa"])
    held = o["held"]
    assert held.sum() >= 3 and not o["failed"].any()
    np.testing.assert_allclose(o["N2"][held], -STANDARD.M, rtol=1e-6)        # the friction carries the weight
    rel = np.abs(o["muN"] - d["available"][i])[held] / d["available"][i][held]
    assert rel.max() < FORCE_REL, rel
    assert np.abs(o["h"] - d["h"][i])[held].max() < POS_ABS
    np.testing.assert_allclose(o["tip_x"][held], STANDARD.b / 2, atol=1e-4)   # tip on the box's face
    # dropped states carry no force values (the free finger is not a point of the grip's curves)
    assert np.isnan(o["muN"][~held]).all() and np.isnan(o["h"][~held]).all()
    # shapes: held states at integer kappa, on the drawn reference shapes
    for kk, (x, z) in zip(o["shape_kappa"], o["shapes"]):
        j = _at(d, [kk])[0]
        assert _off_shape(x, z, d["shape_x"][j], d["shape_z"][j]) < POS_ABS


def test_fig09_overlay_lies_on_the_curves(sim16, fig09):
    d, o = fig09, sim16["fig09"]
    i = _at(d, o["kappa"])
    held = o["held"]
    assert held.sum() >= 3 and not o["failed"].any()
    np.testing.assert_allclose(o["gamma"][held], STANDARD.gamma, atol=2e-3)   # corner sticks at gamma
    # the corner capsule sits r_link + r_corner = 3e-3 l off the centreline: as the rod turns under
    # it (warm-started sweep), X(gamma) moves by up to that much (the box's x is fixed)
    np.testing.assert_allclose(o["x_gamma"][held], STANDARD.b / 2, atol=3e-3)
    np.testing.assert_allclose(o["N2"][held], -STANDARD.M, rtol=1e-6)
    budget = d["available"][i][held]                                          # mu_s n of the curve
    assert (np.abs(o["f"] - d["required"][i])[held] / budget).max() < FORCE_REL
    assert (np.abs(o["mu_n"] - d["available"][i])[held] / budget).max() < FORCE_REL
    assert np.abs(o["h"] - d["h"][i])[held].max() < POS_ABS
    assert np.abs(o["h_gamma"] - d["h_gamma"][i])[held].max() < POS_ABS


@pytest.mark.parametrize("name", ["fig07", "fig08", "fig09"])
def test_hold_drop_matches_the_feasible_region(name, sim16, fig07, fig08, fig09):
    d = {"fig07": fig07, "fig08": fig08, "fig09": fig09}[name]
    o = sim16[name]
    i = _at(d, o["kappa"])
    away = _away_from_edges(d, d["feasible"], o["kappa"])
    assert away.sum() >= 5
    np.testing.assert_array_equal(o["feasible"][away], d["feasible"][i][away])
    assert o["feasible"][away].any() and not o["feasible"][away].all()   # both verdicts are tested
    if name == "fig09":  # the sim's own hold/drop (friction cone) against |f| <= mu_s n
        away_f = _away_from_edges(d, d["friction_ok"], o["kappa"])
        np.testing.assert_array_equal(o["held"][away_f], d["friction_ok"][i][away_f])
        # where friction suffices but the tip rises above the contact, the sim holds (x marker)
        np.testing.assert_array_equal(o["held"] & ~o["feasible"], o["held"] & ~d["tip_below_contact"][i])


def _legend_texts(fig):
    return [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]


def test_figures_render_with_the_simulation_overlay(sim16, fig07, fig09, tmp_path):
    for name, d in (("fig07", fig07), ("fig09", fig09)):
        o = sim16[name]
        base = figures.plot_figure(name, d)
        fig = figures.plot_figure(name, d, overlay=o)
        texts = _legend_texts(fig)
        assert any("MuJoCo chain, n = 16" in t for t in texts)
        assert "MuJoCo holds the box" in texts and "MuJoCo drops the box" in texts
        assert sum(len(ax.lines) for ax in fig.axes) > sum(len(ax.lines) for ax in base.axes)
        _check_png(figures.save_figure(fig, tmp_path / f"{name}.png"))
    assert "MuJoCo holds, tip above contact" in texts  # fig09, kappa = -6
    assert "friction suffices, tip above contact" in texts
    fig6 = figures.plot_figure("fig06", figures.figure_data("fig06"), overlay=sim16["fig06"])
    assert sum("MuJoCo chain, n = 16 (tips)" in t for t in _legend_texts(fig6)) == 2  # both panels


def test_failed_points_are_nan_and_shown(monkeypatch, fig07):
    import simgrip.settle as settle_mod

    real = settle_mod.settle

    def flaky(scene, **kw):
        if abs(scene.profile.kappa + 5.5) < 1e-12:
            raise settle_mod.SettleError("injected failure")
        return real(scene, **kw)

    monkeypatch.setattr(settle_mod, "settle", flaky)
    o = figures.simulation_overlay("fig07", kappas=[-5.0, -5.5, -6.0])
    np.testing.assert_array_equal(o["failed"], [False, True, False])
    assert np.isnan(o["muN"][1]) and not o["held"][1]
    assert "injected failure" in o["errors"][1] and "warm start" in o["errors"][1] and "cold start" in o["errors"][1]
    assert o["held"][2]  # the sweep goes on after a failure (cold start)
    texts = _legend_texts(figures.plot_figure("fig07", fig07, overlay=o))
    assert any("settle failed" in t and "-5.5" in t for t in texts)


def test_make_figures_simulate_switch_and_cli(tmp_path):
    from simgrip.cli import build_parser

    off = figures.make_figures(tmp_path / "off", which=[6], jobs=1, progress=False, simulate=False)
    on = figures.make_figures(tmp_path / "on", which=[6], jobs=1, progress=False, links=8)
    assert off[0].read_bytes() != on[0].read_bytes()
    with pytest.raises(ValueError, match="links"):
        figures.make_figures(tmp_path, which=[6], progress=False, links=1)
    with pytest.raises(ValueError, match="fig06-fig09"):
        figures.simulation_overlay("fig11")
    args = build_parser().parse_args(["figures", "--links", "8", "--no-simulate"])
    assert args.links == 8 and args.no_simulate
    args = build_parser().parse_args(["figures"])
    assert args.links == 16 and not args.no_simulate


def test_bad_out_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from simgrip.cli import main
    from simgrip.figures import make

    def never(task):
        raise AssertionError("a figure was computed before --out was checked")

    monkeypatch.setattr(make, "_render", never)
    (tmp_path / "file").write_text("x")
    for out in (tmp_path / "file", tmp_path / "file" / "sub"):
        assert main(["figures", "--which", "6", "--jobs", "1", "--no-progress", "--out", str(out)]) == 2
        assert "--out" in capsys.readouterr().err
    with pytest.raises(ValueError, match="out_dir"):
        figures.make_figures(tmp_path / "file", which=[6], jobs=1, progress=False)


def test_links_and_jobs_are_bounded_as_every_command(tmp_path, capsys, monkeypatch):
    """``--links`` above MAX_LINKS was drawn (every settle failed, shown only in the legend) and ``--jobs 2000``
    accepted; one figure with ``--jobs 64`` started a local cluster of one worker for one task.  Now: the
    simulate command's bound on the links, the sweep's on the jobs, and no more workers than figures."""
    from simgrip.cli import main
    from simgrip.params import MAX_LINKS

    seen = []

    def fake_run_tasks(fn, tasks, *, options, **kw):
        seen.append(options)
        return [str(tmp_path / f"{t[0]}.png") for t in tasks]

    monkeypatch.setattr("simgrip.parallel.runner.run_tasks", fake_run_tasks)
    for argv, needle in ((["--links", str(MAX_LINKS + 1)], "links must be at most"),
                         (["--jobs", "2000"], "above the bound")):
        assert main(["figures", "--which", "7", "--no-progress", "--out", str(tmp_path), *argv]) == 2
        err = capsys.readouterr().err
        assert needle in err and "Traceback" not in err, err
    assert seen == []
    assert main(["figures", "--which", "7", "--no-progress", "--jobs", "64", "--out", str(tmp_path)]) == 0
    assert "jobs 64 lowered to 1 (1 task to run)" in capsys.readouterr().err
    assert main(["figures", "--which", "7", "--no-progress", "--out", str(tmp_path)]) == 0
    assert [o.in_process for o in seen] == [True, True]


def test_a_failed_overlay_settle_is_said_on_stderr(tmp_path, capsys, monkeypatch):
    """A settle that failed on Figs. 6-9's overlay was shown only in the legend (``figures --links 5000`` drew a
    figure of failed settles with nothing on stderr and exit 0); now one line names the figure and the points."""
    import numpy as np

    from simgrip.figures import make, overlay

    real = overlay.simulation_overlay

    def one_failed(name, links):
        out = real(name, links=links)
        out["failed"] = np.array(out["failed"], dtype=bool)
        out["failed"][0] = True  # as a settle that raised marks its point
        return out

    monkeypatch.setattr(overlay, "simulation_overlay", one_failed)
    paths = make.make_figures(tmp_path, which=[7], jobs=1, progress=False, links=8)
    assert [p.name for p in paths] == ["fig07.png"] and paths[0].is_file()
    err = capsys.readouterr().err
    k0 = real("fig07", links=8)["kappa"][0]
    assert f"simgrip figures: fig07: the settle failed at kappa_bar = {float(k0):g} (8 links" in err, err
