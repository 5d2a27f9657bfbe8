"""The full-contact chain reference (simgrip.reference.constrained): the chain's own energy minimised by
SLSQP under non-penetration constraints, polished by a KKT Newton on the active set."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.chain import link_positions
from simgrip.reference.constrained import Box, ConstrainedEquilibrium, Cylinder, solve_constrained
from simgrip.reference.contact_geometry import self_crossing
from simgrip.reference.hinge_chain import solve_chain


@functools.lru_cache(maxsize=None)
def grip_path(grip: str, n: int, kappa: float) -> ConstrainedEquilibrium:
    """The finger closing on the box: continued in kappa from the point-contact range (cached)."""
    sign = 1.0 if grip == "II" else -1.0
    eq = None
    for k in (7.0, 8.0, 9.0, abs(kappa)):
        eq = solve_constrained(grip, STANDARD, Uniform(sign * k), n, guess=eq)
    return eq


@pytest.mark.parametrize("grip, kappa", [("I", -4.0), ("I", -6.0), ("II", 4.0)])
def test_reproduces_the_point_contact_chain_where_nothing_else_touches(grip, kappa):
    """Inside the point-contact range only the tip is active: the constrained minimiser is the hinge
    chain's equilibrium (same energy, the tip's width constraint as an inequality), to the Newton
    tolerance of both (1e-12 relative gradient: angles to ~1e-11)."""
    n = 32
    ref = solve_chain(grip, STANDARD, Uniform(kappa), n)
    eq = solve_constrained(grip, STANDARD, Uniform(kappa), n)
    assert eq.contacts == ()
    np.testing.assert_allclose(eq.link_angles, ref.link_angles, atol=1e-10)
    assert eq.N == pytest.approx(ref.N1, rel=1e-9)
    assert eq.tip_friction == -STANDARD.M
    assert eq.kkt_residual < 1e-10


def test_grip_I_at_kappa_minus_10_touches_the_top_corner():
    """Past the onset (Grip I, kappa = -10, the default box: top face 0.4 l above the tip) the
    point-contact chain crosses into the box; the constrained chain instead presses the tip on the side
    face and rests one link on the box's top corner.  Every constraint holds, the multipliers are
    positive (the corner pushes the rod out of the box: up and outwards), and the box's balance puts the
    corner's vertical force on the tip's friction."""
    eq = grip_path("I", 32, -10.0)
    ref = solve_chain("I", STANDARD, Uniform(-10.0), 32)
    assert ref.nodes[:, 0].min() < STANDARD.b / 2 - 0.1  # the point-contact loop: inside the box's width
    assert eq.kinds() == {"corner": 1}
    corner = eq.contacts[0]
    assert corner.point[0] == pytest.approx(0.3, abs=1e-12)
    assert corner.point[1] == pytest.approx(eq.tip[1] + Box().depth, abs=1e-12)
    assert corner.force[0] > 0 and corner.force[1] > 0
    assert eq.N > 0
    assert eq.tip_friction == pytest.approx(-STANDARD.M - corner.force[1], rel=1e-12)
    assert eq.tip[0] == pytest.approx(0.3, abs=1e-12)
    assert eq.kkt_residual < 1e-10
    # outside the box: every node right of the face or above the top; no crossing
    above = eq.nodes[:, 1] >= eq.tip[1] + Box().depth - 1e-12
    right = eq.nodes[:, 0] >= 0.3 - 1e-12
    assert np.all(above | right)
    assert not self_crossing(eq.nodes, 4e-3 * (1 - 1e-6))
    # the figures G's full-contact settle must meet (see the module docstring of free_boundary)
    assert eq.N == pytest.approx(19.8724, abs=1e-3)


@pytest.mark.parametrize("n", [16, 24, 32])
def test_no_link_cuts_the_box_s_corner(n):
    """From its own start (as the full-contact references call it) the chain at kappa = -10 rests a link on the
    corner; no link passes inside the box between a node on its top and one on its face.  (Such a state has every
    node outside and a lower energy: at n = 16 a host's round-off once left node 4 on the top's plane and node 5 on
    the face's just below the corner's arms, so the corner's signed distance was not applied to link 4,
    ``contact_geometry.ARM_TOL``.)"""
    eq = solve_constrained("I", STANDARD, Uniform(-10.0), n, box=Box(depth=0.4))
    assert eq.kinds() == {"corner": 1}
    top = eq.tip[1] + 0.4
    s = np.linspace(0.0, 1.0, 201)[:, None, None]
    points = (eq.nodes[:-1][None] * (1 - s) + eq.nodes[1:][None] * s).reshape(-1, 2)
    inside = (points[:, 0] < 0.3 - 1e-9) & (points[:, 1] < top - 1e-9)
    assert not inside.any(), points[inside][:3]


def test_grip_II_rests_the_box_on_its_bottom_corner():
    """Grip II at kappa = 10: the box (bottom face 0.4 l below the tip) rests on the rod at its corner,
    which pushes the rod down; the tip's friction then holds the box down (F_f > 0)."""
    eq = grip_path("II", 32, 10.0)
    assert eq.kinds() == {"corner": 1}
    assert eq.contacts[0].force[1] < 0
    assert eq.tip_friction > 0
    assert eq.N > 0


def test_a_chain_wrapped_on_a_cylinder_follows_its_curvature():
    """A free rod (kappa = -10, tighter than the surface) closing on a cylinder of radius 0.15 wraps an
    arc of it: each link of the wrapped run is tangent to the circle (distance of its line to the centre
    = R, the discrete statement of ``theta' = 1/R`` there), and the hinge curvature over the run is 1/R
    up to where in its link each tangency falls (at most one link length of arc over the run)."""
    R, n, c = 0.15, 16, np.array([0.2, -0.2])
    eq = solve_constrained("free", STANDARD, Uniform(-10.0), n, cylinder=Cylinder(*c, R))
    links = eq.contact_links("cylinder")
    run = max((list(r) for r in np.split(links, np.nonzero(np.diff(links) != 1)[0] + 1)), key=len)
    assert len(run) >= 3
    for j in run:
        a, b = eq.nodes[j], eq.nodes[j + 1]
        t = (b - a) / np.linalg.norm(b - a)
        assert abs(abs(t[0] * (c - a)[1] - t[1] * (c - a)[0]) - R) < 1e-10
    ds = 1.0 / n
    turn = eq.link_angles[run[0]] - eq.link_angles[run[-1]]
    arc = (len(run) - 1) * ds
    assert abs(turn - arc / R) <= ds / R + 1e-12


def test_free_rod_past_a_full_turn_is_a_self_touching_spiral():
    """The free rod at kappa = -9 (a full turn is 2 pi): the unconstrained chain passes through itself;
    with self-contact its turns press on each other (positive multipliers), nothing crosses."""
    n = 16
    ref = solve_chain("free", STANDARD, Uniform(-9.0), n)
    assert self_crossing(ref.nodes, 4e-3)
    eq = solve_constrained("free", STANDARD, Uniform(-9.0), n)
    assert eq.kinds().get("self", 0) >= 1
    assert not self_crossing(eq.nodes, 4e-3 * (1 - 1e-6))
    assert eq.kkt_residual < 1e-10


@pytest.mark.parametrize("kw, match", [
    (dict(grip="III"), "grip"),
    (dict(box=Box(0.3), grip="free"), "box"),
    (dict(clearance=0.5), "clearance"),
    (dict(guess=np.zeros(3)), "guess"),
    (dict(cylinder="round"), "cylinder"),
])
def test_bad_arguments_are_named(kw, match):
    args = dict(grip="I", clearance=4e-3)
    args.update(kw)
    grip = args.pop("grip")
    with pytest.raises(ValueError, match=match):
        solve_constrained(grip, STANDARD, Uniform(-4.0), 16, **args)


@pytest.mark.parametrize("bad, match", [(dict(depth=0.0), "depth"), (dict(depth=float("nan")), "depth")])
def test_box_checks_depth(bad, match):
    with pytest.raises(ValueError, match=match):
        Box(**bad)


def test_cylinder_around_the_root_is_refused():
    with pytest.raises(ValueError, match="root"):
        Cylinder(0.0, 0.0, 0.1)


def test_self_crossing_detects_a_loop():
    phi = np.linspace(0, -2.5 * np.pi, 40)
    assert self_crossing(link_positions(phi, 1 / 40), 1e-3)
    assert not self_crossing(link_positions(np.linspace(0, -np.pi, 40), 1 / 40), 1e-3)
