"""The full-contact static settle (:mod:`simgrip.settle.full_newton`, :mod:`simgrip.settle.full_routes`, issue 17
s.2 and s.5): the same rest states as the guarded dynamics where point contact applies, the free-boundary
verdicts past the onset, the dynamics as the fallback.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import simgrip.settle.full_contact as full_contact
from simgrip.params import DimensionlessParams
from simgrip.settle import settle
from simgrip.settle.dynamics import DYN_TOL
from simgrip.settle.full_contact import FULL_DEPTH_TOL, FULL_PEN_LIMIT, grasp_depth
from simgrip.settle.full_newton import FullNewton
from simgrip.sim.scene import build_scene

STD = DimensionlessParams(D=1.0, M=5.0, mu_s=1.0, b=0.6)

#: The free-boundary BVP (:mod:`simgrip.reference.free_boundary`, tip + box corner, depth 0.4, standard case),
#: measured with ``simgrip solve GRIP --kappa K --contact full --json``: (N, least mu_s = |F_f| / N).  Grip I at
#: -10: :data:`~simgrip.reference.free_boundary.GRIP_I_KAPPA_M10`.
BVP = {("I", -9.5): (19.049839, 0.614481), ("I", -11.0): (21.499806, 0.967064),
       ("I", -12.0): (23.056679, 1.196254), ("II", 10.0): (17.261486, 0.932566)}


def _dynamics(monkeypatch, sc):
    """The guarded dynamics alone (the static route switched off)."""
    with monkeypatch.context() as mp:
        mp.setattr(full_contact, "_by_newton", lambda *a: (None, None))
        return settle(sc)


def _tip_normal(st, n):
    return sum(c["normal_force"] for c in st.contact_set if c["with"] == "workpiece" and c["link"] == n - 1)


@pytest.mark.parametrize("grip, kappa, kw", [
    ("I", -3.0, {}), ("I", -6.0, {}), ("I", -6.0, {"box_depth": 0.4}), ("II", 2.0, {}), ("II", 4.0, {}),
    ("free", -5.0, {}),
])
def test_point_range_is_the_dynamics_answer(monkeypatch, grip, kappa, kw):
    """Where point contact applies the static route answers (method 'newton') with the dynamics' state.

    Tolerance (derived, as ``test_below_the_onset_full_contact_is_the_tip_contact``): the dynamics stops at
    MuJoCo's residual ``DYN_TOL`` (1e-5 over rho g l) and its contacts may sit up to ``FULL_PEN_LIMIT`` (1e-4 l)
    off the static rest depth; the finger's tip stiffness ``dN/dX`` is of order ``10 EI / l^3`` (D = 1), so
    ``|dN| <= 10 FULL_PEN_LIMIT + DYN_TOL`` and the tip moves by ``FULL_PEN_LIMIT`` (plus the residual's
    ``DYN_TOL / (EI / l^3)``).  The box's depth: the dynamics' tip sticks with MuJoCo's soft friction, which
    slips up to ``FULL_DEPTH_TOL`` (its own acceptance), while the static route pins it where the frictionless
    closing left it (or at ``box_depth``).
    """
    n = 16
    sc = build_scene(grip, STD, kappa, n, contact="full", **kw)
    st = settle(sc)
    assert st.method == "newton" and st.converged and st.steps == 0
    assert st.residual < DYN_TOL and st.penetration <= FULL_PEN_LIMIT
    depth = grasp_depth(sc) if st.held else None
    ref = _dynamics(monkeypatch, build_scene(grip, STD, kappa, n, contact="full", **kw))
    assert ref.method == "dynamics"
    assert st.held == ref.held
    assert {(c["link"], c["geom"], c["with"]) for c in st.contact_set} == \
        {(c["link"], c["geom"], c["with"]) for c in ref.contact_set}
    assert abs(st.normal_force - ref.normal_force) <= 10 * FULL_PEN_LIMIT + DYN_TOL
    assert np.max(np.abs(np.asarray(st.tip) - np.asarray(ref.tip))) <= FULL_PEN_LIMIT + DYN_TOL
    if st.held:
        assert abs(depth - grasp_depth(sc, ref.qpos)) <= FULL_DEPTH_TOL
        if "box_depth" in kw:
            assert depth == pytest.approx(kw["box_depth"], abs=1e-12)


def test_past_the_onset_the_verdicts_are_the_free_boundary_ones():
    """Grips I/II grasped at depth 0.4 (every contact but the tip's frictionless): Grip I at kappa -9.5 and -11
    holds, at -12 drops, Grip II at 10 holds, as the free-boundary BVP says (least mu_s 0.61, 0.97, 1.20, 0.93
    against mu_s = 1).  The dynamics dropped the box at -9.5 and did not converge at -11, -12 and Grip II 10 (exit
    1).  The simulation's least mu_s, ``|F_f| / N`` of its tip, agrees with the BVP's within the band the verdict
    needs, ``|1 - least_mu|`` (first order in ds: 0.5 % at n = 32, measured)."""
    n = 32
    for (grip, kappa), (N_bvp, least) in BVP.items():
        sc = build_scene(grip, STD, kappa, n, contact="full", box_depth=0.4)
        st = settle(sc)
        assert st.converged and st.method.startswith("newton")
        assert st.held == (least < STD.mu_s)
        if not st.held:
            assert st.method == "newton+dynamics"  # the finger alone, flowed to rest from the held shape
            continue
        assert st.warnings == [] and st.penetration <= 1e-3
        tipN = _tip_normal(st, n)
        tipF = sum(c["friction_force"] for c in st.contact_set if c["with"] == "workpiece" and c["link"] == n - 1)
        assert abs(abs(tipF) / tipN - least) < abs(1.0 - least)
        assert tipN == pytest.approx(N_bvp, rel=0.01)  # the 1 %; measured 0.2-0.25 %
        assert abs(grasp_depth(sc) - 0.4) < 1e-12  # the depth asked, exactly


def test_a_failed_static_route_says_so_and_the_dynamics_settles(monkeypatch):
    """Where the static Newton fails, the dynamics settles and a warning names the failure."""
    def fail(self, q, free, tol, **kw):
        return False, q, kw.get("lam", 0.0)

    monkeypatch.setattr(FullNewton, "solve", fail)
    monkeypatch.setattr(FullNewton, "solve_kkt", fail)
    sc = build_scene("I", STD, -6.0, 8, contact="full", box_depth=0.4)
    st = settle(sc)
    assert st.method == "dynamics" and st.converged and st.held
    assert any("static Newton failed" in w and "settled by the dynamics" in w for w in st.warnings)


def test_the_step_guard_stops_a_link_short_of_another():
    """:meth:`FullNewton.guarded`: a step that carries the free rod's tip across its own root is cut to a
    fraction that closes the gap plus half a capsule radius at most (no link passes through another between
    iterates); a step of a tenth of a radius is whole."""
    n = 16
    sc = build_scene("free", STD, -4.0, n, contact="full")
    run = FullNewton(sc)
    q0 = np.zeros(sc.model.nq)
    q0[run.hinges] = -2.0 * math.pi / n * 0.95  # a nearly closed ring: the tip just short of the root
    q1 = q0.copy()
    q1[run.hinges] = -2.0 * math.pi / n * 1.2  # past it
    assert run.step_bound(q0, q1) < 1.0
    f = run.guarded(q0, q1 - q0)
    assert 0.0 < f < 1.0
    run.forces(q0 + f * (q1 - q0))  # MuJoCo's collision at the cut step: overlaps of half a radius at most
    assert run.deepest() <= 0.5
    run.forces(q1)
    assert run.deepest() > 0.5  # (the whole step would have put the tip through the root link)
    tiny = q0.copy()
    tiny[run.hinges[-1]] += 0.1 * sc.r_link * n  # the last link turns: its tip moves 0.1 r_link l
    assert run.guarded(q0, tiny - q0) == 1.0


def test_bench_full_record(tmp_path, monkeypatch):
    """simgrip.harness.bench_full: one row per ratio, each ratio the quotient of its own times, checks against the
    issue's targets (3 for full/point, 1 for full/BVP); the files written whole."""
    import json

    from simgrip.harness import bench_full as bf

    rows = bf._point_rows(8, 1, False)
    assert [r["case"] for r in rows] == [f"{g} kappa {k:g} n=8: full/point" for g, k in bf.POINT_CASES]
    assert all(r["ratio"] == r["full_s"] / r["point_s"] and r["method"] == "newton" for r in rows)
    monkeypatch.setattr(bf, "_point_rows", lambda n, reps, before: [{"case": "I kappa -6 n=32: full/point",
                                                                     "ratio": 2.0}])
    monkeypatch.setattr(bf, "_past_rows", lambda ns, reps, before: [{"case": f"I n={n}: full/BVP", "ratio": 1.5}
                                                                    for n in ns])
    rec = bf.write_full_bench(tmp_path, quick=True)
    assert rec["checks"] == {"I kappa -6 n=32: full/point <= 3": True, "I n=16: full/BVP <= 1": False}
    assert json.loads((tmp_path / "full.json").read_text())["checks"] == rec["checks"]
    assert "| I n=16: full/BVP <= 1 | NO |" in (tmp_path / "full.md").read_text()
