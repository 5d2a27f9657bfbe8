"""Whether a pick environment's fingers pass through themselves or each other: ``info["valid"]`` (issue 17).

In the pick scenes every link and tip has a contact pair with the box, so MuJoCo keeps them out of it; what it
cannot prevent is a finger crossing itself (a strongly curled finger has no self-contact) and two fingers
passing through each other (no finger-finger pairs).  :class:`FingerValidity` checks exactly those two with
:func:`simgrip.validity.chain_violations` (the one implementation every path runs), behind a screen that
keeps the usual step cheap:

* pure Python on the hinge angles: every link of every finger within ``pi/2 - delta`` of its start
  direction: each finger advances along it at least ``sin(delta)`` per unit arc, so it cannot cross
  itself, its compared links (an arc ``g >= pi r_link`` apart, :func:`simgrip.validity.self_gap_links`)
  are at least ``pi r_link sin(delta)`` apart, and two fingers from a common base at an angle ``da`` at
  least ``(s_i + s_j) sin(delta) sin(da/2)`` (the compared pairs' arc sums are whole links); ``delta`` is
  the least that puts all of these above the ``(2 - DEPTH_FRACTION) r_link`` limit (at build);
* a finger that turned at most ``pi/2`` in all cannot reach itself (tangents within ``pi/4`` of one
  direction: compared links at least ``pi r_link cos(pi/4) = 2.2 r_link`` apart);
* links whose midpoints are farther apart than the limit plus their half lengths cannot be within it
  (one broadcast over every pair of links of every finger; for two fingers from a common base, the pairs
  that close to it are the palm's joint and not compared, :func:`simgrip.validity.chain_violations`).

The last screen runs as one matrix product over every pair of links in preallocated buffers
(:meth:`FingerValidity._bound`: the midpoint bound against the exact path's clearance, with every hinge
within ``pi/2``): it answers valid only where the steps below would, and it goes straight to
:func:`~simgrip.validity.chain_violations` only where they would, so it changes no verdict, only the cost
(issue 18: six numpy calls instead of ~20 and the pair gathers; a model whose rows would pass ``BOUND_MAX_ENTRIES``,
~(K n)^3 / 2 entries, has no screen and goes to the exact path).  Before the pair rows it tries **coarse rows**
(:func:`_coarse_spans`): the links cut into runs of ``c ~ sqrt(n)`` links, one row per pair of runs whose link pairs
are all compared.  Every point of a run lies within half its arc of its chord's midpoint ``M`` (from a point at arc
``s`` of ``a`` nodes ``A``, ``B``: ``|p - A| <= s``, ``|p - B| <= a - s``), and a link's midpoint ``m`` within half the
run's arc less half the link's of ``M``, so ``|M_A - M_B| - a_A/2 - a_B/2`` is at most each covered pair's midpoint
bound ``|m_i - m_j| - h_i - h_j``: a run pair cleared clears each of its pairs' rows, and all coarse rows cleared answer
valid as the pair rows would (the pairs of runs that mix compared and not compared link pairs, e.g. adjacent runs of
one finger, keep their compared pairs' own rows).  ``n = 12``: 65 rows for two fingers instead of 233, 132 for three
instead of 564; the usual state is cleared there (issue 18, item 5: ``Pick-v1`` checks every step).
A state past the first screen has its hinges between links checked for a half turn or more
(:func:`simgrip.validity_hinges.folded_hinges`, what the node checks cannot see; then the messages are those and
``chain_violations``'). Only what the screen lets through is measured
exactly: first the pairs the bound left open, by their exact
segment distance (:func:`simgrip.intersection.segment_distances`, what the exact check measures): all of them
farther than the limit (by the relative ``CLEAR_MARGIN``) and every hinge within ``pi/2`` (adjacent links cannot
fold onto each other) prove the state valid; only otherwise (a violation, or too close to call) does
:func:`simgrip.validity.chain_violations` run and word the messages.  The verdict and messages are those of
``chain_violations`` alone (``tests/test_pick_validity.py``).  World nodes are MuJoCo's (the link bodies' origins and
the tip geoms), so the palm's pose and each finger's plane need no bookkeeping.

**Checking every k-th step** (issue 18: with curled fingers the screen lets most pairs through and the exact
check costs ~2x a control step's physics).  ``FingerValidity(..., every=k)`` runs the check on the first step
after :meth:`FingerValidity.restart` and then every ``k``-th call, and returns the last result on the calls
between (``every = 1``, the default, checks every call).  A caller that declares success or ends the
episode passes ``force=True`` (:meth:`FingerValidity.__call__`), so a success is always checked at the step it
is declared: an impossible state never counts as a success.  The fragile envs use ``every =
FRAGILE_VALIDITY_EVERY``.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.intersection import CLEAR_MARGIN, segment_distances
from simgrip.validity import SELF_LIMIT_FACTOR, chain_violations

__all__ = ["BOUND_MAX_ENTRIES", "FingerValidity", "FRAGILE_VALIDITY_EVERY", "record_validity"]

#: the fragile envs' check period [control steps]: 25 steps = 0.5 s at 50 Hz (a violation is a configuration the
#: fingers hold for a while; every terminating step, a success included, is checked regardless)
FRAGILE_VALIDITY_EVERY = 25

#: at most this many pair lists are kept (one per pattern of finger pairs compared; K = 2 has 8 patterns, K = 3 64)
_PAIR_CACHE = 256

#: relative margin of :meth:`FingerValidity._bound_clear`'s thresholds over round-off (~1e-16 of the chain's size)
_ROUND_OFF = 1e-8
_HALF_PI = 0.5 * math.pi
#: the most entries of the screen's pair rows (:meth:`FingerValidity._bound`: one row per compared pair of links, a
#: column per node, ~(K n)^3 / 2 for K fingers of n links; 2^22 float64 = 32 MiB, held twice): a larger model is
#: checked by the exact path alone (the same verdicts; two fingers of 1000 links would need ~60 GiB of rows)
BOUND_MAX_ENTRIES = 1 << 22
_min = np.minimum.reduce  # ndarray.min without its Python wrapper


def _coarse_spans(keep: np.ndarray, K: int, n: int) -> list:
    """The coarse rows of :meth:`FingerValidity._bound` as pairs of runs ``((f, a, b), (g, c, e))``: the links are cut
    into runs of ``c = max(2, round(sqrt(n)))``; a pair of runs all of whose link pairs ``keep`` (the pair matrix,
    ``K n`` square) compares is one row, and of any other pair of runs each compared link pair is its own row."""
    c = max(2, int(round(math.sqrt(n))))
    runs = [(a, min(a + c, n)) for a in range(0, n, c)]
    spans = []
    for f in range(K):
        for g in range(f, K):
            for a, b in runs:
                for c0, e in runs:
                    block = keep[f * n + a:f * n + b, g * n + c0:g * n + e]
                    if block.all():
                        spans.append(((f, a, b), (g, c0, e)))
                    else:
                        spans += [((f, a + i, a + i + 1), (g, c0 + j, c0 + j + 1)) for i, j in zip(*np.nonzero(block))]
    return spans


def record_validity(info: dict, invalid: list) -> bool:
    """Write a fresh check's result into a step's ``info``: ``info["valid"]``, and ``info["invalid"]`` (the
    messages) only when there are any, an older one dropped.  Returns whether the state is valid."""
    info["valid"] = not invalid
    info.pop("invalid", None)
    if invalid:
        info["invalid"] = invalid
    return not invalid


class FingerValidity:
    """Callable ``probe(q, data) -> list of messages`` (empty: valid) for a pick model's fingers.

    ``model``: the env's MuJoCo model (read once: the link radius); ``index``: its
    :class:`~simgrip.sim.fingers.FingerIndex`; ``q``: ``data.qpos.tolist()`` (the step already has it),
    ``data`` the env's ``MjData``.  Lengths are the model's (m).  Keeps views of the last ``data`` it read
    (dropped when pickled: picklable).
    ``every``: check on every ``every``-th call only (module docstring), a positive int; ``checked`` says
    whether the last call ran the check.
    """

    def __init__(self, model, index, every: int = 1):
        import mujoco

        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise ValueError(f"every must be a positive integer, got {every!r}")
        self.every = int(every)
        self._calls = 0
        self._last: list = []
        self.checked = False

        self._bodies = np.asarray(index.link_body, dtype=int)
        self._tips = np.asarray(index.tip_geom, dtype=int)
        self._jq = [[int(v) for v in row] for row in np.asarray(index.joint_qpos)]
        self._r = float(model.geom_size[int(np.asarray(index.link_geom)[0, 0])][0])
        self._limit = SELF_LIMIT_FACTOR * self._r
        self._flat = self._bodies.ravel()
        # each finger's plane: the horizontal direction of its first link at the model's rest pose (the palm
        # only slides vertically, the hinges turn about horizontal axes: it never changes)
        d0 = mujoco.MjData(model)
        mujoco.mj_forward(model, d0)
        w0 = self.nodes(d0)
        K, n = self._bodies.shape
        dirs = []
        for w in w0:
            e1 = w[1] - w[0]
            e1[2] = 0.0
            dirs.append(e1 / max(float(np.linalg.norm(e1)), 1e-300))
        self._dirs = dirs
        self._length = float(np.sum(np.linalg.norm(np.diff(w0[0], axis=0), axis=1)))
        common = np.array([[np.linalg.norm(w0[f][0] - w0[g][0]) < self._limit for g in range(K)] for f in range(K)])
        cos = np.clip(np.array([[float(dirs[f] @ dirs[g]) for g in range(K)] for f in range(K)]), -1.0, 1.0)
        # two straight fingers from a common base: near ends at arcs s_i, s_j are >= (s_i + s_j) sin(da/2) apart
        self._sines = np.where(common, np.abs(np.sin(0.5 * np.arccos(cos))), 1.0)
        i = np.arange(n)
        pair_gap = (i[:, None] + i[None, :]) / n * self._length  # arc lengths of the near ends, summed [m]
        mask = np.zeros((K, K, n, n), dtype=bool)
        for f in range(K):
            mask[f, f] = i[None, :] >= i[:, None] + 2
            for g in range(f + 1, K):
                mask[f, g] = pair_gap * self._sines[f, g] >= self._limit
        self._mask = mask
        self._pair_cache: dict = {}
        # links one link apart are proved clear by the link between them when every link is longer than the limit
        # (rigid links: their lengths change by round-off only, far inside this margin)
        self._skip_one = float(np.min([np.linalg.norm(np.diff(w, axis=0), axis=1).min() for w in w0])) \
            >= self._limit * (1.0 + 1e-6)
        # the pure-Python screen (:meth:`_mild`): every link within pi/2 - delta of its finger's start direction,
        # delta the least margin that keeps every compared pair apart (module docstring)
        ds = self._length / n
        need = SELF_LIMIT_FACTOR / math.pi  # one finger: pi r_link sin(delta) >= (2 - DEPTH_FRACTION) r_link
        for f in range(K):
            for g in range(f + 1, K):
                sine = float(self._sines[f, g])
                k_min = max(1, math.ceil(self._limit / (ds * sine) - 1e-12)) if sine > 0 else 1
                need = max(need, self._limit / (k_min * ds * sine) if sine > 0 else 2.0)
        self._cap = 0.5 * math.pi - math.asin(need) if need < 1.0 else -1.0
        self._bind_bound(w0, n)

    def _bind_bound(self, w0: list, n: int) -> None:
        """Precompute :meth:`_bound_clear`'s pair matrices, thresholds and buffers (the links' half lengths at the rest
        pose: rigid links keep them to round-off)."""
        K = len(w0)
        half = np.concatenate([0.5 * np.linalg.norm(np.diff(w, axis=0), axis=1) for w in w0])
        keep = np.zeros((K * n, K * n), dtype=bool)
        for f in range(K):
            for g in range(f, K):
                keep[f * n:(f + 1) * n, g * n:(g + 1) * n] = self._mask[f, g]
        if self._skip_one:  # links i and i+2 of one finger: proved apart by the link between them (_near_clear)
            i = np.arange(K * n - 2)
            keep[i, i + 2] &= (i // n) != ((i + 2) // n)
        self._hinges = [a for row in self._jq for a in row]
        # the hinges' qpos as one slice where contiguous (the builder's case): _bound reads their min and max
        h = self._hinges
        self._hinge_slice = slice(h[0], h[-1] + 1) if h == list(range(h[0], h[0] + len(h))) else None
        self._views = (None, None, None)  # (data, its xpos rows, its geom_xpos rows): _bind_views
        bodies, tips = self._bodies, self._tips
        self._body_cols = (int(bodies.min()), int(bodies.max()) + 1)
        self._tip_cols = (int(tips.min()), int(tips.max()) + 1)
        self._nb = self._body_cols[1] - self._body_cols[0]
        columns = self._nb + self._tip_cols[1] - self._tip_cols[0]
        if int(np.count_nonzero(keep)) * columns > BOUND_MAX_ENTRIES:  # (K n)^3 / 2 entries: no screen, exact path
            self._QT = None
            return
        pi, pj = np.nonzero(keep)
        # twice the midpoint of link k of finger f is node k + node k+1 (nodes: the link bodies' origins in
        # data.xpos, then the tip geom in data.geom_xpos); one row per pair holds S_i - S_j as +-1 entries over
        # the span of bodies and the span of tip geoms, so the pairs' differences are two matrix products
        # a pair is cleared when its midpoints are farther apart than the exact path's clearance plus both half
        # lengths, the relative _ROUND_OFF above it: the bound and the exact distances are computed in floating
        # point (~1e-16 of the coordinates, metres from the origin at most).  Each row is divided by twice its
        # threshold T, so a pair is cleared when its row's squared norm is at least 1
        spans = [((a // n, a % n, a % n + 1), (b // n, b % n, b % n + 1)) for a, b in zip(pi.tolist(), pj.tolist())]
        self._Qb, self._Qt, T = self._rows(spans, half, n)
        # _bound's one product: the nodes' coordinates (bodies, then tips) gathered in _P, times the rows of both
        # matrices side by side, transposed (3 x pairs: BLAS's fast shape for three coordinates)
        self._QT = np.ascontiguousarray(np.hstack([self._Qb, self._Qt]).T)
        # the coarse rows tried first (:meth:`_bound`): the same bound over runs of links (module docstring)
        Cb, Ct, _ = self._rows(_coarse_spans(keep, K, n), half, n)
        self._QcT = np.ascontiguousarray(np.hstack([Cb, Ct]).T)
        self._DcT = np.empty((3, self._QcT.shape[1]))
        self._dc2 = np.empty(self._QcT.shape[1])
        self._P = np.empty((columns, 3))
        self._DT = np.empty((3, pi.size))
        # the other way round: midpoints closer than the clearance (by _ROUND_OFF) put the pair's exact distance
        # below it, so the exact path cannot prove the state valid (:meth:`_bound`); same scale as the rows
        self._C = (self._limit * (1.0 + CLEAR_MARGIN) * (1.0 - _ROUND_OFF) / T) ** 2
        self._pair_self = np.where(pi // n == pj // n, pi // n, -1).tolist()  # the finger of a self pair, else -1
        self._d2 = np.empty(pi.size)
        self._ones = np.ones(3)

    def _bind_views(self, data) -> tuple:
        """``(data, data.xpos[bodies], data.geom_xpos[tips])``: the views :meth:`_bound` copies the nodes from, kept
        for the next call with the same ``data`` (issue 18: two attribute lookups and slices a step fewer)."""
        (b0, b1), (t0, t1) = self._body_cols, self._tip_cols
        self._views = views = (data, data.xpos[b0:b1], data.geom_xpos[t0:t1])
        return views

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_views"] = (None, None, None)  # views of one MjData: bound again on the next call
        return state

    def _rows(self, spans: list, half: np.ndarray, n: int) -> tuple:
        """The bound's rows for ``spans``, pairs of runs of links ``((f, a, b), (g, c, e))`` (links ``a .. b-1`` of
        finger ``f`` against links ``c .. e-1`` of finger ``g``): per row ``(S_A - S_B) / (2 T)`` as its body and tip
        columns, ``S`` a run's end nodes summed (twice its chord's midpoint), ``T`` the exact path's clearance plus
        both runs' half arcs (the half lengths ``half`` summed), the relative ``_ROUND_OFF`` above; and ``T``."""
        bodies, tips = self._bodies, self._tips
        Qb = np.zeros((len(spans), self._body_cols[1] - self._body_cols[0]))
        Qt = np.zeros((len(spans), self._tip_cols[1] - self._tip_cols[0]))
        T = np.empty(len(spans))
        for row, runs in enumerate(spans):
            T[row] = self._limit * (1.0 + CLEAR_MARGIN)
            for (f, a, b), sign in zip(runs, (1.0, -1.0)):
                T[row] += float(np.sum(half[f * n + a:f * n + b]))
                for node in (a, b):
                    if node < n:
                        Qb[row, bodies[f, node] - self._body_cols[0]] += sign
                    else:
                        Qt[row, tips[f] - self._tip_cols[0]] += sign
        T *= 1.0 + _ROUND_OFF
        return Qb / (2.0 * T[:, None]), Qt / (2.0 * T[:, None]), T

    def nodes(self, d) -> list:
        """Each finger's world nodes ``(n+1, 3)`` [m] in ``d``: its link bodies' origins, then its tip."""
        K, n = self._bodies.shape
        xs = np.asarray(d.xpos)[self._flat].reshape(K, n, 3)
        tips = np.asarray(d.geom_xpos)[self._tips]
        return [np.vstack([xs[f], tips[f:f + 1]]) for f in range(K)]

    def _mild(self, q: list) -> bool:
        """Every finger's link angles within the screen's cap of its start: no violation possible (module docstring)."""
        cap = self._cap
        for row in self._jq:
            phi = 0.0
            for a in row:
                phi += q[a]
                if phi > cap or phi < -cap:
                    return False
        return True

    def restart(self) -> None:
        """A new episode: the next call checks."""
        self._calls = 0
        self._last = []

    def __call__(self, q: list, data, force: bool = False) -> list:
        """The violation messages in this state (empty: valid); between every-k checks, the last check's."""
        calls = self._calls
        self._calls = calls + 1
        if force or calls % self.every == 0:  # (every == 1: always)
            self.checked = True
            self._last = last = self._check(q, data)
        else:
            self.checked = False
            last = self._last
        return list(last) if last else []  # a new list either way (the caller's to keep)

    def check_now(self, q: list, data) -> list:
        """Check this state now, whatever the every-k schedule says, without moving the schedule: the messages
        (empty: valid), also kept as the last check's result.  For a reward paid mid-episode on the strength of
        a state (:mod:`simgrip.envs.pick_place_v6`'s grip), which a between-checks step would otherwise judge
        by an older check."""
        self.checked = True
        self._last = last = self._check(q, data)
        return list(last) if last else []

    def _bound_clear(self, q: list, data) -> bool:
        """:meth:`_bound` proves the state valid."""
        return self._bound(q, data) > 0

    def _bound(self, q: list, data) -> int:
        """1 when every pair the exact path could compare is proved clear by its midpoint bound (module docstring):
        every hinge within ``pi/2``, and for every pair of the mask (links ``i``, ``i + 2`` of one finger aside, as
        :meth:`_near_clear` sets them aside) ``|M_i - M_j| - h_i - h_j`` above the exact path's clearance ``(1 +
        CLEAR_MARGIN)`` times the limit by the relative ``_ROUND_OFF``: whatever the exact path would then compare,
        its bound or its exact distances clear it, so it answers valid too.  -1 when the exact path cannot prove
        it valid: a pair it compares (a pair of two fingers: their nodes' boxes come within the limit; of one
        finger: one that turned more than ``pi/2``) has midpoints closer than the clearance, so it is near and its
        exact distance is below the clearance (:meth:`_near_clear` fails), and only
        :func:`~simgrip.validity.chain_violations` decides.  0 otherwise.  Shortcuts to the same verdict: one
        matrix product gives every pair's midpoint difference over its threshold (precomputed rows, transposed:
        3 x pairs), six numpy calls in preallocated buffers instead of the exact path's ~20 and its gathers; the coarse
        rows first (module docstring: all of them cleared clear every pair's row), then the pair rows."""
        h = self._hinge_slice
        if h is not None:  # the step's state is finite (checked before): min / max decide as the loop below
            qh = q[h]
            if not (-_HALF_PI < min(qh) and max(qh) < _HALF_PI):
                return 0
        else:
            for a in self._hinges:
                if not -_HALF_PI < q[a] < _HALF_PI:
                    return 0
        if self._QT is None:  # a model too large for the screen's rows (BOUND_MAX_ENTRIES): the exact path decides
            return 0
        if not self._d2.size:  # no pair is ever compared (the exact path answers valid too)
            return 1
        views = self._views
        if views[0] is not data:  # the nodes' rows of data.xpos and data.geom_xpos, bound once per data
            views = self._bind_views(data)
        P, nb = self._P, self._nb
        P[:nb] = views[1]
        P[nb:] = views[2]
        # first the coarse rows (runs of links: a quarter of the rows for n = 12); all cleared clears every pair
        D = np.dot(P.T, self._QcT, out=self._DcT)
        np.multiply(D, D, out=D)
        if _min(np.dot(self._ones, D, out=self._dc2)) >= 1.0:
            return 1
        D = np.dot(P.T, self._QT, out=self._DT)  # (S_i - S_j) / (2 T) of every pair, one column each
        np.multiply(D, D, out=D)
        d2 = np.dot(self._ones, D, out=self._d2)
        if _min(d2) >= 1.0:
            return 1
        for p in np.flatnonzero(d2 < self._C).tolist():
            f = self._pair_self[p]
            if f < 0 or self._turned_one(q, f):
                return -1
        return 0

    def _check(self, q: list, data) -> list:
        if self._cap > 0.0 and self._mild(q):
            return []
        folded = self._folded(q)  # what no node check can see (simgrip.validity_hinges); a mild state has none
        if folded:
            return folded + self._violations(self._world(data))
        bound = self._bound(q, data)
        if bound > 0:
            return []
        W = self._world(data)  # (K, n+1, 3)
        if bound < 0:
            return self._violations(W)
        K = W.shape[0]
        # the pairs compared: the self pairs of each finger that turned more than pi/2 (one that turned less cannot
        # reach itself, module docstring) and the pairs of two fingers whose nodes' bounding boxes come within the
        # limit (each link lies in its nodes' box: boxes farther apart keep every pair farther apart)
        lo, hi = W.min(axis=1).tolist(), W.max(axis=1).tolist()
        lim = self._limit * (1.0 + CLEAR_MARGIN)
        keys = []
        for f in range(K):
            if self._turned_one(q, f):
                keys.append((f, f))
            lf, hf = lo[f], hi[f]
            for g in range(f + 1, K):
                lg, hg = lo[g], hi[g]
                if (lg[0] - hf[0] < lim and lf[0] - hg[0] < lim and lg[1] - hf[1] < lim and lf[1] - hg[1] < lim
                        and lg[2] - hf[2] < lim and lf[2] - hg[2] < lim):
                    keys.append((f, g))
        i, j = self._pairs(tuple(keys))
        if not i.size:
            return []
        # every point of a link lies within half its length of its midpoint: a lower bound of each pair's distance
        # (np.linalg.norm's arithmetic, over the compared pairs only)
        M = (0.5 * (W[:, 1:] + W[:, :-1])).reshape(-1, 3)
        E = W[:, 1:] - W[:, :-1]
        h = (0.5 * np.sqrt(np.add.reduce(E * E, axis=2))).ravel()
        D = M[i] - M[j]
        near = np.sqrt(np.add.reduce(D * D, axis=1)) - h[i] - h[j] < self._limit
        if not near.any():
            return []
        if self._near_clear(q, W, i[near], j[near]):
            return []
        return self._violations(W)

    def _folded(self, q: list) -> list:
        """:func:`simgrip.validity_hinges.folded_hinges`' messages for the hinges between links (each finger's row of
        ``_jq`` but its clamp hinge): none unless one turned by ``pi`` or more."""
        for row in self._jq:
            for a in row[1:]:
                if not -math.pi < q[a] < math.pi:
                    from simgrip.validity_hinges import folded_hinges

                    return [m for _, m in folded_hinges([[q[b] for b in r] for r in self._jq])]
        return []

    def _violations(self, W: np.ndarray, batch: bool | None = None) -> list:
        """:func:`~simgrip.validity.chain_violations`' messages for the nodes ``W`` ``(K, n+1, 3)`` [m] (``batch``: its
        own)."""
        K = W.shape[0]
        world = [W[f] for f in range(K)]
        planar = []
        for f, w in enumerate(world):
            rel = w - w[0]
            planar.append(np.stack([rel @ self._dirs[f], rel[:, 2]], axis=1))
        L = self._length
        # chain_violations works over l: scale the nodes to the finger's length
        found = chain_violations([p / L for p in planar], [w / L for w in world], r_link=self._r / L,
                                 r_tip=None, solid=None, base_sines=self._sines, batch=batch)
        return [m for _, m in found]

    def _world(self, d) -> np.ndarray:
        """The fingers' world nodes as one array ``(K, n+1, 3)`` [m] (:meth:`nodes`)."""
        K, n = self._bodies.shape
        W = np.empty((K, n + 1, 3))
        W[:, :n] = d.xpos[self._flat].reshape(K, n, 3)
        W[:, n] = d.geom_xpos[self._tips]
        return W

    def _pairs(self, keys: tuple) -> tuple:
        """Flat link indices ``(i, j)`` (link ``k`` of finger ``f`` is ``f n + k``) of the mask's pairs in the finger
        pairs ``keys`` (``(f, g)``, ``f <= g``).  Cached per ``keys`` (at most ``_PAIR_CACHE`` entries)."""
        pairs = self._pair_cache.get(keys)
        if pairs is None:
            n = self._bodies.shape[1]
            i, j = [np.zeros(0, np.intp)], [np.zeros(0, np.intp)]
            for f, g in keys:
                a, b = np.nonzero(self._mask[f, g])
                i.append((f * n + a).astype(np.intp))
                j.append((g * n + b).astype(np.intp))
            pairs = (np.concatenate(i), np.concatenate(j))
            if len(self._pair_cache) < _PAIR_CACHE:
                self._pair_cache[keys] = pairs
        return pairs

    def _near_clear(self, q: list, W: np.ndarray, i: np.ndarray, j: np.ndarray) -> bool:
        """True when the pairs ``(i, j)`` the screen left open are proved clear by their exact distance
        (:func:`simgrip.intersection.segment_distances`, the exact test's own measure) at least ``(1 +
        CLEAR_MARGIN)`` times the limit, links ``i`` and ``i + 2`` of one finger by the link between them: every pair the screen cleared is farther than its bound, so
        :func:`~simgrip.validity.chain_violations` would find nothing (a crossing is at distance 0; its crossing
        test skips adjacent links, which cannot cross while every hinge turns less than ``pi/2``, checked here)."""
        for row in self._jq:
            for a in row:
                if not -0.5 * math.pi < q[a] < 0.5 * math.pi:
                    return False
        if self._skip_one:
            # links i and i+2 of one finger: with both hinges of link i+1 within pi/2, link i lies behind link i+1's
            # start and link i+2 beyond its end along link i+1's direction: they are at least its length apart
            n = self._bodies.shape[1]
            rest = (j - i != 2) | (i // n != j // n)
            if not rest.any():
                return True
            i, j = i[rest], j[rest]
        s0, s1 = W[:, :-1].reshape(-1, 3), W[:, 1:].reshape(-1, 3)
        dist = segment_distances(s0[i], s1[i], s0[j], s1[j])
        return bool((dist >= self._limit * (1.0 + CLEAR_MARGIN)).all())

    def _turned_one(self, q: list, f: int) -> bool:
        phi = lo = hi = 0.0
        for a in self._jq[f]:
            phi += q[a]
            if phi < lo:
                lo = phi
            elif phi > hi:
                hi = phi
        return hi - lo > 0.5 * math.pi
