"""The hinge-chain discretisation (springs and rest angles)."""

import numpy as np
import pytest

from simgrip.chain import chain_springs, check_links, link_positions
from simgrip.profiles import Concentrated, Uniform


def test_springs_for_uniform_curvature():
    c = chain_springs(Uniform(-2.0), 8)
    ds = 1 / 8
    assert c.stiffness[0] == 2 / ds and np.all(c.stiffness[1:] == 1 / ds)
    np.testing.assert_allclose(c.rest[0], -2.0 * ds / 2, rtol=1e-15)
    np.testing.assert_allclose(c.rest[1:], -2.0 * ds, rtol=1e-14)


def test_rest_angles_add_up_to_the_curvature_up_to_the_last_midpoint():
    # hinges own [0, l - ds/2]; the last half cell is moment free
    p = Concentrated(6.0, 2.0, -1)
    c = chain_springs(p, 16)
    assert np.isclose(c.rest.sum(), p.integral(0.0, 1 - 0.5 / 16), rtol=1e-13)


def test_straight_chain_positions():
    nodes = link_positions(np.zeros(4), 0.25)
    np.testing.assert_allclose(nodes[:, 0], np.linspace(0, 1, 5))
    assert np.all(nodes[:, 1] == 0)


@pytest.mark.parametrize("n", [1, 0, -3, 2.5, "x", None])
def test_too_few_links_named(n):
    with pytest.raises(ValueError, match="links"):
        check_links(n)
