"""Arguments are checked once where they enter and handed down as checked values (issue 21).

Each public call below counts the checks that do work:

* the grip's parse (:func:`simgrip.params._parse_grip`, behind
  :func:`~simgrip.params.check_grip`, which hands a :class:`~simgrip.params.Grip`
  back unchanged);
* a :class:`~simgrip.params.DimensionlessParams` built equal to the argument or
  to one built before it (the same groups validated again: the old ``to_physical`` /
  ``dimensionless`` round trip of every layer) -- a *new* value, such as the
  settle's ``params.replace(b=b - 2e-6)``, is not a re-check and is not counted;
* any :class:`~simgrip.params.PhysicalParams` built (the dimensionless argument
  realised with ``l = rho = g = 1`` is checked groups copied, not re-validated);
* the link count's parse (:func:`simgrip.chain._parse_count`, behind
  :func:`~simgrip.chain.check_links`, which hands a :class:`~simgrip.chain.Count`
  back unchanged);
* :func:`simgrip.gripper.scene.check_gripper` (grip, fingers, workpiece).

Before this (measured with this file on the same calls, n = 16, grip parses /
link-count parses / params re-validated / physical built): ``simulate`` 6-7 / 6-8
/ 2 / 2, ``compare`` 8 / 7 / 2 / 2, ``simulate_gripper`` 5-6 / 8-10 / 2 / 1, a
sweep point (its grid already checked) 6 / 6 / 0 / 2, ``gripper_record`` 1 / 1,
the command line's ``simulate`` 8-9 / 8-12 / 2 / 1-2.
Every count here must now be the number of arguments that entered: one grip,
one link count, zero re-validated params.
"""

from __future__ import annotations

import collections

import pytest

import simgrip.chain as C
import simgrip.params as P
from simgrip.chain import Count, check_links
from simgrip.params import DimensionlessParams, Grip, check_grip

LINKS = 16  # the counts do not depend on the resolution; 16 links settle in ~0.1 s


@pytest.fixture
def counts(monkeypatch):
    """Counters of the checks that do work, wrapped for the test (the reuse caches cleared: the fresh-build path,
    through every layer, is the one counted)."""
    from simgrip.gripper import scene as gscene
    from simgrip.sim import reuse

    reuse.clear()
    c = collections.Counter()
    entered: list = []
    links, parse, gripper = C._parse_count, P._parse_grip, gscene.check_gripper
    dp_init, pp_init = DimensionlessParams.__post_init__, P.PhysicalParams.__post_init__

    def links_w(n, name):
        c["links parsed"] += 1
        return links(n, name)

    def parse_w(grip):
        c["grip parsed"] += 1
        return parse(grip)

    def dp_w(self):
        dp_init(self)
        if any(self == p for p in entered):
            c["params re-validated"] += 1
        entered.append(self)

    def pp_w(self):
        c["physical built"] += 1
        pp_init(self)

    def gripper_w(*a, **k):
        c["check_gripper"] += 1
        return gripper(*a, **k)

    monkeypatch.setattr(C, "_parse_count", links_w)
    monkeypatch.setattr(P, "_parse_grip", parse_w)
    monkeypatch.setattr(DimensionlessParams, "__post_init__", dp_w)
    monkeypatch.setattr(P.PhysicalParams, "__post_init__", pp_w)
    monkeypatch.setattr(gscene, "check_gripper", gripper_w)
    c.entered = entered
    yield c
    reuse.clear()


def _params(counts) -> DimensionlessParams:
    p = DimensionlessParams()
    counts.entered.append(p)
    counts.clear()
    return p


@pytest.mark.parametrize("grip", ["I", "iii"])
def test_simulate_checks_each_argument_once(counts, grip):
    from simgrip.settled import simulate

    p = _params(counts)
    state = simulate(grip, p, 0.0, LINKS)
    assert dict(counts) == {"grip parsed": 1, "links parsed": 1}
    assert state.grip is check_grip(grip)  # handed down as the checked value


def test_compare_checks_each_argument_once(counts):
    from simgrip.compare import compare

    p = _params(counts)
    out = compare("I", p, 0.0, LINKS)
    assert dict(counts) == {"grip parsed": 1, "links parsed": 1}
    assert out["simulation"]["grip"] == "I"


@pytest.mark.parametrize("grip,fingers,workpiece", [("I", 3, "cylinder"), ("III", 4, "box")])
def test_simulate_gripper_checks_each_argument_once(counts, grip, fingers, workpiece):
    from simgrip.gripper.simulate import gripper_record, simulate_gripper

    p = _params(counts)
    state = simulate_gripper(grip, p, 0.0, LINKS, fingers=fingers, workpiece=workpiece)
    assert dict(counts) == {"grip parsed": 1, "links parsed": 1, "check_gripper": 1}
    counts.clear()
    rec = gripper_record(state, p, 0.0)  # the state's grip is already checked
    assert not counts, dict(counts)  # nothing re-checked: the state's values were checked when they entered
    assert rec["grip"] == grip


def test_sweep_point_checks_its_grip_with_the_grid(counts):
    """A sweep's grip is checked once, with its grid; each point builds its params (the point's own entry)."""
    from simgrip.sweep.grid import make_grid
    from simgrip.sweep.point import evaluate_point

    grid = make_grid("I", kappa=[0.0], links=LINKS, reference="none")
    assert counts["grip parsed"] == 1 and isinstance(grid.grip, Grip) and isinstance(grid.links, Count)
    point = next(iter(grid.points()))
    counts.clear()
    row = evaluate_point(point)
    assert row["status"] == "settled"
    assert "grip parsed" not in counts and "links parsed" not in counts and "physical built" not in counts


@pytest.mark.parametrize("argv", [["simulate", "III", "--links", "16", "--kappa", "-1"],
                                  ["simulate", "I", "--links", "16", "--kappa", "0", "--fingers", "3",
                                   "--workpiece", "cylinder"]])
def test_cli_checks_each_argument_once(counts, capsys, argv):
    """The command line checks its arguments where they enter (its parser) and hands them down checked."""
    from simgrip.cli import main

    assert main(argv) == 0
    assert "grip" in capsys.readouterr().out  # the record was printed
    assert counts["grip parsed"] == 1 and counts["links parsed"] == 1
    assert "params re-validated" not in counts and "physical built" not in counts


def test_grip_is_a_plain_str_to_readers():
    """A checked grip reads, prints, hashes and serialises as its name: no reader of a grip changes."""
    import json
    import pickle

    g = check_grip(" iii ")
    assert g is Grip.III and check_grip(g) is g
    assert g == "III" and {"III": 1}[g] == 1 and hash(g) == hash("III")
    assert (str(g), f"{g}", repr(g), json.dumps(g)) == ("III", "III", "'III'", '"III"')
    assert pickle.loads(pickle.dumps(g)) is g
    with pytest.raises(ValueError, match="grip must be one of"):
        check_grip("IV")


def test_count_is_a_plain_int_to_readers():
    """A checked count is an ``int`` (arithmetic, JSON, pickling as before) that :func:`check_links` passes through."""
    import json
    import pickle

    n = check_links(16.0)
    assert type(n) is Count and n == 16 and check_links(n) is n and type(n + 1) is int
    assert (repr(n), json.dumps(n), hash(n)) == ("16", "16", hash(16))
    assert pickle.loads(pickle.dumps(n)) == 16
    with pytest.raises(ValueError, match="links must be an integer >= 2"):
        check_links(1.5)


def test_unit_physical_is_to_physical_bit_for_bit():
    """The scenes' realisation of a dimensionless argument (not re-validated) equals the validated one exactly."""
    for p in (DimensionlessParams(), DimensionlessParams(D=0.37, M=0.0, b=1.3, mu_s=0.0, gamma=0.9999),
              DimensionlessParams(D=1e4, M=1e4, b=1e-9, mu_s=100.0, gamma=1e-9)):
        u, v = p.unit_physical(), p.to_physical(length=1.0, rho=1.0, g=1.0)
        assert u == v and u.dimensionless() is p and v.dimensionless() == p
