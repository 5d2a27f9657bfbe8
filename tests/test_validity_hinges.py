"""A hinge turned by half a turn or more is an impossible state (:mod:`simgrip.validity_hinges`): the one a
chain's nodes cannot show.  Found by trying the commands as a hostile user would: ``simgrip simulate I --kappa
-55.27 --links 8`` (each hinge at rest at -6.9 rad, a whole turn and 0.6 rad) was reported held, feasible and
valid, N = 19.5, while the BVP failed."""

from __future__ import annotations

import math

import numpy as np

from simgrip.chain import link_positions
from simgrip.compare import simulate
from simgrip.params import STANDARD
from simgrip.validity_hinges import folded_hinges


def test_the_nodes_cannot_tell_a_whole_turn():
    """Why the node checks miss it: the same nodes for a hinge at ``phi`` and at ``phi - 2 pi``."""
    q = np.array([-0.3, -0.5, -0.5, -0.5])
    wound = q.copy()
    wound[2] -= 2 * math.pi
    nodes = link_positions(np.cumsum(q), 0.25)
    assert np.allclose(link_positions(np.cumsum(wound), 0.25), nodes, atol=1e-14)
    assert folded_hinges(q) == []
    (kind, message), = folded_hinges(wound)
    assert kind == "folded" and "finger 0: hinge 2 turned -6.78 rad" in message


def test_the_threshold_is_half_a_turn_and_the_clamp_is_not_a_fold():
    pi = math.pi
    assert folded_hinges([[0.0, pi - 1e-12, 0.0]]) == []
    assert len(folded_hinges([[0.0, -pi, 0.0]])) == 1
    assert folded_hinges([[4.0, 0.1, 0.1]]) == []  # the clamp hinge: the palm and the first link
    found = folded_hinges([[0.0, 0.1], [0.0, 3.5], [0.0, -3.2]])
    assert [m.split(":")[0] for _, m in found] == ["finger 1", "finger 2"]
    (_, m), = folded_hinges([[0.0, 3.2, -3.9, 3.3]])
    assert "hinge 2 (and 2 more) turned -3.9 rad" in m


def test_a_wound_chain_is_not_reported_held():
    """The case found: every hinge of the 8-link chain wound past half a turn (nearly a whole one).  Settled, it looks like a
    gently curved finger holding the box (its node checks pass); it is now invalid, not held, and says why."""
    s = simulate("I", STANDARD, -55.2654824574, 8)
    assert np.all(np.abs(s.joint_angles[0, 1:]) > math.pi)
    assert not s.valid and not s.held
    assert any("half a turn or more" in w for w in s.warnings)
    ok = simulate("I", STANDARD, -5.5, 8)  # the paper's standard case at the same links: untouched
    assert ok.valid and ok.held and not any("half a turn" in w for w in ok.warnings)
