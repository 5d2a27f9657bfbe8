"""contact="full" (issue 17 section 2): every link and the tip may touch the workpiece, itself and the other fingers.

The checks here are independent of the settle: the candidate pairs are counted from the chain's topology, a
link's depth in the box from the capsule's sampled distance to the box in the finger's plane, and a link
through another from exact segment-segment distances of the settled centreline.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from simgrip.harness.stress import self_intersects
from simgrip.params import DimensionlessParams
from simgrip.settle import settle
from simgrip.sim.full_contact import candidate_pairs
from simgrip.sim.scene import build_scene

STD = DimensionlessParams(D=1.0, M=5.0, mu_s=1.0, b=0.6)
#: The issue's bound on a link's depth in the workpiece or in another link (over l).
PEN_BOUND = 1e-3


def _box_depth(nodes, half, zc, r, samples=256) -> float:
    """Deepest a capsule of radius ``r`` around the centreline ``nodes`` reaches into the rectangle ``|x| <= hx,
    |z - zc| <= hz`` (over l).  The rectangle's signed distance is 1-Lipschitz, so the sampled minimum along a link
    is within half a sample spacing of the true one: that half spacing is added (the bound is conservative)."""
    hx, hz = half
    worst = -math.inf
    for a, b in zip(nodes[:-1], nodes[1:]):
        t = np.linspace(0.0, 1.0, samples)[:, None]
        p = a + t * (b - a)
        dx = np.abs(p[:, 0]) - hx
        dz = np.abs(p[:, 1] - zc) - hz
        sdf = np.hypot(np.maximum(dx, 0.0), np.maximum(dz, 0.0)) + np.minimum(np.maximum(dx, dz), 0.0)
        slack = 0.5 * float(np.linalg.norm(b - a)) / (samples - 1)
        worst = max(worst, r - (float(sdf.min()) - slack))
    return max(0.0, worst)


def _segment_distance(p0, p1, q0, q1) -> float:
    """Exact distance between the planar segments ``p0 p1`` and ``q0 q1``."""
    def point_seg(x, a, b):
        ab = b - a
        t = np.clip(np.dot(x - a, ab) / max(np.dot(ab, ab), 1e-300), 0.0, 1.0)
        return float(np.linalg.norm(x - a - t * ab))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    d1, d2 = cross(q0, q1, p0), cross(q0, q1, p1)
    d3, d4 = cross(p0, p1, q0), cross(p0, p1, q1)
    if d1 * d2 < 0.0 and d3 * d4 < 0.0:
        return 0.0
    return min(point_seg(p0, q0, q1), point_seg(p1, q0, q1), point_seg(q0, p0, p1), point_seg(q1, p0, p1))


def _self_depth(nodes, r) -> float:
    """Deepest overlap (over l) of two capsules of one finger at least two links apart (``2 r`` minus their
    centrelines' distance)."""
    n = len(nodes) - 1
    worst = 0.0
    for i in range(n):
        for j in range(i + 2, n):
            d = _segment_distance(nodes[i], nodes[i + 1], nodes[j], nodes[j + 1])
            worst = max(worst, 2.0 * r - d)
    return worst


# -- the scene -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [8, 32])
def test_candidate_pairs_from_the_topology(n):
    """Self pairs: links i < j with j >= i + 2, ``(n-1)(n-2)/2``, plus the tip (on the last link) with links
    0..n-3, ``n - 2``: ``(n-2)(n+1)/2``; every link and the tip with the box: ``n + 1``."""
    sc = build_scene("I", STD, -4.0, n, contact="full")
    pairs = candidate_pairs(sc.model, sc.index.finger_of_geom)
    assert pairs["self"] == (n - 2) * (n + 1) // 2
    assert pairs["finger_workpiece"] == n + 1
    assert pairs["finger_finger"] == 0
    assert sc.model.npair == 0  # no explicit pairs: the broad phase finds the contacts


def test_two_fingers_touch_each_other():
    sc = build_scene("I", STD, -4.0, 8, contact="full", fingers=2)
    pairs = candidate_pairs(sc.model, sc.index.finger_of_geom)
    # every geom of one finger (8 links and the tip) with every geom of the other, but the two first links:
    # clamped at one point, they overlap by construction and are excluded
    assert pairs["finger_finger"] == 9 * 9 - 1


def test_the_box_is_real_and_below_the_palm():
    sc = build_scene("I", STD, -10.0, 16, contact="full")
    top = float(sc.model.body_pos[sc.workpiece_body][2] + sc.box_half[2]) / sc.length
    assert top == pytest.approx(-0.15)  # DEFAULT_BOX_GAP below the palm plane
    assert sc.box_half[0] / sc.length == pytest.approx(0.3 - sc.r_tip)  # a touching tip's centre at X = b/2
    up = build_scene("II", STD, 6.0, 16, contact="full")
    assert float(up.model.body_pos[up.workpiece_body][2] - up.box_half[2]) / up.length == pytest.approx(0.15)
    plain = build_scene("I", STD, -10.0, 16)
    assert plain.contact == "pairs" and not np.any(plain.model.geom_contype | plain.model.geom_conaffinity)


@pytest.mark.parametrize("kw, name", [
    (dict(contact="bogus"), "contact"),
    (dict(contact="full", grip="III"), "contact"),
    (dict(box_gap=0.2), "box_gap"),
    (dict(contact="full", box_gap=-1.0), "box_gap"),
])
def test_bad_arguments_are_named(kw, name):
    grip = kw.pop("grip", "I")
    with pytest.raises(ValueError, match=name):
        build_scene(grip, STD, -4.0, 8, **kw)


def test_settle_refuses_a_mismatched_contact():
    with pytest.raises(ValueError, match="contact"):
        settle(build_scene("I", STD, -4.0, 8), contact="full")
    with pytest.raises(ValueError, match="contact"):
        settle(build_scene("I", STD, -4.0, 8, contact="full"), contact="point")


# -- settled states ------------------------------------------------------------------------------------------


def _check_physical(sc, st):
    r = sc.r_link
    assert not self_intersects(st.nodes[0])
    assert _self_depth(st.nodes[0], r) <= PEN_BOUND
    if sc.has_workpiece and st.workpiece_pose is not None:
        zc = float(sc.data.xpos[sc.workpiece_body][2]) / sc.length
        half = (sc.box_half[0] / sc.length, sc.box_half[2] / sc.length)
        assert _box_depth(st.nodes[0], half, zc, r) <= PEN_BOUND


@pytest.mark.parametrize("n", [32, pytest.param(64, marks=pytest.mark.slow)])
def test_grip_i_past_the_onset_wraps_and_holds(n):
    """kappa = -10: the point-contact chain loops through itself and the box; with full contact it does neither,
    presses the face along more than its tip and holds the workpiece (mu_s N far above M = 5: the theory's
    verdict is held)."""
    sc = build_scene("I", STD, -10.0, n, contact="full")
    st = settle(sc)
    assert st.converged and st.held and getattr(st, "valid", True)
    _check_physical(sc, st)
    on_box = [c for c in st.contact_set if c["with"] == "workpiece"]
    assert on_box and all(abs(c["point"][0] - 0.3) <= 2 * sc.r_link for c in on_box)  # on the side face
    assert any(c["arc_length"] < 1.0 - 1.0 / n for c in on_box)  # not (only) the tip
    assert st.N2 == pytest.approx(-5.0, rel=1e-3)  # friction carries the weight M (dynamics creep ~1e-5)
    assert STD.mu_s * st.normal_force > 5.0


def test_free_rod_curls_into_a_self_touching_spiral():
    """kappa = -9 turns the rest shape by 9 rad, more than a full turn: the rod must touch itself."""
    sc = build_scene("free", STD, -9.0, 32, contact="full")
    st = settle(sc)
    assert st.converged
    assert any(c["with"] == "self" for c in st.contact_set)
    _check_physical(sc, st)
    assert np.ptp(st.link_angles[0]) > 2 * math.pi  # it does turn more than once


# -- the JSON record -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("extra", [[], ["--contact", "surface"], ["--contact", "full"]])
def test_simulate_json_has_nodes_and_contacts(extra, capsys):
    from simgrip.cli import main

    n = 16
    assert main(["simulate", "I", "--kappa", "-6", "--links", str(n), "--json", *extra]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert np.asarray(rec["nodes"]).shape == (1, n + 1, 2)
    assert rec["nodes"][0][0] == [0.0, 0.0]
    assert rec["nodes"][0][-1] == pytest.approx(rec["tip"])
    assert rec["held"] and rec["contacts"]
    total = np.zeros(2)
    for c in rec["contacts"]:
        assert {"finger", "link", "arc_length", "with", "point", "normal", "normal_force", "friction_force"} <= set(c)
        assert c["with"] == "workpiece" and 0 <= c["link"] < n and 0.0 <= c["arc_length"] <= 1.0
        assert c["normal_force"] >= 0.0 and math.hypot(*c["normal"]) == pytest.approx(1.0)
        total += np.asarray(c["force"])
    # the contacts' forces add up to the record's (the workpiece's force on the finger)
    assert total == pytest.approx([rec["N1"], rec["N2"]], rel=1e-6, abs=1e-9)


def test_simulate_table_counts_contacts(capsys):
    from simgrip.cli import main

    assert main(["simulate", "free", "--kappa", "-9", "--links", "16", "--contact", "full"]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("contacts"))
    assert "self" in line and "nodes" not in out


# -- K fingers -----------------------------------------------------------------------------------------------


def _capsule_gap(p0, p1, q0, q1, samples=64) -> float:
    """Distance between the 3-D segments ``p0 p1`` and ``q0 q1`` from a sampled first one (each sample's exact
    distance to the second; the distance is 1-Lipschitz along the first, so half a spacing is subtracted)."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    p = p0 + t * (p1 - p0)
    ab = q1 - q0
    u = np.clip(((p - q0) @ ab) / max(float(ab @ ab), 1e-300), 0.0, 1.0)[:, None]
    d = np.linalg.norm(p - (q0 + u * ab), axis=1)
    return float(d.min()) - 0.5 * float(np.linalg.norm(p1 - p0)) / (samples - 1)


def _check_gripper_physical(st, rec, n, r):
    nodes = np.asarray(rec["nodes"])
    assert nodes.shape == (st.fingers, n + 1, 3)
    # no capsule through another: every pair of links of different fingers (but the clamped first links) and
    # of one finger at least two apart stays 2 r apart, less the bound
    for a in range(st.fingers):
        for b in range(a, st.fingers):
            for i in range(n):
                for j in range(i + 2 if a == b else 0, n):
                    if a != b and i + j == 0:
                        continue  # both first links start at the common clamp (excluded from contact)
                    gap = _capsule_gap(nodes[a, i], nodes[a, i + 1], nodes[b, j], nodes[b, j + 1])
                    assert gap >= 2 * r - PEN_BOUND, (a, i, b, j, gap)
    return nodes


def test_three_fingers_hold_a_sphere_below_the_palm():
    """K = 3 around a sphere (diameter b) below the palm, kappa = -6: held, no finger through another or the
    sphere (every capsule point at least R + r_link - 1e-3 l from its centre), equal shares."""
    from simgrip.gripper import gripper_record, simulate_gripper

    n, r = 16, 2e-3
    st = simulate_gripper("I", STD, -6.0, n, fingers=3, workpiece="sphere", contact="full")
    rec = gripper_record(st, STD)
    assert st.converged and st.held and getattr(st, "valid", True)
    nodes = _check_gripper_physical(st, rec, n, r)
    c = np.asarray(st.workpiece_position)
    for f in range(3):
        for i in range(n):
            t = np.linspace(0.0, 1.0, 64)[:, None]
            p = nodes[f, i] + t * (nodes[f, i + 1] - nodes[f, i])
            slack = 0.5 * float(np.linalg.norm(nodes[f, i + 1] - nodes[f, i])) / 63
            assert float(np.linalg.norm(p - c, axis=1).min()) - slack >= 0.3 - 2e-3 + r - PEN_BOUND
    on = [x for x in rec["contacts"] if x["with"] == "workpiece"]
    per = [sum(x["normal_force"] for x in on if x["finger"] == k) for k in range(3)]
    assert min(per) > 0.0 and per == pytest.approx([per[0]] * 3, rel=1e-2)
    _check_balance(st, rec)


def _check_balance(st, rec):
    """The workpiece's balance from every contact (its rows of MuJoCo's residual: within the settle's tolerance):
    the fingers' vertical resultants add up to the weight K M, and share it equally (the scene is symmetric under a
    turn by 2 pi / K; the same 1e-2 as the normal forces')."""
    assert np.max(np.abs(rec["force_balance"])) <= st.tolerance
    shares = [f["friction_force"] for f in rec["fingers"]]
    assert sum(shares) == pytest.approx(-st.fingers * STD.M, abs=st.tolerance)
    assert shares == pytest.approx([shares[0]] * st.fingers, rel=1e-2)


def test_three_fingers_wrap_a_cylinder():
    """K = 3 around a cylinder below the palm: held, the fingers touch the cylinder along more than their tips,
    no finger crosses itself or another, none enters the cylinder; the three fingers carry equal shares."""
    from simgrip.gripper import gripper_record, simulate_gripper

    n, r = 16, 2e-3
    st = simulate_gripper("I", STD, -8.0, n, fingers=3, workpiece="cylinder", contact="full")
    rec = gripper_record(st, STD)
    assert st.converged and st.held and getattr(st, "valid", True)
    nodes = _check_gripper_physical(st, rec, n, r)
    # none inside the cylinder (radius b/2 - r_tip, vertical axis through its centre)
    c = np.asarray(st.workpiece_position)
    radial = np.hypot(nodes[..., 0] - c[0], nodes[..., 1] - c[1])
    below_top = nodes[..., 2] < c[2] + 1.0  # the cylinder is BOX_HEIGHT = 2 l tall
    assert np.all(radial[below_top] >= 0.3 - 2e-3 + r - PEN_BOUND)
    on = [x for x in rec["contacts"] if x["with"] == "workpiece"]
    assert {x["finger"] for x in on} == {0, 1, 2}
    assert any(x["arc_length"] < 1.0 - 1.0 / n for x in on)  # wrapping: more than the tips
    per = [sum(x["normal_force"] for x in on if x["finger"] == k) for k in range(3)]
    assert per == pytest.approx([per[0]] * 3, rel=1e-2)  # the scene is symmetric under a turn by 120 degrees
    _check_balance(st, rec)


def test_gripper_json_has_nodes_and_contacts(capsys):
    from simgrip.cli import main

    n = 8
    assert main(["simulate", "I", "--kappa", "-6", "--links", str(n), "--fingers", "3", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    nodes = np.asarray(rec["nodes"])
    assert nodes.shape == (3, n + 1, 3) and np.allclose(nodes[:, 0], 0.0)
    assert len(rec["contacts"]) == 3 and all(c["link"] == n - 1 for c in rec["contacts"])


# -- the independent reference: the chain's energy minimised under non-penetration (SLSQP) -------------------


def test_free_spiral_is_the_constrained_energy_minimum():
    """The settled spiral (kappa = -9, n = 32) is a KKT point of the chain's own energy with every pair of
    non-adjacent links kept 2 r_link apart (:func:`simgrip.reference.constrained.solve_constrained`, SciPy's
    SLSQP and an active-set KKT polish, no MuJoCo): started from the settled angles it stays there, with the
    same contacts and forces.

    Tolerance (derived): the settle stops at MuJoCo's static residual ``tol = DYN_TOL`` (1e-5 per hinge, over
    rho g l^2), which moves the angles by at most ``sqrt(n) tol / lambda_min`` (``lambda_min`` ~ 2.4, the
    chain's smallest stability eigenvalue here: 7e-5 rad); its soft contacts sit ``p <= 2e-6 l`` deep, which
    turns a link by at most ``2 p / ds`` (1.3e-4 rad at n = 32).  Forces: MuJoCo splits a node's contact in two
    (the tip sphere and the last capsule, or the two capsules meeting at a node), so they are summed per pair of
    places; the same residual bounds their difference relative to their size (1e-5 / 0.5, 1e-3 with margin).
    """
    constrained = pytest.importorskip("simgrip.reference.constrained")
    n = 32
    sc = build_scene("free", STD, -9.0, n, contact="full")
    st = settle(sc)
    ref = constrained.solve_constrained("free", STD, -9.0, n, guess=st.link_angles[0])
    assert ref.kkt_residual < 1e-10
    bound = math.sqrt(n) * 1e-5 / 2.4 + 2.0 * max(st.penetration, 2e-6) * n
    assert np.max(np.abs(st.link_angles[0] - ref.link_angles)) <= bound
    sim_total = sum(c["normal_force"] for c in st.contact_set)
    ref_total = sum(float(np.linalg.norm(c.force)) for c in ref.contacts)
    assert sim_total == pytest.approx(ref_total, rel=1e-3)


def test_below_the_onset_full_contact_is_the_tip_contact():
    """kappa = -6 (inside the paper's point-contact range): every link may touch, but only the tip does, and the
    state is the static settle's with the same surface contact (``contact="surface"``, Newton).

    Tolerance (derived): the dynamics stops at MuJoCo's residual ``DYN_TOL = 1e-5`` (over rho g l) and its tip
    sits ``p <= 1e-4 l`` (:data:`~simgrip.settle.full_contact.FULL_PEN_LIMIT`) deeper in the face than Newton's
    ``~1e-6 l``; the finger's tip stiffness ``dN/dX`` is of order ``10 EI / l^3`` (D = 1), so ``|dN| <= 10 p + 1e-5``
    = 1e-3 rho g l: 1.3e-4 of N = 7.8; the tip moves by ``p``.
    """
    n = 32
    ref = settle(build_scene("I", STD, -6.0, n), contact="surface")
    st = settle(build_scene("I", STD, -6.0, n, contact="full"))
    assert st.held and ref.held
    assert {(c["link"], c["arc_length"]) for c in st.contact_set} == {(n - 1, 1.0)}
    assert st.normal_force == pytest.approx(ref.normal_force, rel=1.3e-4)
    assert np.max(np.abs(st.tip[0] - ref.tip[0])) <= 1e-4
