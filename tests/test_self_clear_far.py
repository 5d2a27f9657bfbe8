"""simgrip.intersection._far_pairs_clear: the midpoint proof of a curled rod's far pairs against the exact tests.

The proof (its docstring): every point of link ``k`` is within ``h_k / 2`` of its midpoint, so links ``i`` and
``j`` are at least ``|c_i - c_j| - h_i / 2 - h_j / 2`` apart.  Where it says the pairs ``j - i >= d_k`` are
clear, the exact tests (:func:`simgrip.intersection.crossing_pairs` and every pair's
:func:`simgrip.intersection.segment_distances`, no pruning) must find no crossing and no pair within the limit
among them -- on random curls, circles that close on themselves, and hairpins and spirals whose far pairs sit
just above and just below the limit (the proof's edge); and :func:`simgrip.validity.chain_violations` must give
the same list with the proof on and with every pair tested exactly (``self_clear_below`` -> 2).
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


def _hairpin(n, sep, bend_links):
    """Straight, a half turn of diameter ~``sep`` over ``bend_links`` links, straight back: arms ``sep`` apart."""
    h = 1.0 / n
    k = max(2, int(bend_links))
    turns = np.zeros(n - 1)
    start = n // 2 - k // 2
    turns[start:start + k] = math.pi / k
    P = _chain(turns, h)
    # scale the bend so that the arms are sep apart: the half turn's width is h / (2 sin(pi / 2k)) * 2 (a polygon)
    width = h / math.sin(math.pi / (2 * k))
    return P * (sep / width)


def _curls(rng, limit):
    for n in (16, 32, 64, 128, 256):
        h = 1.0 / n
        for total in np.concatenate([np.linspace(3.0, 7.0, 17), [2 * math.pi - 1e-3, 2 * math.pi + 1e-3]]):
            yield _chain(np.full(n - 1, total / (n - 1)), h)  # a uniform curl (the free rod's |kappa_bar| = total)
            yield _chain(total / (n - 1) * (1 + 0.5 * rng.standard_normal(n - 1)), h)
        for total in (4.0, 8.0, 12.0):  # spirals: the curvature growing along the rod, the turns closing in
            yield _chain(np.linspace(0.0, 2.0 * total / (n - 1), n - 1), h)
        for f in (0.9, 0.999, 1.0, 1.001, 1.1, 2.0):  # hairpins whose arms are about the limit apart
            yield _hairpin(n, f * limit, max(2, n // 8))


def _exact_far(P, d_k, limit):
    """(crossings, least distance) of the pairs ``j - i >= d_k``, every pair tested."""
    n = len(P) - 1
    i, j = np.triu_indices(n, k=max(d_k, 2))
    if i.size == 0:
        return 0, math.inf
    ci, _ = isect.crossing_pairs(P, pairs=(i, j))
    dist = isect.segment_distances(P[i], P[i + 1], P[j], P[j + 1])
    return ci.size, float(dist.min())


@pytest.mark.parametrize("r_link", [0.01, 0.05])
def test_far_pairs_proved_clear_are_clear_in_the_exact_tests(r_link):
    rng = np.random.default_rng(19)
    limit = V.SELF_LIMIT_FACTOR * r_link
    need = limit * (1.0 + isect.CLEAR_MARGIN)
    seen = {True: 0, False: 0}
    for P in _curls(rng, limit):
        n = len(P) - 1
        d = P[1:] - P[:-1]
        for d_k in sorted({2, n // 4, n // 2, 3 * n // 4, n - 2}):
            if not 2 <= d_k < n:
                continue
            proved = isect._far_pairs_clear(P, d, d_k, need)
            seen[proved] += 1
            if proved:
                crossings, least = _exact_far(P, d_k, limit)
                assert crossings == 0 and least >= limit, (n, d_k, least, limit)
    assert seen[True] > 0 and seen[False] > 0, seen  # the proof passes and fails on these shapes


def test_far_proof_takes_the_uniform_curl_the_tangent_range_leaves_open(monkeypatch):
    """The free rod's curl at kappa_bar = -4, n = 256 (issue 19's call bench): the tangent range stops part way,
    the midpoints prove the rest, and the exact tests agree that nothing is left."""
    n, r_link = 256, 0.05
    P = _chain(np.full(n - 1, -4.0 / (n - 1)), 1.0 / n)
    limit, gap = V.SELF_LIMIT_FACTOR * r_link, V.self_gap_links(n, r_link)
    assert isect.self_clear_below(P, limit, gap) >= n
    monkeypatch.setattr(isect, "_far_pairs_clear", lambda *a: False)
    low = isect.self_clear_below(P, limit, gap)
    assert 2 < low < n
    assert _exact_far(P, low, limit)[0] == 0 and _exact_far(P, low, limit)[1] >= limit


def test_far_proof_refuses_a_large_band():
    """Beyond FAR_PAIR_LINKS links a side the O(K^2) proof is not tried (the exact tests' pruning runs)."""
    n = 2 * isect.FAR_PAIR_LINKS + 8
    P = _chain(np.full(n - 1, 4.0 / (n - 1)), 1.0 / n)
    assert not isect._far_pairs_clear(P, P[1:] - P[:-1], 4, 1e-6)


@pytest.mark.parametrize("r_link", [0.005, 0.02, 0.05])
def test_chain_violations_unchanged_by_the_far_proof(monkeypatch, r_link):
    rng = np.random.default_rng(23)
    limit = V.SELF_LIMIT_FACTOR * r_link
    chains = list(_curls(rng, limit))
    fast = [V.chain_violations([P], [P], r_link=r_link, r_tip=None, solid=None) for P in chains]
    monkeypatch.setattr(isect, "self_clear_below", lambda nodes, limit, gap: 2)  # the proof off (simgrip.link_pairs)
    exact = [V.chain_violations([P], [P], r_link=r_link, r_tip=None, solid=None) for P in chains]
    assert fast == exact
    assert any(fast) and not all(fast)
