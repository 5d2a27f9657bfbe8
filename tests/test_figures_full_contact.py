"""fig07_full (issue 17 s.5): Fig. 7 past the onset -- the data only, few points, n = 16 (seconds).

Checks that the figure shows what it claims: the paper's point-contact curve is valid up to the onset and
invalid past it (judged by :func:`simgrip.reference.onset.point_contact_violations`, the onset's own test), the
full-contact reference past the onset is the tip + corner free-boundary BVP, and the MuJoCo chain with
``contact="full"`` lies within the first-order error bound of that reference at kappa = -10
(:func:`simgrip.figures.full_contact.first_order_bound`, each term derived in tests/test_full_grasp.py).
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.figures.full_contact import first_order_bound, first_order_tip_bound, full_contact_data
from simgrip.settle.full_contact import FULL_DEPTH_TOL
from simgrip.sim.scene import DEFAULT_R_LINK

N = 16
KAPPAS = (-2.0, -4.0, -6.0, -8.0, -9.0, -10.0)


@pytest.fixture(scope="module")
def data():
    return full_contact_data(kappas=KAPPAS, sim_kappas=(-6.0, -10.0), links=N, ref_links=N, shape_kappa=-10.0)


def test_point_contact_is_invalid_past_the_onset(data):
    k = data["kappa"]
    assert -8.3 < data["onset"] < -8.2  # standard case: -8.269 (simgrip.reference.onset)
    before = k > data["onset"]
    assert np.all(data["pc_valid"][before]) and not np.any(data["pc_valid"][~before])
    assert all(v for v in data["pc_violation"][~before]) and not any(data["pc_violation"][before])
    # the full-contact reference: the paper's solution before the onset, the corner BVP (valid) past it
    assert list(data["full_source"][before]) == ["point"] * int(before.sum())
    assert list(data["full_source"][~before]) == ["corner"] * int((~before).sum())
    assert np.all(data["full_valid"])
    np.testing.assert_array_equal(data["full_N"][before], data["pc_N"][before])
    # past the onset the invalid point-contact N overstates the full-contact one (the loop through the box)
    assert np.all(data["pc_N"][~before] > data["full_N"][~before])


def test_simulation_within_the_first_order_bound(data):
    ks, status = data["sim_kappa"], list(data["sim_status"])
    assert status == ["held", "held"]
    j = int(np.argmin(np.abs(ks + 10.0)))
    i = int(np.argmin(np.abs(data["kappa"] + 10.0)))
    bound = first_order_bound(N, DEFAULT_R_LINK, FULL_DEPTH_TOL)
    assert abs(data["sim_N"][j] - data["full_N"][i]) <= bound
    # the tip's height: the constrained chain's offset at n plus the depth slip and the edge's rounding
    assert abs(data["sim_h"][j] - data["full_h"][i]) <= first_order_tip_bound(N, DEFAULT_R_LINK, FULL_DEPTH_TOL)
    assert data["shape_sim"] is not None and data["shape_full"] is not None


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="sim_kappas"):
        full_contact_data(kappas=(-1.0,), sim_kappas=[-1.0] * 9)
    with pytest.raises(ValueError, match="kappas"):
        full_contact_data(kappas=(1.0,), sim_kappas=())
    with pytest.raises(ValueError, match="depth"):
        full_contact_data(kappas=(-1.0,), sim_kappas=(), depth=3.0)
