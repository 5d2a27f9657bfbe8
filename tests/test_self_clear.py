"""simgrip.validity.self_clear_below: the tangent-range proof agrees with the exact pair tests on every pair it proves.

The proof (its docstring) says every pair of links ``2 <= j - i < low`` neither crosses nor (``j - i >= gap``)
comes within ``limit``.  Here the exact tests (:func:`simgrip.intersection.crossing_pairs`, all pairs'
:func:`simgrip.intersection.segment_distances`, no pruning) run on random chains -- smooth arcs that pass
the proof, tight curls, hairpins and spirals near the limit that it leaves open -- and must find nothing
below ``low``; and :func:`chain_violations`, which skips the proved pairs, must give the same list as with
the proof switched off (``low`` = 2, every pair exact).
"""

import math

import numpy as np
import pytest

from simgrip import intersection as isect
from simgrip import validity as V


def _chain(turns, h):
    ang = np.concatenate([[0.0], np.cumsum(turns)])
    P = np.zeros((len(ang) + 1, 2))
    P[1:] = np.cumsum(h * np.stack([np.cos(ang), np.sin(ang)], axis=1), axis=0)
    return P


def _chains(rng):
    for n in (8, 16, 32, 64, 256):
        h = 1.0 / n
        for total in (0.5, 2.8, 3.3, 6.0, 2 * math.pi - 0.05, 2 * math.pi + 0.3, 9.0, 14.0):
            yield _chain(np.full(n - 1, total / (n - 1)), h)  # a circular arc: a full turn closes on itself
            yield _chain(total / (n - 1) * (1 + 0.8 * rng.standard_normal(n - 1)), h)
        # a hairpin: straight, a half turn in a few links, straight back at about the limit's distance
        k = max(2, n // 8)
        turns = np.zeros(n - 1)
        turns[n // 2 - k // 2: n // 2 - k // 2 + k] = math.pi / k
        yield _chain(turns, h)
        yield _chain(rng.uniform(-1.2, 1.2, n - 1), h)  # kinked
        # zigzags (turns +-a): link j's start is (j - i - 1) h cos(a/2) from link i's end, the proof's own bound,
        # so these sit on its edge: at some a the limit lies between the bound and the distances
        for a in np.linspace(2.0, 3.1, 12):
            yield _chain(a * (-1.0) ** np.arange(n - 1), h)


@pytest.mark.parametrize("r_link", [0.002, 0.02, 0.05])
def test_proved_pairs_are_clear_in_the_exact_tests(r_link):
    rng = np.random.default_rng(7)
    limit = V.SELF_LIMIT_FACTOR * r_link
    seen = {"all": 0, "part": 0, "none": 0}
    for P in _chains(rng):
        n = len(P) - 1
        gap = V.self_gap_links(n, r_link)
        low = V.self_clear_below(P, limit, gap)
        seen["all" if low >= n else "none" if low == 2 else "part"] += 1
        i, j = np.triu_indices(n, k=2)
        proved = j - i < low
        ci, cj = isect.crossing_pairs(P, pairs=(i[proved], j[proved]))
        assert ci.size == 0
        far = proved & (j - i >= gap)
        dist = isect.segment_distances(P[i[far]], P[i[far] + 1], P[j[far]], P[j[far] + 1])
        assert np.all(dist >= limit)
        assert V.self_clear(P, limit, gap) == (low >= n)
    assert min(seen.values()) > 0, seen  # the proof passes, stops part way and fails outright on these chains


def test_chain_violations_unchanged_by_the_proof(monkeypatch):
    rng = np.random.default_rng(11)
    chains = list(_chains(rng))
    fast = [V.chain_violations([P], [P], r_link=0.02, r_tip=None, solid=None) for P in chains]
    monkeypatch.setattr(isect, "self_clear_below", lambda nodes, limit, gap: 2)  # the proof off (simgrip.link_pairs)
    exact = [V.chain_violations([P], [P], r_link=0.02, r_tip=None, solid=None) for P in chains]
    assert fast == exact
    assert any(fast) and not all(fast)
