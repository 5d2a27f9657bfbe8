"""simgrip.link_pairs: every pair of links measured at once gives the pruned path's sets, order and messages.

:func:`simgrip.validity.chain_violations` measures every pair of links of all the fingers at once
(:func:`~simgrip.link_pairs.all_self_pairs`, :func:`~simgrip.link_pairs.all_finger_pairs`) for a few short fingers
and prunes a finger and a pair of fingers at a time otherwise.  Here both run on the same states (``batch=True`` /
``False``) and must give the same list, messages and all: one finger's random curls, hairpins and kinked chains
(crossings and overlaps); K = 2, 3 and 4 fingers at equal azimuths, each curled by its own random curvature, and all
of them curled alike through the palm's axis (the claws' usual invalid state, where every finger pair's closest
links tie and the pair named is the first in candidate order); and the pair sets themselves against a brute force
over every pair (:func:`simgrip.intersection.segment_distances`, :func:`simgrip.intersection.crossing_pairs`).
"""

import math

import numpy as np
import pytest

from simgrip import intersection as isect
from simgrip import link_pairs as lp
from simgrip import validity as V


def _planar(turns, h=None):
    """A planar chain from the base along +x turning by ``turns`` (n - 1 of them) between links of length h."""
    n = len(turns) + 1
    h = 1.0 / n if h is None else h
    ang = np.concatenate([[0.0], np.cumsum(turns)])
    P = np.zeros((n + 1, 2))
    P[1:] = np.cumsum(h * np.stack([np.cos(ang), np.sin(ang)], axis=1), axis=0)
    return P


def _fingers(planar, azimuths):
    """Each planar finger (x out from the palm's centre, z up) turned to its azimuth: world nodes (n+1, 3)."""
    out = []
    for P, phi in zip(planar, azimuths):
        out.append(np.stack([P[:, 0] * math.cos(phi), P[:, 0] * math.sin(phi), P[:, 1]], axis=1))
    return out


def _sines(azimuths):
    K = len(azimuths)
    return [[abs(math.sin(0.5 * (azimuths[f] - azimuths[g]))) if f != g else 1.0 for g in range(K)] for f in range(K)]


def _both(planar, world, **kw):
    return (V.chain_violations(planar, world, batch=True, **kw), V.chain_violations(planar, world, batch=False, **kw))


def _one_finger_states(rng):
    for n in (4, 8, 12, 16):
        for total in (0.5, 3.0, 2 * math.pi - 0.05, 2 * math.pi + 0.3, 9.0, 14.0):
            yield _planar(np.full(n - 1, total / (n - 1)))
            yield _planar(total / (n - 1) * (1 + 0.8 * rng.standard_normal(n - 1)))
        turns = np.zeros(n - 1)
        k = max(2, n // 6)
        turns[n // 2 - k // 2:n // 2 - k // 2 + k] = math.pi / k  # a hairpin
        yield _planar(turns)
        yield _planar(rng.uniform(-2.5, 2.5, n - 1))  # kinked, often crossing itself


@pytest.mark.parametrize("r_link", [0.01, 0.03, 0.06])
def test_one_finger_batched_equals_the_pruned_path(r_link):
    rng = np.random.default_rng(5)
    kinds = set()
    for P in _one_finger_states(rng):
        batched, pruned = _both([P], [P], r_link=r_link, r_tip=None, solid=None)
        assert batched == pruned
        kinds |= {k for k, _ in batched}
    assert kinds == {"self_crossing", "self_overlap"}  # both kinds met, so both are compared


@pytest.mark.parametrize("K,n", [(2, 12), (3, 8), (3, 12), (3, 16), (4, 12)])
def test_batched_fingers_equal_the_pruned_path(K, n):
    """K fingers at equal azimuths, each curled by its own random curvature (some through the palm's axis), and the
    symmetric curl of all of them through the axis, where every finger pair's closest links tie."""
    rng = np.random.default_rng(9 + K + n)
    az = [2 * math.pi * f / K for f in range(K)]
    sines = _sines(az)
    seen = 0
    for trial in range(100):
        totals = rng.uniform(-1.0, 9.0, K) if trial % 5 else np.full(K, rng.uniform(3.0, 7.0))
        planar = [_planar(t / (n - 1) * (1 + 0.3 * rng.standard_normal(n - 1)) if trial % 5 else
                          np.full(n - 1, t / (n - 1))) for t in totals]
        world = _fingers(planar, az)
        batched, pruned = _both(planar, world, r_link=0.03, r_tip=None, solid=None, base_sines=sines)
        assert batched == pruned
        seen += sum(k == "fingers" for k, _ in batched)
    assert seen > 10  # the finger pairs' messages are met, so they are compared


def test_pair_sets_against_every_pair():
    """The sets themselves, against the exact tests on every pair of links (no pruning)."""
    rng = np.random.default_rng(3)
    n, r_link = 12, 0.03
    limit = V.SELF_LIMIT_FACTOR * r_link
    az = [0.0, 2 * math.pi / 3, 4 * math.pi / 3]
    sines = _sines(az)
    a, b = np.indices((n, n)).reshape(2, -1)
    found = 0
    for _ in range(60):
        planar = [_planar(rng.uniform(-1.0, 9.0) / (n - 1) * (1 + 0.5 * rng.standard_normal(n - 1))) for _ in az]
        world = _fingers(planar, az)
        got = lp.all_finger_pairs(world, limit, sines)
        assert sorted(got) == [(0, 1), (0, 2), (1, 2)]
        gap = V.self_gap_links(n, r_link)
        i, j = np.triu_indices(n, 2)
        for P, (ci, cj, si, sj, sd) in zip(planar, lp.all_self_pairs(planar, limit, gap)):
            xi, xj = isect.crossing_pairs(P, pairs=(i, j))
            far = j - i >= gap
            d = isect.segment_distances(P[i[far]], P[i[far] + 1], P[j[far]], P[j[far] + 1])
            assert set(zip(ci.tolist(), cj.tolist())) == set(zip(xi.tolist(), xj.tolist()))
            assert set(zip(si.tolist(), sj.tolist())) == {(p, q) for p, q, x in zip(i[far].tolist(), j[far].tolist(),
                                                                                   d.tolist()) if x < limit}
            found += len(si) + len(ci)
        for (f, g), (gi, gj, gd) in got.items():
            A, B = world[f], world[g]
            d = isect.segment_distances(A[a], A[a + 1], B[b], B[b + 1])
            keep = (d < limit) & ((a + b) / n * sines[f][g] >= limit)
            assert set(zip(gi.tolist(), gj.tolist())) == set(zip(a[keep].tolist(), b[keep].tolist()))
            assert np.all(gd < limit)
            found += int(keep.sum())
    assert found > 0


def test_pairs_are_listed_in_candidate_order():
    """Blocks of BLOCK links first, then i, then j: the order candidate_pairs lists them in."""
    P = _planar(np.full(19, 0.3))
    for (i, j), (ci, cj) in [(lp._other_index(20), isect.candidate_pairs(P, P + 0.01, limit=10.0)),
                             (lp._self_index(20), isect.candidate_pairs(P, limit=10.0, min_gap=2))]:
        key = list(zip((i // isect.BLOCK).tolist(), (j // isect.BLOCK).tolist(), i.tolist(), j.tolist()))
        assert key == sorted(key)
        assert ci.tolist() == i.tolist() and cj.tolist() == j.tolist()  # every pair's boxes overlap: all listed


def test_the_default_batches_two_short_fingers_or_more(monkeypatch):
    """batch=None: every pair at once for BATCH_FINGERS fingers or more of at most BATCH_LINKS links, all alike; a
    finger and a pair of fingers at a time otherwise (one finger, long fingers, fingers of different lengths)."""
    calls = []
    monkeypatch.setattr(V, "all_finger_pairs", lambda *a, **k: calls.append(1) or lp.all_finger_pairs(*a, **k))
    az = [0.0, 2 * math.pi / 3, 4 * math.pi / 3]

    def check(ns):
        planar = [_planar(np.full(k - 1, 4.0 / (k - 1))) for k in ns]
        V.chain_violations(planar, _fingers(planar, az), r_link=0.03, r_tip=None, solid=None, base_sines=_sines(az))

    check([12])
    check([lp.BATCH_LINKS + 1] * 3)
    check([12, 12, 10])
    assert calls == []
    check([12] * lp.BATCH_FINGERS)
    check([lp.BATCH_LINKS] * 3)
    assert calls == [1, 1]
