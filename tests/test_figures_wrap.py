"""fig07_wrap (issue 17 s.5, the round workpiece): the data only, two curvatures (seconds).

The paper's free rod passes through the cylinder (its curve is marked invalid there), the wrap BVP is a valid
state, and the constrained chain (the independent discrete reference) approaches it at first order or better:
the chain's contact force sits on a straight link while the BVP's is at the arc's end, an O(ds) offset
(:mod:`simgrip.reference.free_boundary`'s argument), so halving ds must shrink the tip force's error.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.figures.wrap_contact import wrap_contact_data


@pytest.fixture(scope="module")
def data():
    return {n: wrap_contact_data(kappas=(-8.0, -10.0), free_kappas=(0.0, -1.0, -2.0, -5.0, -10.0), links=n)
            for n in (16, 32)}


def test_free_rod_invalid_where_it_enters_the_cylinder(data):
    d = data[32]
    k, ok = d["kappa_free"], d["free_valid"]
    assert ok[k == 0.0].all() and not ok[k <= -2.0].any()
    assert np.all(d["wrap_valid"]) and np.all(d["arc"] > 0.2)
    assert d["shape_free"] is not None and d["shape_wrap"] is not None and d["shape_chain"] is not None


def test_chain_approaches_the_wrap_bvp(data):
    e16 = np.abs(data[16]["chain_Q"] - data[16]["Q"])
    e32 = np.abs(data[32]["chain_Q"] - data[32]["Q"])
    np.testing.assert_allclose(data[16]["Q"], data[32]["Q"], rtol=1e-6)  # the BVP does not depend on n
    assert np.all(e32 < 0.75 * e16)  # first order: 0.5 expected, 0.75 leaves room for where the arc ends fall
    assert np.all(np.abs(data[32]["chain_h"] - data[32]["h"]) < 1.0 / 32)


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="kappas"):
        wrap_contact_data(kappas=(1.0,), free_kappas=())
    with pytest.raises(ValueError, match="cylinder"):
        wrap_contact_data(kappas=(-8.0,), free_kappas=(), cylinder=(0.2, -0.2))
