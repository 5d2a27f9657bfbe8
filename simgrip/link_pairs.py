"""Which links of a set of fingers cross or come too close: the sets :func:`simgrip.validity.chain_violations` words.

* :func:`finger_self_pairs` -- one finger's own pairs, pruned first (:func:`simgrip.intersection.self_clear_below`'s
  proof, then :func:`simgrip.intersection.candidate_pairs`' boxes), so a long chain costs ``O(n)`` pairs and a smooth
  curl a few calls.
* :func:`finger_pair_contacts` -- one pair of fingers, pruned by the boxes.
* :func:`all_self_pairs`, :func:`all_finger_pairs` -- every finger's own pairs, and every pair of fingers, at once:
  every pair of links measured, one :func:`~simgrip.intersection.segment_distances` call each.  For a few short
  fingers (``K >= BATCH_FINGERS``, ``n <= BATCH_LINKS``: the pick environments' 12 links) the pruning's calls, a
  finger and a pair of fingers at a time, cost more than measuring all ``~K^2 n^2 / 2`` pairs (issue 18, item 5:
  the claws' fingers curled through the palm's axis, their usual invalid state under random actions).

The sets are the same either way: the pairs the pruning drops are the ones its proof clears (the tangent range by
:data:`~simgrip.intersection.CLEAR_MARGIN` above the limit: neither crossing nor within it) and those whose boxes
are farther apart than the limit on some axis (so are the links).  Both list the pairs in
:func:`~simgrip.intersection.candidate_pairs`' order (blocks of :data:`~simgrip.intersection.BLOCK` links, then
``i``, then ``j``) with the same elementwise arithmetic, so the closest pair named (the first on a tie) agrees too (``tests/test_link_pairs.py``: the messages equal on random and
tied states, the sets against every pair).  Lengths in any one unit (simgrip passes them over ``l``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from simgrip import intersection as isect

__all__ = ["BATCH_FINGERS", "BATCH_LINKS", "all_finger_pairs", "all_self_pairs", "finger_pair_contacts",
           "finger_self_pairs"]

#: :func:`simgrip.validity.chain_violations` measures every pair of links at once (:func:`all_self_pairs`,
#: :func:`all_finger_pairs`) by default for at least this many fingers of at most ``BATCH_LINKS`` links each; for one
#: finger, or longer ones, a finger and a pair of fingers at a time, pruned.  Measured on the states the pick envs
#: check (``violation_check_times`` of :mod:`simgrip.envs.throughput`: the invalid states of 4000 random-action
#: steps, the least of 7 passes): the sphere claws (K = 3, n = 12) 354 against 786 us a state, the cradle (K = 2)
#: 265 against 398 us; a uniform curl of 5 rad through the palm's axis (``r_link = 0.03 l``), K = 3: 1.70 / 1.60 /
#: 1.38 / 1.08 / 0.69 times faster at n = 8 / 12 / 16 / 24 / 32, K = 2: 0.83--0.90 at n <= 16, K = 1: the same.
BATCH_FINGERS = 2
BATCH_LINKS = 16


def finger_self_pairs(P: np.ndarray, limit: float, gap: int) -> tuple:
    """One planar finger ``P`` ``(n+1, 2)``'s own pairs, pruned: ``(ci, cj, i, j, dist)``, the links ``ci[k] < cj[k]``
    that cross properly and the links ``i[k]``, ``j[k] >= i[k] + gap`` whose centrelines are ``dist[k] < limit``
    apart; None when the tangent-range proof clears every pair."""
    n = len(P) - 1
    # pairs j - i < low are proved clear by the tangents' range (O(n log n); the exact tests' verdict on them)
    low = isect.self_clear_below(P, limit, gap)
    if low >= n:
        return None
    cand = isect.candidate_pairs(P, limit=limit, min_gap=low)  # one pass for both tests
    ci, cj = isect.crossing_pairs(P, pairs=cand)
    far = cand[1] - cand[0] >= gap
    i, j = cand[0][far], cand[1][far]
    dist = isect.segment_distances(P[i], P[i + 1], P[j], P[j + 1]) if i.size else np.zeros(0)
    close = dist < limit
    return ci, cj, i[close], j[close], dist[close]


def finger_pair_contacts(A: np.ndarray, B: np.ndarray, limit: float, sine: float) -> tuple:
    """Fingers ``A``, ``B`` ``(n+1, d)`` from a common base at half-angle sine ``sine``, pruned: ``(i, j, dist)``,
    link ``i[k]`` of ``A`` and ``j[k]`` of ``B`` closer than ``limit``, the pairs near the base left out (``(i + j) / n
    * sine < limit``: the palm's joint)."""
    n = len(A) - 1
    i, j, dist = isect.close_link_pairs(A, limit, other=B)
    # two straight fingers from the common base: near ends at arcs s_i, s_j are >= (s_i + s_j) sin(da/2)
    # apart; pairs that close to the base are within the limit by construction (the palm's joint)
    far = (i + j) / n * sine >= limit
    return i[far], j[far], dist[far]


def _block_order(i: np.ndarray, j: np.ndarray) -> tuple:
    """``(i, j)`` sorted as :func:`~simgrip.intersection.candidate_pairs` lists them (block pair, then ``i``, ``j``),
    read-only."""
    order = np.lexsort((j, i, j // isect.BLOCK, i // isect.BLOCK))
    i, j = i[order], j[order]
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


@lru_cache(maxsize=64)
def _other_index(n: int) -> tuple:
    """Every pair of links of two ``n``-link fingers, in candidate order."""
    i, j = np.indices((n, n)).reshape(2, -1)
    return _block_order(i.astype(np.intp), j.astype(np.intp))


@lru_cache(maxsize=64)
def _self_index(n: int) -> tuple:
    """Every pair of links ``j >= i + 2`` of an ``n``-link finger, in candidate order."""
    i, j = np.triu_indices(n, 2)
    return _block_order(i.astype(np.intp), j.astype(np.intp))


def all_self_pairs(planar, limit: float, gap: int) -> list:
    """:func:`finger_self_pairs` of every finger (never None), every pair of links measured at once (module
    docstring): ``planar``, ``K`` arrays ``(n+1, 2)``, each finger in its own plane, every finger ``n >= 1`` links."""
    P = np.stack([np.asarray(p, dtype=float) for p in planar])  # (K, n+1, 2)
    K, n = P.shape[0], P.shape[1] - 1
    si, sj = _self_index(n)
    a, b = P[:, :-1], P[:, 1:]
    ai, bi, aj, bj = a[:, si], b[:, si], a[:, sj], b[:, sj]  # (K, pairs, 2)

    def orient(u, v, w):  # (crossing_pairs' arithmetic)
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])

    crossing = (orient(aj, bj, ai) * orient(aj, bj, bi) < 0) & (orient(ai, bi, aj) * orient(ai, bi, bj) < 0)
    far = sj - si >= gap
    fi, fj = si[far], sj[far]
    dist = isect.segment_distances(ai[:, far], bi[:, far], aj[:, far], bj[:, far]) if fi.size else np.zeros((K, 0))
    out = []
    for f in range(K):
        close = dist[f] < limit
        out.append((si[crossing[f]], sj[crossing[f]], fi[close], fj[close], dist[f][close]))
    return out


def all_finger_pairs(world, limit: float, sines=None) -> dict:
    """:func:`finger_pair_contacts` of every pair of fingers ``f < g`` as ``{(f, g): (i, j, dist)}``, every pair of
    links measured at once (module docstring).

    ``world``: ``K`` arrays ``(n+1, d)``, the fingers' nodes in one frame, every finger ``n >= 1`` links; ``limit``
    the least distance two links keep; ``sines[f][g]`` the sine of half the angle between fingers ``f`` and ``g`` at
    the base (None: 1).
    """
    K = len(world)
    out = {}
    if K > 1:
        W = np.stack([np.asarray(w, dtype=float) for w in world])  # (K, n+1, d)
        n = W.shape[1] - 1
        oi, oj = _other_index(n)
        fs, gs = np.triu_indices(K, 1)
        u0, u1, v0, v1 = W[fs][:, oi], W[fs][:, oi + 1], W[gs][:, oj], W[gs][:, oj + 1]  # (pairs of fingers, n^2, d)
        dist = isect.segment_distances(u0, u1, v0, v1)
        for k, (f, g) in enumerate(zip(fs.tolist(), gs.tolist())):
            sine = 1.0 if sines is None else float(sines[f][g])
            d = dist[k]
            hit = d < limit
            i, j, d = oi[hit], oj[hit], d[hit]
            keep = (i + j) / n * sine >= limit
            out[(f, g)] = (i[keep], j[keep], d[keep])
    return out
