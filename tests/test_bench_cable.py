"""MuJoCo's cable peer (simgrip.harness.bench_cable): it builds, settles, represents a rest curvature and
converges to the elastica BVP at second order; its bench row is consistent."""

import math

import numpy as np
import pytest

from simgrip.harness.bench_cable import build_cable, cable_bench_md, cable_row, cable_run, steps_to_error
from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.reference import elastica

KAPPA = -3.0


@pytest.fixture(scope="module")
def ref():
    return elastica.solve("free", STANDARD, Uniform(KAPPA), tol=1e-10)


def _settled_tip(n, kappa=KAPPA, **kw):
    cable = build_cable(n, kappa, dt=0.003, **kw)
    tips, vmax, warns = cable_run(cable, 3000)  # T = 9 sqrt(l/g): exp(-zeta omega_1 T) ~ 1e-10
    assert not warns
    assert vmax[-1] < 1e-6  # at rest by its own rule
    return tips[-1]


def test_rest_shape_is_the_equilibrium_without_gravity():
    # The compiled (curved) configuration is the flex's bending reference: with no weight nothing moves.
    # The discrete rest shape's tip: edge angles accumulate kappa over the Voronoi lengths.
    cable = build_cable(8, KAPPA, gravity=False)
    start = cable.tip()
    tips, vmax, warns = cable_run(cable, 500)
    assert not warns
    assert np.max(np.abs(tips[-1] - start)) < 1e-9  # round-off of the flex's forces over 500 steps
    # and it is the curled rod, not the straight one: within O(h^2) of the arc's tip (sin k / k, (1 - cos k)/k)
    arc = np.array([math.sin(KAPPA) / KAPPA, (1 - math.cos(KAPPA)) / KAPPA])
    assert np.linalg.norm(start - arc) < 0.5 * (1 / 8) ** 2 * abs(KAPPA)


def test_converges_to_the_bvp_at_second_order(ref):
    e8, e16 = (float(np.linalg.norm(_settled_tip(n) - ref.tip)) for n in (8, 16))
    # second order in h = l/n: e8/e16 = 4 up to the next term, O(h) relative at h = 1/8 (+-25 %); the near-hard
    # edge constraint's stretch (~1e-7 l at these n) is far below both errors
    assert 3.0 < e8 / e16 < 5.0
    assert e16 < 0.5 * 16 ** -2 * abs(KAPPA)  # the same order of magnitude as the hinge chain's C h^2 (C ~ 0.3)


def test_steps_to_error():
    err = np.array([5.0, 3.0, 0.5, 2.0, 0.5, 0.4])
    assert steps_to_error(err, 1.0) == 5  # below from step 5 on (the dip at step 3 does not count)
    assert steps_to_error(err, 10.0) == 1
    assert steps_to_error(np.array([1.0, 2.0]), 1.5) is None  # not below at the end


@pytest.mark.parametrize("bad", [{"n": 1}, {"n": 2.5}, {"n": True}, {"dt": 0.0}, {"dt": math.nan}, {"zeta": -1.0}])
def test_bad_input_names_the_parameter(bad):
    kw = {"n": 8, "dt": 0.003, "zeta": 0.7} | bad
    name = next(iter(bad))
    with pytest.raises(ValueError, match=name):
        build_cable(kw.pop("n"), KAPPA, **kw)


def test_cable_row_matches_the_settle_error(ref):
    row = cable_row(16, KAPPA, repeats=1, ref=ref)
    assert row["steps_to_match"] is not None and row["cable_s"] > 0 and row["settle_s"] > 0
    tried = row["cable_tried"][-1]
    assert tried["dt"] == row["cable_dt"] and not row["cable_warnings"]
    # matched means: at or below simgrip's own error at this n
    cable = build_cable(16, KAPPA, dt=row["cable_dt"])
    tips, _, _ = cable_run(cable, row["steps_to_match"])
    assert np.linalg.norm(tips[-1] - ref.tip) <= row["settle_tip_err"]
    md = cable_bench_md({"mujoco": "x", "kappa": KAPPA, "D": 1.0, "ahead_at_every_n": True, "rows": [row]})
    assert md.count("\n| 16 |") == 1
