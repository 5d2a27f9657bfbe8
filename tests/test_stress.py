"""Small numerical stress run: every case ends settled or with a named error."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from simgrip.harness.stress import (
    GRIPS,
    make_cases,
    names_an_input,
    run_stress,
    self_intersects,
)


@pytest.fixture(scope="module")
def stress(tmp_path_factory):
    out = tmp_path_factory.mktemp("stress")
    # n <= 64 keeps this under half a minute on two cores; the 60 s guard per case only
    # catches hangs (a case takes well under a second), so a loaded machine cannot fail it
    return run_stress(out, cases=40, seed=1, jobs=1, progress=False, timeout_s=60.0, grid_cases=16, max_links=64), out


def test_no_failures(stress):
    res, _ = stress
    assert res.counts["total"] == 40
    assert res.counts["failed"] == 0, res.failures
    assert sum(res.counts[k] for k in ("settled", "rejected", "unsettled", "failed")) == 40
    assert {c["grip"] for c in res.cases} == set(GRIPS)
    assert sum(c["source"] == "random" for c in res.cases) == 24


def test_rejections_name_a_parameter(stress):
    res, _ = stress
    for c in res.rejected:
        assert c["error_type"] == "ValueError"
        assert names_an_input(c["error"]), c["error"]


def test_rejection_names():
    assert names_an_input("gamma (contact arc length over l) must lie in (0, 1), got 2")
    assert names_an_input("profile: no Grip III starting shape with gamma = 0.8")
    assert not names_an_input("11 is not in list")


def test_settled_states_are_finite_and_converged(stress):
    res, _ = stress
    for c in res.cases:
        if c["outcome"] == "settled":
            # settle's tol is 1e-10; it may stop at its noise floor (reported to the lead), never far above
            assert math.isfinite(c["residual"]) and c["residual"] <= 1e-6
            assert set(c["flags"]) >= {"self_intersection", "penetration", "tip_touches_workpiece"}


def test_files(stress):
    res, out = stress
    data = json.loads((out / "stress.json").read_text())
    assert data["counts"]["total"] == 40 and len(data["cases"]) == 40
    assert (out / "stability_map.png").read_bytes()[:4] == b"\x89PNG"


def test_cases_are_deterministic():
    a, b = make_cases(120, seed=3), make_cases(120, seed=3)
    assert a == b and len(a) == 120
    assert make_cases(120, seed=4) != a


def test_self_intersection_check():
    s = np.linspace(0, 1, 65)
    half = np.stack([np.cos(np.pi * s), np.sin(np.pi * s)], axis=1)  # half circle: no crossing
    assert not self_intersects(half)
    # a chain curled uniformly through 1.2 turns passes through itself
    phi = np.cumsum(np.full(64, 2.4 * np.pi / 64))
    nodes = np.vstack([[0, 0], np.cumsum(np.stack([np.cos(phi), np.sin(phi)], axis=1) / 64, axis=0)])
    assert self_intersects(nodes)
    assert not self_intersects(nodes[:50])  # less than a full turn
    zigzag = np.array([[0, 0], [1, 0], [1, 1], [0.5, -0.5]])
    assert self_intersects(zigzag)
    assert not self_intersects(np.array([[0, 0], [1, 0], [2, 0]]))
