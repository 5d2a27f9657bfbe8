"""Pure geometry of a settled chain: link-link distances and links against the workpiece's solid.

No MuJoCo, no physics: NumPy arrays in, distances out (lengths in whatever unit
the points are given; simgrip passes them over ``l``).  The physical verdicts
built on these (which distance is too close, which tolerance) are
:mod:`simgrip.validity`'s (:func:`simgrip.validity.check_valid`).

* :func:`segment_distances` -- the least distance between segment pairs
  (any dimension, vectorised; Ericson, *Real-Time Collision Detection*, 5.1.9).
* :func:`crossing_pairs` -- proper crossings of a planar polyline with itself
  (orientation tests, exact in the sign of each determinant).
* :func:`close_link_pairs` -- pairs of links of one polyline (or of two)
  closer than a limit, pruned by bounding boxes (:func:`candidate_pairs`: two
  segments whose boxes, one grown by ``limit``, do not overlap cannot be within
  it), in blocks of links first, so a smooth chain costs ``O(n)`` pairs, not ``O(n^2)``.
* :func:`self_clear_below` -- which pairs of links of a planar polyline the range of
  its tangents (then, for a curled rod, the distances of the links' midpoints) proves
  neither crossing nor within a limit (``O(n log n)``; the exact tests above then see
  only the rest).
* :func:`box_sdf`, :func:`cylinder_sdf`, :func:`sphere_sdf` -- signed distance
  to a convex solid in its own frame (negative inside).
* :func:`segment_box_sdf_2d` -- the least signed distance along planar
  segments to a rectangle, exact (see its docstring);
  :func:`segment_min_sdf` -- the same for any convex solid by golden-section
  search (the signed distance of a convex solid is convex along a line).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CLEAR_MARGIN", "FAR_PAIR_LINKS", "box_sdf", "candidate_pairs", "close_link_pairs", "crossing_pairs", "cylinder_sdf",
           "segment_box_sdf_2d", "segment_distances", "segment_min_sdf", "self_clear", "self_clear_below", "sphere_sdf"]

_EPS = 1e-300
_einsum, _where, _min, _max = np.einsum, np.where, np.minimum, np.maximum


def segment_distances(p0, p1, q0, q1) -> np.ndarray:
    """Least distance between segments ``p0 p1`` and ``q0 q1``, row by row.

    ``p0, p1, q0, q1``: arrays ``(m, d)`` (``d`` = 2 or 3), or broadcastable.
    Degenerate (zero-length) segments are points.  Exact up to round-off
    (the closest parameters clamped to ``[0, 1]`` in the order of Ericson's
    ``ClosestPtSegmentSegment``).
    """
    p0, p1, q0, q1 = (np.asarray(v, dtype=float) for v in (p0, p1, q0, q1))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = _einsum("...i,...i->...", d1, d1)
    e = _einsum("...i,...i->...", d2, d2)
    f = _einsum("...i,...i->...", d2, r)
    c = _einsum("...i,...i->...", d1, r)
    b = _einsum("...i,...i->...", d1, d2)
    # each quantity once, clipped to [0, 1] as min(max(x, 0), 1) (np.clip's values, NaN kept, without its wrapper):
    # the segment's parameters of Ericson's cases (issue 18, item 5: the same arithmetic, each quotient and clip once;
    # 55 us instead of 72 for 50 pairs, 82 instead of 104 for 432)
    a_ok, e_ok = a > _EPS, e > _EPS
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = a * e - b * b
        s = _min(_max((b * f - c * e) / _where(denom > 0, denom, 1.0), 0.0), 1.0)
        s = _where(denom > 1e-14 * _max(a * e, _EPS), s, 0.0)
        t = _where(e_ok, (b * s + f) / _where(e_ok, e, 1.0), 0.0)
        a_div = _where(a_ok, a, 1.0)
        s_start = _where(a_ok, _min(_max(-c / a_div, 0.0), 1.0), 0.0)  # p's point nearest q0 (t clamped to 0)
        s = _where(t < 0.0, s_start, s)
        s = _where(t > 1.0, _where(a_ok, _min(_max((b - c) / a_div, 0.0), 1.0), 0.0), s)
        t = _min(_max(t, 0.0), 1.0)
        # degenerate segments (Ericson's first cases): q a point -> s from p's projection; p a point -> t from q's
        e_pt = ~e_ok
        s = _where(e_pt, s_start, s)
        t = _where(e_pt, 0.0, t)
        t = _where(~a_ok & e_ok, _min(_max(f / _where(e_ok, e, 1.0), 0.0), 1.0), t)
        s = _where(a_ok, s, 0.0)
    diff = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return np.sqrt(_einsum("...i,...i->...", diff, diff))


#: Links per block of :func:`candidate_pairs`' first pass.
BLOCK = 8


def candidate_pairs(A, B=None, *, limit: float = 0.0, min_gap: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Link pairs ``(i, j)`` whose bounding boxes, grown by ``limit``, overlap: the only ones that can be within it.

    ``A`` ``(n+1, d)`` (``B`` None: its own links ``j >= i + min_gap``) or against ``B`` ``(m+1, d)``.
    Two passes: blocks of :data:`BLOCK` consecutive links (their boxes), then the links of the block pairs
    that overlap -- ``O((n/BLOCK)^2 + candidates)`` instead of ``O(n^2)``.
    """
    P = np.asarray(A, dtype=float)
    Q = P if B is None else np.asarray(B, dtype=float)
    lo_a, hi_a = np.minimum(P[:-1], P[1:]) - limit, np.maximum(P[:-1], P[1:])
    lo_b, hi_b = np.minimum(Q[:-1], Q[1:]), np.maximum(Q[:-1], Q[1:])
    na, nb = len(lo_a), len(lo_b)
    sa, sb = np.arange(0, na, BLOCK), np.arange(0, nb, BLOCK)
    blo_a, bhi_a = np.minimum.reduceat(lo_a, sa, axis=0), np.maximum.reduceat(hi_a, sa, axis=0) + limit
    blo_b, bhi_b = np.minimum.reduceat(lo_b, sb, axis=0), np.maximum.reduceat(hi_b, sb, axis=0)
    hit = np.all((blo_a[:, None] <= bhi_b[None]) & (blo_b[None] <= bhi_a[:, None]), axis=2)
    if B is None:
        hit &= np.triu(np.ones(hit.shape, dtype=bool))
    bi, bj = np.nonzero(hit)
    if bi.size == 0:
        return np.zeros(0, int), np.zeros(0, int)
    k = np.arange(BLOCK)
    i = (bi[:, None, None] * BLOCK + k[None, :, None]) + np.zeros((1, 1, BLOCK), int)
    j = (bj[:, None, None] * BLOCK + k[None, None, :]) + np.zeros((1, BLOCK, 1), int)
    i, j = i.ravel(), j.ravel()
    keep = (i < na) & (j < nb)
    if B is None:
        keep &= j >= i + min_gap
    i, j = i[keep], j[keep]
    ok = np.all((lo_a[i] <= hi_b[j] + limit) & (lo_b[j] <= hi_a[i] + limit), axis=1)
    return i[ok], j[ok]


def crossing_pairs(nodes, min_gap: int = 2, pairs=None) -> tuple[np.ndarray, np.ndarray]:
    """Links ``(i, j)``, ``j >= i + min_gap``, of the planar polyline ``nodes`` ``(n+1, 2)`` that cross properly.

    A proper crossing: each segment's end points lie strictly on opposite
    sides of the other's line (touching or collinear overlap is not one; the
    capsule distance of :func:`close_link_pairs` sees those).  ``pairs``: the
    candidates ``(i, j)`` to test (default :func:`candidate_pairs`' with no margin).
    """
    P = np.asarray(nodes, dtype=float)
    a, b = P[:-1], P[1:]
    m = len(a)
    if m < min_gap + 1:
        return np.zeros(0, int), np.zeros(0, int)
    # segments whose bounding boxes do not overlap cannot cross
    i, j = candidate_pairs(P, min_gap=min_gap) if pairs is None else (np.asarray(pairs[0]), np.asarray(pairs[1]))

    def orient(u, v, w):
        return (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])

    d1 = orient(a[j], b[j], a[i])
    d2 = orient(a[j], b[j], b[i])
    d3 = orient(a[i], b[i], a[j])
    d4 = orient(a[i], b[i], b[j])
    hit = (d1 * d2 < 0) & (d3 * d4 < 0)
    return i[hit], j[hit]


def close_link_pairs(nodes, limit: float, *, min_gap: int = 2, other=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pairs of links closer than ``limit``: ``(i, j, distance)``.

    ``nodes`` ``(n+1, d)``: one polyline; its links ``i < j`` with ``j - i >=
    min_gap`` are compared.  With ``other`` ``(m+1, d)``: every link ``i`` of
    ``nodes`` against every link ``j`` of ``other`` (``min_gap`` ignored).
    Candidate pairs are pruned by bounding boxes (:func:`candidate_pairs`), then
    measured exactly (:func:`segment_distances`).
    """
    P = np.asarray(nodes, dtype=float)
    Q = P if other is None else np.asarray(other, dtype=float)
    a0, a1, b0, b1 = P[:-1], P[1:], Q[:-1], Q[1:]
    i, j = candidate_pairs(P, None if other is None else Q, limit=limit, min_gap=min_gap)
    if i.size == 0:
        return i, j, np.zeros(0)
    dist = segment_distances(a0[i], a1[i], b0[j], b1[j])
    hit = dist < limit
    return i[hit], j[hit], dist[hit]


#: Relative margin by which :func:`self_clear`'s lower bound must clear the limit: the bound and the exact
#: distances it stands for are both computed in floating point (round-off ~1e-16 of the chain's size), so
#: a bound this far above the limit proves the exact test's answer too, not only the exact arithmetic's.
CLEAR_MARGIN = 1e-9


def self_clear(nodes, limit: float, gap: int) -> bool:
    """True when no two links of the planar polyline can cross or come within ``limit`` (proved, O(n log n)).

    ``self_clear_below(nodes, limit, gap) >= len(nodes) - 1``: see there.
    """
    return self_clear_below(nodes, limit, gap) >= len(nodes) - 1


def self_clear_below(nodes, limit: float, gap: int) -> int:
    """The least index gap ``d`` of the pairs of links this proof leaves open (``>= n``: none left; 2: none proved).

    ``nodes`` ``(n+1, 2)``; ``gap``: the least index gap of the pairs whose distance counts
    (:func:`simgrip.validity.self_gap_links`).  Every pair of links ``(i, j)`` with ``2 <= j - i < d`` is
    proved neither to cross nor (``j - i >= gap``) to be closer than ``limit``: the exact pair tests of
    :func:`simgrip.validity.chain_violations` give the same verdict on them, so they need to see only the
    pairs ``j - i >= d``.  The proof: let links ``i..j`` all have their directions within ``R/2`` of one unit
    vector ``u`` (``R``, the range of their angles, below ``pi``).  Along the rod from a
    point ``p`` of link ``i`` to a point ``q`` of link ``j``, the tangent's projection on ``u`` is at least
    ``cos(R/2) > 0``, so ``|q - p| >= (q - p).u >= cos(R/2)`` times the arc between them, which covers the
    ``j - i - 1`` whole links between: ``|q - p| >= (j - i - 1) h_min cos(R/2)``; and the projections of
    links ``i`` and ``j >= i + 2`` are disjoint intervals of ``u``, so they do not cross.  The pairs are taken
    in bands of ``d = j - i``: ``[2, gap)`` (crossings only), then ``[d_k, 2 d_k)`` from ``d_1 = gap``, each
    with ``R`` the largest range over windows of ``2 d_k`` consecutive links (every pair of the band lies in
    one; doubled windows from the halves' extremes, so O(n) a band) and the bound ``(d_k - 1) h_min
    cos(R/2)``, which must exceed ``limit`` by :data:`CLEAR_MARGIN` (bounds and exact distances are both
    computed in floating point).  A smooth rod, whose tangent turns little over a short arc, passes at
    every ``n``; where a band's window is curled through ``pi`` or more, the pairs from that band's ``d_k``
    on are tried by the links' midpoints instead (:func:`_far_pairs_clear`: a uniform curl of ``|kappa_bar|``
    up to ~2 pi passes), and only where that fails too are they left to the exact tests.
    """
    P = np.asarray(nodes, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 2:
        return 2
    m = len(P) - 1
    gap = max(int(gap), 2)
    d = P[1:] - P[:-1]
    h_min = float(np.sqrt(np.min(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])))
    need = float(limit) * (1.0 + CLEAR_MARGIN)
    if not h_min > 0.0:
        return 2
    # the links' angles, each turn from the last taken in (-pi, pi] (any 2 pi shifts leave the directions, the
    # proof's input, alone): the first link's 0, then the running sum of the turns
    turn = np.arctan2(d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0], d[:-1, 0] * d[1:, 0] + d[:-1, 1] * d[1:, 1])
    angle = np.zeros(m)
    np.cumsum(turn, out=angle[1:])
    R = float(angle.max() - angle.min())
    if R < math.pi and (gap - 1) * h_min * math.cos(0.5 * R) > need:
        return m  # one band for every pair: the whole rod's range
    # the bands; hi/lo[i]: the extremes of the window of w links starting at link i
    hi, lo, w = angle, angle, 1

    def grow(w_new):
        nonlocal hi, lo, w
        while w < w_new:
            step = min(w, w_new - w)
            hi = np.maximum(hi[:len(hi) - step], hi[step:])
            lo = np.minimum(lo[:len(lo) - step], lo[step:])
            w += step
        return float((hi - lo).max())

    if gap > 2:  # d in [2, gap): crossings only; separation >= h_min cos(R/2), kept well above round-off
        R = grow(min(gap, m))
        if not (R < math.pi and math.cos(0.5 * R) > 1e-6):
            return 2
    d_k = gap
    while d_k <= m - 1:
        R = grow(min(2 * d_k, m))
        if not (R < math.pi and (d_k - 1) * h_min * math.cos(0.5 * R) > need):
            return m if _far_pairs_clear(P, d, d_k, need) else d_k
        d_k *= 2
    return m


#: The most links on each side of :func:`_far_pairs_clear`'s pairs (its work is their square: 128 x 128 ~ 30 us).
FAR_PAIR_LINKS = 128


def _far_pairs_clear(P, d, d_k: int, need: float) -> bool:
    """True when every pair of links ``j - i >= d_k`` of the polyline ``P`` is proved farther apart than ``need``.

    ``d = P[1:] - P[:-1]`` (the links).  The proof, for the rods :func:`self_clear_below`'s tangent range leaves
    open (curled through ``pi`` or more over a band's window, e.g. a uniform curl ``|kappa_bar| > pi``): every
    point of link ``k`` lies within ``h_k / 2`` of its midpoint ``c_k`` (a segment is within half its length of
    its centre), so by the triangle inequality any two points of links ``i`` and ``j`` are at least
    ``|c_i - c_j| - h_i / 2 - h_j / 2`` apart.  When that bound exceeds ``need`` (``limit`` raised by
    :data:`CLEAR_MARGIN`, which covers the round-off of the bound and of the exact distances) for every pair,
    no pair is within ``limit`` and none crosses (crossing links are 0 apart).  ``O(K^2)`` for the ``K = n -
    d_k`` links on each side, so only tried for ``K <= FAR_PAIR_LINKS``; False (not proved) otherwise.
    """
    m = len(d)
    K = m - d_k
    if K <= 0:
        return True
    if K > FAR_PAIR_LINKS:
        return False
    c = P[:-1] + 0.5 * d  # midpoints
    half = 0.5 * np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    # pair (a, b): link i = a, link j = d_k + b; j - i >= d_k is b >= a (the upper triangle with its diagonal)
    dx = c[:K, 0, None] - c[None, d_k:, 0]
    dy = c[:K, 1, None] - c[None, d_k:, 1]
    bound = np.sqrt(dx * dx + dy * dy) - half[:K, None] - half[None, d_k:]
    a = np.arange(K)
    return bool(np.min(bound, where=a[:, None] <= a[None, :], initial=np.inf) > need)


def box_sdf(points, half) -> np.ndarray:
    """Signed distance of ``points`` ``(..., d)`` to the box ``|x_k| <= half_k`` (its own frame; negative inside)."""
    q = np.abs(np.asarray(points, dtype=float)) - np.asarray(half, dtype=float)
    m = np.maximum(q, 0.0)  # (np.linalg.norm's axis sum sqrt(sum m * m) and np.max's reduction, without their wrappers)
    outside = np.sqrt(np.add.reduce(m * m, axis=-1))
    return outside + np.minimum(np.maximum.reduce(q, axis=-1), 0.0)


def cylinder_sdf(points, radius: float, half_height: float) -> np.ndarray:
    """Signed distance of ``points`` ``(..., 3)`` to the solid cylinder about the local ``z`` axis (radius, half height)."""
    p = np.asarray(points, dtype=float)
    q = np.stack([np.hypot(p[..., 0], p[..., 1]) - radius, np.abs(p[..., 2]) - half_height], axis=-1)
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(np.max(q, axis=-1), 0.0)


def sphere_sdf(points, radius: float) -> np.ndarray:
    """Signed distance of ``points`` ``(..., d)`` to the ball of ``radius`` about the origin."""
    return np.linalg.norm(np.asarray(points, dtype=float), axis=-1) - radius


def segment_box_sdf_2d(a, b, half) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance along planar segments ``a b`` ``(m, 2)`` to the rectangle ``|x| <= half`` (its frame).

    Returns ``(sdf, t)``: the least value and where (``a + t (b - a)``).  Exact: the signed
    distance is convex along the segment; outside the rectangle it is the Euclidean distance,
    least at an end point or at the foot of a corner on the segment; inside it is the largest of
    the four face functions ``+-x_k - half_k``, linear in ``t``, least at an end point or where
    two of them are equal.  All those parameters (clipped to ``[0, 1]``) are evaluated.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    h = np.asarray(half, dtype=float)
    d = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", d, d), _EPS)
    cand = [np.zeros(len(a)), np.ones(len(a))]
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            c = np.array([sx * h[0], sy * h[1]])
            cand.append(np.einsum("ij,ij->i", c - a, d) / L2)
    # face functions g_k(t) = s_k x_k(t) - h_k, k over (x+, x-, y+, y-); breakpoints g_k = g_l
    faces = [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)]
    with np.errstate(divide="ignore", invalid="ignore"):
        for u in range(4):
            for v in range(u + 1, 4):
                (ku, su), (kv, sv) = faces[u], faces[v]
                slope = su * d[:, ku] - sv * d[:, kv]
                off = su * a[:, ku] - h[ku] - (sv * a[:, kv] - h[kv])
                cand.append(np.where(np.abs(slope) > _EPS, -off / np.where(slope == 0, 1.0, slope), 0.0))
    T = np.clip(np.stack(cand, axis=1), 0.0, 1.0)  # (m, 22)
    pts = a[:, None, :] + T[..., None] * d[:, None, :]
    val = box_sdf(pts, h)
    k = np.argmin(val, axis=1)
    rows = np.arange(len(a))
    return val[rows, k], T[rows, k]


#: Golden-section iterations of :func:`segment_min_sdf`: the bracket shrinks by 0.618 each, so 48 of them
#: leave ``0.618**48 ~ 1e-10`` of the segment, and the signed distance (1-Lipschitz) is found to that.
GOLDEN_ITERATIONS = 48


def segment_min_sdf(sdf, a, b, iterations: int = GOLDEN_ITERATIONS) -> tuple[np.ndarray, np.ndarray]:
    """Least value of the signed distance ``sdf(points)`` along segments ``a b`` ``(m, d)``: ``(value, t)``.

    ``sdf`` must be a convex solid's (convex along every line, so one minimum);
    golden-section search in ``t`` vectorised over the segments, the end points
    compared too (a minimum at an end is found exactly).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    d = b - a
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    lo, hi = np.zeros(len(a)), np.ones(len(a))
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = sdf(a + x1[:, None] * d), sdf(a + x2[:, None] * d)
    for _ in range(int(iterations)):
        left = f1 < f2  # the minimum lies in [lo, x2]: drop (x2, hi]; else in [x1, hi]: drop [lo, x1)
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        keep_x, keep_f = np.where(left, x1, x2), np.where(left, f1, f2)  # the surviving interior point
        x_new = np.where(left, hi - g * (hi - lo), lo + g * (hi - lo))
        f_new = sdf(a + x_new[:, None] * d)
        x1, f1 = np.where(left, x_new, keep_x), np.where(left, f_new, keep_f)
        x2, f2 = np.where(left, keep_x, x_new), np.where(left, keep_f, f_new)
    t = np.stack([np.zeros(len(a)), np.ones(len(a)), 0.5 * (lo + hi)], axis=1)
    val = sdf(a[:, None, :] + t[..., None] * d[:, None, :])
    k = np.argmin(val, axis=1)
    rows = np.arange(len(a))
    return val[rows, k], t[rows, k]
