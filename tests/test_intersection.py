"""simgrip.intersection and simgrip.validity's chain checks against hand-computed geometry (issue 17, section 1)."""

import math

import numpy as np
import pytest

from simgrip import intersection as isect
from simgrip.validity import (DEPTH_FRACTION, SELF_LIMIT_FACTOR, Solid, chain_violations, self_gap_links)

# --- segment-segment distance -------------------------------------------------------------------------------


@pytest.mark.parametrize("p0,p1,q0,q1,want", [
    ((0, 0), (1, 0), (0, 1), (1, 1), 1.0),                      # parallel, overlapping
    ((0, 0), (1, 0), (2, 1), (3, 1), math.sqrt(2.0)),           # parallel, end to end
    ((0, 0), (2, 2), (0, 2), (2, 0), 0.0),                      # a proper crossing
    ((0, 0), (1, 0), (1, 0), (2, 5), 0.0),                      # sharing an end
    ((0, 0), (1, 0), (0.5, 0.3), (0.5, 0.3), 0.3),              # a point (zero-length segment)
    ((0, 0, 0), (1, 0, 0), (0.5, -1, 1), (0.5, 1, 1), 1.0),     # skew lines, closest points inside both
    ((0, 0, 0), (1, 0, 0), (3, -1, 4), (3, 1, 4), math.sqrt(20.0)),  # skew, closest at an end: (1,0,0)-(3,0,4)
    ((0.5, 0.3), (0.5, 0.3), (0, 0), (1, 0), 0.3),              # the point first
])
def test_segment_distance_hand_cases(p0, p1, q0, q1, want):
    d = isect.segment_distances(*(np.array([v], dtype=float) for v in (p0, p1, q0, q1)))
    assert d[0] == pytest.approx(want, abs=1e-12)


def test_segment_distance_is_the_least_over_samples():
    """Against the least of 201 x 201 samples: never above it, and within the samples' spacing (h/2 each)."""
    rng = np.random.default_rng(1)
    p0, q0 = rng.normal(size=(100, 3)), rng.normal(size=(100, 3))
    p1, q1 = p0 + rng.normal(size=(100, 3)), q0 + rng.normal(size=(100, 3))
    d = isect.segment_distances(p0, p1, q0, q1)
    t = np.linspace(0.0, 1.0, 201)
    P = p0[:, None] + t[None, :, None] * (p1 - p0)[:, None]
    Q = q0[:, None] + t[None, :, None] * (q1 - q0)[:, None]
    brute = np.linalg.norm(P[:, :, None] - Q[:, None, :], axis=3).min(axis=(1, 2))
    step = (np.linalg.norm(p1 - p0, axis=1) + np.linalg.norm(q1 - q0, axis=1)) / 200
    assert np.all(d <= brute + 1e-12) and np.all(brute - d <= step)


# --- crossings and close pairs ------------------------------------------------------------------------------


def test_crossing_pairs_of_a_loop():
    """A polyline that loops back over its start: links 0 and 3 cross at (0.5, 0); touching ends do not count."""
    nodes = np.array([[0, 0], [1, 0], [1, 1], [0.5, 1], [0.5, -1]], dtype=float)
    i, j = isect.crossing_pairs(nodes)
    assert list(zip(i, j)) == [(0, 3)]
    touching = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)  # a closed square: ends meet
    assert isect.crossing_pairs(touching)[0].size == 0


def test_close_link_pairs_of_a_hairpin():
    """Two straight runs 0.1 apart joined by a turn: the links facing each other are 0.1 apart."""
    run = np.linspace(0.0, 1.0, 11)
    out = np.stack([run, np.zeros_like(run)], axis=1)
    back = np.stack([run[::-1], np.full_like(run, 0.1)], axis=1)
    nodes = np.vstack([out, back])  # 22 nodes, link 10 is the turn
    i, j, d = isect.close_link_pairs(nodes, 0.1 + 1e-9, min_gap=2)
    assert np.allclose(d, 0.1)  # link k faces link 20 - k, and touches its neighbours' shared x at 0.1 too
    assert {(k, 20 - k) for k in range(10)} <= set(zip(i.tolist(), j.tolist()))
    assert isect.close_link_pairs(nodes, 0.1 - 1e-9, min_gap=2)[0].size == 0


# --- signed distances ---------------------------------------------------------------------------------------


def test_sdf_hand_cases():
    h = np.array([1.0, 0.5])
    assert isect.box_sdf(np.array([0.0, 0.0]), h) == pytest.approx(-0.5)
    assert isect.box_sdf(np.array([2.0, 1.5]), h) == pytest.approx(math.sqrt(2.0))
    assert isect.box_sdf(np.array([0.0, 0.8]), h) == pytest.approx(0.3)
    assert isect.cylinder_sdf(np.array([0.0, 0.0, 0.0]), 1.0, 2.0) == pytest.approx(-1.0)
    assert isect.cylinder_sdf(np.array([2.0, 0.0, 3.0]), 1.0, 2.0) == pytest.approx(math.sqrt(2.0))
    assert isect.cylinder_sdf(np.array([0.0, 0.3, 1.9]), 1.0, 2.0) == pytest.approx(-0.1)
    assert isect.sphere_sdf(np.array([3.0, 4.0, 0.0]), 2.0) == pytest.approx(3.0)


@pytest.mark.parametrize("a,b,want", [
    ((-2, 0), (2, 0), -0.5),                  # through the centre: half the height deep
    ((-3, 1), (3, 1), 0.5),                   # above the top face
    ((2, 0), (0, 2), 0.0),                    # x + y = 2 passes through the corner (1, 1)... half (1, 1)
    ((3, 0), (0, 3), 1 / math.sqrt(2.0)),     # x + y = 3: the corner's distance to the line
])
def test_segment_box_sdf_hand_cases(a, b, want):
    half = np.array([1.0, 0.5]) if want in (-0.5, 0.5) else np.array([1.0, 1.0])
    v, _ = isect.segment_box_sdf_2d(np.array([a], float), np.array([b], float), half)
    assert v[0] == pytest.approx(want, abs=1e-12)


def test_golden_section_agrees_with_the_exact_planar_minimum():
    """segment_min_sdf (any convex solid) against segment_box_sdf_2d (exact): 48 golden steps leave 0.618^48 ~ 1e-10
    of the segment, and the signed distance is 1-Lipschitz, so they agree to 1e-9 (segments up to ~1.7 long)."""
    rng = np.random.default_rng(2)
    a = rng.uniform(-2, 2, (500, 2))
    b = a + rng.uniform(-1, 1, (500, 2))
    h = np.array([0.7, 0.3])
    exact, _ = isect.segment_box_sdf_2d(a, b, h)
    golden, _ = isect.segment_min_sdf(lambda p: isect.box_sdf(p, h), a, b)
    assert np.max(np.abs(exact - golden)) < 1e-9
    t = np.linspace(0.0, 1.0, 2001)
    brute = isect.box_sdf(a[:, None] + t[None, :, None] * (b - a)[:, None], h).min(axis=1)
    assert np.all(exact <= brute + 1e-12)


# --- the chain checks on hand-made shapes -------------------------------------------------------------------


def _arc(turn: float, n: int, length: float = 1.0) -> np.ndarray:
    """Nodes of a uniform arc (curvature turn/length) from the origin along +x, curling down."""
    phi = -turn * (np.arange(n) + 0.5) / n
    steps = length / n * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    return np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])


def test_self_gap_links():
    """pi r_link n links apart at least (2 when that is less): n = 32, r = 2e-3: pi r n = 0.2 -> 2; n = 256: 1.6 -> 3."""
    assert self_gap_links(32, 2e-3) == 2
    assert self_gap_links(256, 2e-3) == 3
    assert self_gap_links(1000, 0.01) == 1 + math.ceil(math.pi * 10)


@pytest.mark.parametrize("n", [32, 256])
def test_an_arc_below_a_full_turn_is_valid_and_beyond_it_is_not(n):
    r = 2e-3
    assert chain_violations([_arc(5.5, n)], [_arc(5.5, n)], r_link=r, r_tip=None, solid=None) == []
    ((_, msg),) = chain_violations([_arc(7.0, n)], [_arc(7.0, n)], r_link=r, r_tip=None, solid=None)
    assert "crosses itself" in msg or "closer than their capsules allow" in msg


def test_capsules_overlap_limit_is_two_radii_less_the_allowed_depth():
    """Parallel runs (1.5 - 0.01) r apart are flagged, (1.5 + 0.01) r apart are not: (2 - DEPTH_FRACTION) r."""
    r = 2e-3
    assert SELF_LIMIT_FACTOR == 2.0 - DEPTH_FRACTION
    for gap, bad in ((SELF_LIMIT_FACTOR - 0.01) * r, True), ((SELF_LIMIT_FACTOR + 0.01) * r, False):
        # out along y = 0, round a wide detour (no tight turn), back along y = -gap
        nodes = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0], [0.3, 0.0], [0.4, 0.0], [0.4, -0.2], [0.3, -0.2],
                          [0.3, -gap], [0.2, -gap], [0.1, -gap], [0.0, -gap]])
        found = chain_violations([nodes], [nodes], r_link=r, r_tip=None, solid=None)
        assert bool(found) is bad, (gap, found)


def test_a_link_through_the_box_is_found_and_one_beside_it_is_not():
    r = 2e-3
    box = Solid("box", np.array([0.0, -0.5]), np.eye(2), np.array([0.3, 0.5]))
    inside = np.array([[0.5, 0.0], [0.5, -0.2], [0.2, -0.3], [0.1, -0.5]])  # links 1, 2 cross x = 0.3
    ((_, msg),) = chain_violations([inside], [inside], r_link=r, r_tip=None, solid=box)
    assert "link(s) 1-2 inside the workpiece" in msg and "link 2" in msg
    # a rod along the face at (1 - DEPTH_FRACTION) r + 1e-6 from it: legitimately near, not flagged
    x = 0.3 + (1.0 - DEPTH_FRACTION) * r + 1e-6
    beside = np.array([[x, 0.0], [x, -0.3], [x, -0.6]])
    assert chain_violations([beside], [beside], r_link=r, r_tip=None, solid=box) == []
    x = 0.3 + (1.0 - DEPTH_FRACTION) * r - 1e-6
    closer = np.array([[x, 0.0], [x, -0.3], [x, -0.6]])
    assert chain_violations([closer], [closer], r_link=r, r_tip=None, solid=box)


def test_a_tip_pressed_on_the_face_is_valid_until_its_centre_is_inside():
    """The tip sphere carries the contact: its depth is check_contact_depth's; only its centre inside is invalid."""
    r, rt = 2e-3, 2e-3
    box = Solid("box", np.array([0.0, -0.5]), np.eye(2), np.array([0.3, 0.5]))
    for tip_x, bad in ((0.3 + 0.5 * rt, False), (0.3 - 1e-4, True)):
        nodes = np.array([[0.5, 0.0], [0.6, -0.2], [tip_x, -0.3]])
        found = chain_violations([nodes], [nodes], r_link=r, r_tip=rt, solid=box)
        assert bool(found) is bad and (not bad or "tip sphere's centre" in found[-1][1])


def test_two_fingers_crossing_each_other():
    """Mirrored fingers: one that curls past the palm axis into the other is found; two apart are not."""
    r = 2e-3
    a = _arc(2.0, 32)
    mirror = a * np.array([-1.0, 1.0])
    assert chain_violations([a, a], [a, mirror], r_link=r, r_tip=None, solid=None) == []
    through = _arc(4.5, 32)  # curls back past x = 0 at the level of ...
    through_m = through * np.array([-1.0, 1.0])
    found = chain_violations([through, through], [through, through_m], r_link=r, r_tip=None, solid=None)
    assert any(k == "fingers" and "pass through each other" in m for k, m in found)


def test_clipped_solid_keeps_the_far_side():
    box = Solid("box", np.array([0.0, 0.0]), np.eye(2), np.array([1.0, 1.0]))
    top = box.clipped(hi=0.2)
    assert np.allclose(top.half, [1.0, 0.6]) and np.allclose(top.centre, [0.0, -0.4])
    assert box.clipped(lo=2.0) is None


def test_solid_segment_sdf_bound_is_exact_below_the_cut():
    """segment_sdf(below=c): exact wherever the value is under c, a lower bound (>= c) elsewhere."""
    rng = np.random.default_rng(3)
    a = rng.uniform(-2, 2, (400, 2))
    b = a + rng.uniform(-0.3, 0.3, (400, 2))
    box = Solid("box", np.array([0.1, -0.2]), np.eye(2), np.array([0.7, 0.3]),
                np.array([[0.7, -0.3], [-0.7, -0.3]]), 0.05)
    exact = box.segment_sdf(a, b)
    cut = box.segment_sdf(a, b, below=0.2)
    low = exact < 0.2
    assert np.array_equal(cut[low], exact[low]) and np.all(cut[~low] >= 0.2 - 1e-12) and np.all(cut <= exact + 1e-12)
