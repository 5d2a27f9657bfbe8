"""contact="full" Grip I grasped at a depth (issue 17 s.4): the MuJoCo chain against the free-boundary elastica.

The reference is helper H's free-boundary BVP (:data:`simgrip.reference.free_boundary.GRIP_I_KAPPA_M10`: the box
hangs on the sticking tip, its top edge ``depth = 0.4`` above it, every other contact frictionless; N = 19.88035
at kappa = -10).  The scene solves the same problem with ``build_scene(..., contact="full", box_depth=0.4)``
(friction at the tip only by default, :func:`simgrip.sim.full_contact.check_grasp`).

Error budget of |N - N_BVP| (each term derived or measured on the independent reference, not on the settle):

* discretisation: the corner touches a straight link, so the chain is first order in ds; H's bound on the
  constrained chain, ``|dN/dtilt| |theta'(gamma)| ds = 1.73 ds`` (:mod:`simgrip.reference.free_boundary`);
* the depth the settle ends at: ``|dN/d depth| |depth - 0.4|`` with ``|dN/d depth| = 56`` (the constrained
  chain at n = 16: N = 19.93616 at depth 0.39948, 19.95012 at 0.39923);
* the corner's rounding: MuJoCo's capsule (radius ``r``) meets the box's edge; the centreline model's corner is
  the sharp ``(b/2, top + r)``.  Along the corner force's direction ``(n_x, n_y)`` they differ by
  ``r (n_x + n_y - 1) <= r (sqrt 2 - 1)``, a change of the depth by that over ``n_y`` (>= 0.8 here: the force
  is within 37 degrees of vertical, BVP (5.54, 9.61)): ``|dN/d depth| r (sqrt 2 - 1) / 0.8``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip.params import DimensionlessParams
from simgrip.reference.free_boundary import GRIP_I_KAPPA_M10
from simgrip.settle import settle
from simgrip.settle.full_contact import FULL_DEPTH_TOL, grasp_depth
from simgrip.sim.scene import build_scene

STD = DimensionlessParams(D=1.0, M=5.0, mu_s=1.0, b=0.6)
DEPTH = 0.4
#: |dN/d depth| of the Grip I kappa -10 corner grasp (module docstring).
DN_DDEPTH = 56.0


def _bvp_n() -> float:
    return float(GRIP_I_KAPPA_M10["bvp"]["N"])


def _tip_forces(sc, st):
    """(N, friction) of the contacts at the tip (the sphere and the last capsule's end), and the others."""
    tip = np.asarray(st.nodes[0][-1])
    at_tip, others = [], []
    for c in st.contact_set:
        if c["with"] != "workpiece":
            continue
        (at_tip if math.dist(c["point"], tip) < 3 * sc.r_tip else others).append(c)
    return (sum(c["normal_force"] for c in at_tip), sum(c["friction_force"] for c in at_tip)), others


@pytest.fixture(scope="module")
def grasps():
    out = {}
    for n in (16, 32, 64, 128):
        sc = build_scene("I", STD, -10.0, n, contact="full", box_depth=DEPTH)
        st = settle(sc)
        out[n] = (sc, st)
    return out


@pytest.mark.parametrize("n", [16, 32, 64, 128])
def test_grip_i_grasped_at_depth_is_the_free_boundary_solution(grasps, n):
    sc, st = grasps[n]
    assert st.converged and st.held and not st.warnings
    depth = grasp_depth(sc)
    assert abs(depth - DEPTH) <= FULL_DEPTH_TOL
    (N, friction), others = _tip_forces(sc, st)
    # the contact set the BVP has: the tip on the face and the box's top edge on the rod, nothing else
    assert len(others) == 1
    top = depth + float(st.nodes[0][-1][1])  # the centreline's top edge
    assert others[0]["point"][0] == pytest.approx(0.3 - sc.r_tip, abs=1e-9 + 2 * sc.r_link)
    assert others[0]["point"][1] == pytest.approx(top - sc.r_link, abs=2 * sc.r_link)
    assert abs(others[0]["friction_force"]) <= 1e-12 * others[0]["normal_force"]  # frictionless (condim 1)
    # the box hangs on the tip's friction: F_f = -M - (the edge's vertical force on the rod), in the cone
    assert friction == pytest.approx(-STD.M - others[0]["force"][1], abs=1e-3 * STD.M)
    assert abs(friction) <= STD.mu_s * N
    bound = 1.73 / n + DN_DDEPTH * abs(depth - DEPTH) + DN_DDEPTH * sc.r_link * (math.sqrt(2) - 1) / 0.8
    assert abs(N - _bvp_n()) <= bound
    if n == 64:  # the target
        assert abs(N - _bvp_n()) <= 0.01 * _bvp_n()


def test_the_error_falls_with_ds(grasps):
    """First order plus the resolution-independent rounding term: each halving of ds lowers the error (measured
    0.18, 0.091, 0.060, 0.013 at n = 16 ... 128; the depth's slip, up to 8e-4 l, moves each by up to 0.045)."""
    errs = [abs(_tip_forces(*grasps[n])[0][0] - _bvp_n()) for n in (16, 32, 64, 128)]
    assert errs[0] > errs[1] > errs[2] > errs[3]


@pytest.mark.parametrize("kw,name", [
    ({"box_depth": 0.0}, "box_depth"), ({"box_depth": -0.1}, "box_depth"), ({"box_depth": 1.5}, "box_depth"),
    ({"box_depth": float("nan")}, "box_depth"), ({"box_depth": "deep"}, "box_depth"),
    ({"box_depth": True}, "box_depth"), ({"extra_friction": 1}, "extra_friction"),
    ({"extra_friction": "no"}, "extra_friction"),
])
def test_bad_grasp_arguments_are_named(kw, name):
    with pytest.raises(ValueError, match=name):
        build_scene("I", STD, -10.0, 8, contact="full", **kw)


@pytest.mark.parametrize("kw,name", [
    ({"box_depth": 0.4}, "box_depth"), ({"extra_friction": False}, "extra_friction"),
])
def test_grasp_arguments_need_full_contact(kw, name):
    with pytest.raises(ValueError, match=name):
        build_scene("I", STD, -6.0, 8, **kw)
    if name == "box_depth":
        with pytest.raises(ValueError, match=name):
            build_scene("free", STD, -6.0, 8, contact="full", **kw)


def test_grasp_defaults():
    """Grasped at a depth, only the tip has friction (the determinate problem); otherwise every contact does."""
    a = build_scene("I", STD, -10.0, 8, contact="full", box_depth=0.4)
    b = build_scene("I", STD, -10.0, 8, contact="full")
    c = build_scene("II", STD, 6.0, 8, contact="full", box_depth=0.3, extra_friction=True)
    assert (a.box_depth, a.extra_friction) == (0.4, False)
    assert (b.box_depth, b.extra_friction) == (None, True)
    assert (c.box_depth, c.extra_friction) == (0.3, True)


@pytest.mark.parametrize("argv,option", [
    (["--box-depth", "0.4"], "--box-depth"), (["--contact", "full", "--box-depth", "2"], "--box-depth"),
    (["--contact", "full", "--box-depth", "nan"], "--box-depth"), (["--extra-friction", "off"], "--extra-friction"),
])
def test_cli_grasp_options_named(argv, option, capsys):
    from simgrip.cli import main

    assert main(["simulate", "I", "--kappa", "-10", "--links", "8", *argv]) == 2
    err = capsys.readouterr().err
    assert option in err and len(err.strip().splitlines()) == 1


def test_compare_full_uses_the_free_boundary_reference(capsys):
    """compare --contact full --box-depth: the tip's N and friction against the free-boundary BVP (at n = 16 its
    error budget above), the resultant kept beside them."""
    import json

    from simgrip.cli import main

    assert main(["compare", "I", "--kappa", "-10", "--links", "16", "--contact", "full", "--box-depth", "0.4",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sim, ref = out["simulation"], out["reference"]
    assert "free-boundary" in ref["source"] and ref["contact_set"].startswith("tip + corner")
    assert ref["normal_force"] == pytest.approx(_bvp_n(), rel=1e-6)
    bound = 1.73 / 16 + DN_DDEPTH * FULL_DEPTH_TOL + DN_DDEPTH * 2e-3 * (math.sqrt(2) - 1) / 0.8
    assert abs(sim["normal_force"] - ref["normal_force"]) <= bound
    assert sim["resultant_friction_force"] == pytest.approx(-STD.M, rel=1e-3)  # the whole box on the finger
    assert sim["feasible"] and ref["feasible"] and not out["warnings"]
