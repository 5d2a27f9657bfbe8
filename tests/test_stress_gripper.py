"""The K-finger cases of the stress run (simgrip.harness.stress_gripper): draws, checks, and that they can fail."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import simgrip.harness.stress_gripper as sg
from simgrip.harness.stress_gripper import (GRIPPER_SHAPES, MAX_BOX_YAW, OFFSET_FRACTION, gripper_counts,
                                            make_gripper_cases, run_gripper_case)


def test_cases_are_seeded_and_within_their_ranges():
    a = make_gripper_cases(20, seed=3)
    assert a == make_gripper_cases(20, seed=3) and a != make_gripper_cases(20, seed=4)
    assert [c["id"] for c in a] == list(range(20))
    assert {(c["workpiece"], c["fingers"]) for c in a} == set(GRIPPER_SHAPES)
    for c in a:
        assert len(c["kappas"]) == c["fingers"]
        assert all(k < 0 for k in c["kappas"]) if c["grip"] == "I" else all(k > 0 for k in c["kappas"])
        assert math.hypot(*c["offset"]) <= OFFSET_FRACTION * 0.5 * c["b"]
        if c["fingers"] == 2:
            assert c["offset"][1] == 0.0  # along the fingers' plane
        if c["workpiece"] == "box":
            assert abs(c["workpiece_yaw"]) <= MAX_BOX_YAW
    assert max(c["n"] for c in make_gripper_cases(10, max_links=8)) == 8
    for kw, name in ((dict(count=-1), "count"), (dict(count=2, seed=-1), "seed"), (dict(count=2, max_links=1),
                                                                                    "max_links")):
        with pytest.raises(ValueError, match=name):
            make_gripper_cases(**kw)


@pytest.fixture(scope="module")
def two():
    return [run_gripper_case(c) for c in make_gripper_cases(2)]


def test_cases_settle_balanced_and_deterministic(two):
    for rec in two:
        assert rec["outcome"] == "settled", rec["error"]
        assert rec["held"] and math.isfinite(rec["residual"]) and rec["steps"] > 0
    counts = gripper_counts(two)
    assert counts["settled"] == counts["total"] == 2 and counts["held"] == 2


def test_the_checks_can_fail(monkeypatch):
    case = make_gripper_cases(1)[0]
    good = sg._settle(case)
    calls = {"n": 0}

    def nan_state(_case):
        return replace(good, residual=math.nan)

    def unbalanced(_case):
        return replace(good, force_balance=good.force_balance + np.array([0.0, 0.0, 1e-3]))

    def changing(_case):
        calls["n"] += 1
        return replace(good, steps=good.steps + calls["n"])

    def named(_case):
        raise ValueError("offset must keep the palm axis inside the cylinder")

    def unnamed(_case):
        raise ValueError("something inside went wrong")

    for fake, outcome, text in ((nan_state, "failed", "non-finite"), (unbalanced, "failed", "force balance"),
                                (changing, "failed", "deterministic"), (named, "rejected", "offset"),
                                (unnamed, "failed", "unnamed")):
        monkeypatch.setattr(sg, "_settle", fake)
        rec = run_gripper_case(case)
        assert rec["outcome"] == outcome and text in rec["error"], (fake.__name__, rec["error"])


def test_a_drop_is_explained_from_its_start(monkeypatch):
    """diagnose_start names the first reason that applies; run_gripper_case records it for drops and unsettled
    cases only, and gripper_counts tallies them."""
    from simgrip.gripper import stability as gst
    from simgrip.gripper import start as gs

    case = make_gripper_cases(1)[0]
    real = gs.start_forces(sg._scene(case))

    def forces(mu=None, balanced=True):
        f = real if mu is None else replace(real, required_mu=np.full_like(real.required_mu, mu))
        return lambda scene: replace(f, balanced=balanced)

    for mu, eig, balanced, reason in ((2 * case["mu_s"], -1.0, False, "friction"),
                                     (0.5 * case["mu_s"], -1.0, False, "unbalanced start"),
                                     (0.5 * case["mu_s"], -1.0, True, "unstable start"),
                                     (0.5 * case["mu_s"], 1.0, True, "unexplained")):
        monkeypatch.setattr(gs, "start_forces", forces(mu, balanced))
        monkeypatch.setattr(gst, "start_growth", lambda scene: 1.25)
        monkeypatch.setattr(gst, "start_stiffness", lambda scene, e=eig: gst.StartStiffness(np.array([e, 2.0]), 2, 1e-6))
        d = sg.diagnose_start(case)
        assert d["drop_reason"] == reason and d["start_mu"] == pytest.approx(mu) and d["start_growth"] == 1.25
        assert d["start_min_eigenvalue"] == eig
    # a held case is not diagnosed; a dropped one is
    good = sg._settle(case)
    monkeypatch.setattr(sg, "_settle", lambda _c: good)
    assert run_gripper_case(case)["drop_reason"] is None
    monkeypatch.setattr(sg, "_settle", lambda _c: replace(good, held=False, records=[]))
    rec = run_gripper_case(case)
    assert rec["outcome"] == "settled" and rec["drop_reason"] == "unexplained"
    monkeypatch.setattr(sg, "_settle", lambda _c: replace(good, held=False, records=[], grip_matched=False))
    assert run_gripper_case(case)["drop_reason"] == "wrong grip"
    counts = gripper_counts([rec, dict(rec, outcome="unsettled", drop_reason="friction")])
    assert counts["dropped_by"] == {"unexplained": 1} and counts["unsettled_by"] == {"friction": 1}


def test_an_impossible_k_finger_state_is_counted_unless_reported(monkeypatch):
    """Issue 17: the K-finger stress recomputes the geometric check; a crossing state reported valid is counted."""
    case = dict(make_gripper_cases(1)[0])
    good = sg._settle(case)
    crossed = replace(good, link_angles=np.cumsum(np.full_like(good.link_angles, -3.0 * np.pi / good.links), axis=1))
    monkeypatch.setattr(sg, "_settle", lambda _c: crossed)  # a curl through 1.5 turns, still claimed valid
    rec = run_gripper_case(case)
    assert rec["invalid_kinds"] and rec["valid"] is True
    assert gripper_counts([rec])["invalid_returned_as_valid"] == 1
    assert gripper_counts([dict(rec, valid=False)])["invalid_returned_as_valid"] == 0  # reported: not counted
