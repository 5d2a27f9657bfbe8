"""Geometry of the full-contact chain: its nodes, the non-penetration constraints and their derivatives.

Used by :mod:`simgrip.reference.constrained` (see there for the model).  Every
constraint is ``g(phi) >= 0`` with ``phi`` the ``n`` link angles; a block
evaluation gives all of them with their gradients (:func:`all_constraints`),
:func:`keyed` evaluates a frozen list of them (the active set, each with its
piece: which face, which side, which part of a segment) for the KKT Newton.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simgrip.chain import link_positions

__all__ = ["Geometry", "Spec", "all_constraints", "keyed", "keys_of", "self_pairs"]


# ---------------------------------------------------------------------------
# geometry: nodes and their derivatives in the link angles


class Geometry:
    """Nodes ``P`` (n+1, 2) of the chain and ``T`` (n, 2), ``dP_k/dphi_i = T_i`` for ``i < k``."""

    def __init__(self, phi: np.ndarray, ds: float):
        self.phi = phi
        self.ds = ds
        self.n = phi.size
        self.c, self.s = np.cos(phi), np.sin(phi)
        self.P = link_positions(phi, ds)
        self.T = ds * np.stack([-self.s, self.c], axis=1)
        self.idx = np.arange(self.n)

    def dnode(self, k: np.ndarray, f: np.ndarray) -> np.ndarray:
        """Rows ``d(f_m . P_{k_m})/dphi`` for node indices ``k`` (m,) and directions ``f`` (m, 2)."""
        k = np.asarray(k)
        return (f @ self.T.T) * (self.idx[None, :] < k[:, None])

    def tangent(self, j):
        return np.stack([self.c[j], self.s[j]], axis=-1)


def _segment_distance(geo: Geometry, j: np.ndarray, q: np.ndarray, dq: np.ndarray, sign: np.ndarray | None,
                      pieces: np.ndarray | None = None):
    """Distance (signed by ``sign`` on the perpendicular piece when given) from points ``q`` (m, 2), with
    derivatives ``dq`` (m, 2, n), to links ``j`` (m,); returns (value, gradient (m, n), piece) where piece
    is 0 (perpendicular), -1 / +1 (the link's start / end node); ``pieces`` forces them (the polish)."""
    m = j.size
    a = geo.P[j]
    t = geo.tangent(j)
    nl = np.stack([-t[:, 1], t[:, 0]], axis=1)  # left normal
    rel = q - a
    u = np.einsum("ij,ij->i", rel, t) / geo.ds
    val = np.empty(m)
    grad = np.empty((m, geo.n))
    piece = np.zeros(m, dtype=int)
    # derivative of a (node j) along direction f: geo.dnode(j, f)
    if pieces is None:
        pieces = np.where(u < 0.0, -1, np.where(u > 1.0, 1, 0))
    inside = pieces == 0
    if np.any(inside):
        ii = np.nonzero(inside)[0]
        sg = np.ones(ii.size) if sign is None else sign[ii]
        d = np.einsum("ij,ij->i", rel[ii], nl[ii])
        if sign is None:
            sg = np.where(d >= 0.0, 1.0, -1.0)
        val[ii] = sg * d
        f = sg[:, None] * nl[ii]
        g = np.einsum("ij,ijk->ik", f, dq[ii]) - geo.dnode(j[ii], f)
        # d nl / d phi_j = -t
        g[np.arange(ii.size), j[ii]] += sg * np.einsum("ij,ij->i", rel[ii], -t[ii])
        grad[ii] = g
    for end, mask in ((-1, pieces == -1), (1, pieces == 1)):
        if np.any(mask):
            ii = np.nonzero(mask)[0]
            node = j[ii] + (1 if end > 0 else 0)
            r = q[ii] - geo.P[node]
            dist = np.maximum(np.hypot(r[:, 0], r[:, 1]), 1e-300)
            f = r / dist[:, None]
            val[ii] = dist
            grad[ii] = np.einsum("ij,ijk->ik", f, dq[ii]) - geo.dnode(node, f)
            piece[ii] = end
    return val, grad, piece


# ---------------------------------------------------------------------------
# the constraints


@dataclass
class Spec:
    """What is constrained: the grip's box (``sd`` = +1 Grip I, -1 Grip II, 0 none), a cylinder, the mirror,
    self-contact candidate pairs ``(k, j, sign)``."""

    n: int
    ds: float
    xb: float
    sd: int
    depth: float
    cylinder: object  # Cylinder or None
    mirror: bool
    clearance: float
    pairs: np.ndarray  # (p, 3) int: node k, link j, side sign (+1 left of link j, -1 right)


#: how near a face's plane a node counts as on it when deciding which links straddle the box's corner (over l:
#: far above the round-off of the solver's active constraints, ~1e-15, far below any link, 1/n)
ARM_TOL = 1e-9


def _corner(geo: Geometry, sp: Spec):
    """The box's corner ``(b/2, Y(l) + sd depth)`` repeated for every link, and its derivative (n, 2, n)."""
    n = sp.n
    q = np.tile([sp.xb, geo.P[n, 1] + sp.sd * sp.depth], (n, 1))
    dq = np.zeros((n, 2, n))
    dq[:, 1, :] = sp.ds * geo.c[None, :]
    return q, dq


def _blocks(geo: Geometry, sp: Spec, want_keys: bool = False):
    """All constraints, block by block: a list of (values, jacobian rows, keys or None)."""
    n = sp.n
    out = []
    e1 = np.array([1.0, 0.0])
    if sp.sd:
        out.append((np.array([geo.P[n, 0] - sp.xb]), geo.dnode(np.array([n]), e1[None]),
                    [("tip", n)] if want_keys else None))
        k = np.arange(1, n)
        b1 = geo.P[k, 0] - sp.xb
        b2 = sp.sd * (geo.P[k, 1] - geo.P[n, 1]) - sp.depth
        fy = np.tile([0.0, float(sp.sd)], (k.size, 1))
        j1 = geo.dnode(k, np.tile(e1, (k.size, 1)))
        j2 = geo.dnode(k, fy) - geo.dnode(np.full(k.size, n), fy)
        top = b2 > b1
        keys = [("top" if t else "face", int(i)) for t, i in zip(top, k)] if want_keys else None
        out.append((np.where(top, b2, b1), np.where(top[:, None], j2, j1), keys))
        # the corner against every link: signed where the link straddles it, else the segment distance
        j = np.arange(n)
        q, dq = _corner(geo, sp)
        corner_y = q[0, 1]
        ends = geo.P
        # which side of the corner each node is on, a node on a face's plane (an active constraint holds it there
        # to round-off) counted on both: a link from a node on the top to one on the face is then signed whatever
        # the round-off, so it cannot cut the corner unseen (a point on the planes' boundary is in both arms)
        tol = ARM_TOL * max(1.0, abs(sp.xb), abs(corner_y))
        above = sp.sd * (ends[:, 1] - corner_y)
        arm_a = (ends[:, 0] < sp.xb + tol) & (above >= -tol)
        arm_b = (ends[:, 0] >= sp.xb - tol) & (above < tol)
        straddle = (arm_a[:-1] & arm_b[1:]) | (arm_b[:-1] & arm_a[1:])
        t = geo.tangent(j)
        nl = np.stack([-t[:, 1], t[:, 0]], axis=1)
        sign = -np.sign(nl @ np.array([1.0, float(sp.sd)]))
        sign[sign == 0] = 1.0
        v, g, pc = _segment_distance(geo, j, q, dq, np.where(straddle, sign, 1.0))
        vu, gu, pu = _segment_distance(geo, j, q, dq, None)
        vals = np.where(straddle, v, vu)
        keys = None
        if want_keys:
            keys = [("corner", int(i), float(sign[i]) if straddle[i] else None, int(pc[i] if straddle[i] else pu[i]))
                    for i in j]
        out.append((vals, np.where(straddle[:, None], g, gu), keys))
    if sp.cylinder is not None:
        j = np.arange(n)
        cy = sp.cylinder
        q = np.tile([cy.x, cy.y], (n, 1))
        v, g, pc = _segment_distance(geo, j, q, np.zeros((n, 2, n)), None)
        out.append((v - cy.radius, g, [("cylinder", int(i), None, int(pc[i])) for i in j] if want_keys else None))
    if sp.mirror:
        k = np.arange(1, n + 1)
        out.append((geo.P[k, 0], geo.dnode(k, np.tile(e1, (k.size, 1))),
                    [("mirror", int(i)) for i in k] if want_keys else None))
    if sp.pairs.size:
        kk, jj, sg = sp.pairs[:, 0], sp.pairs[:, 1], sp.pairs[:, 2].astype(float)
        dq = geo.T.T[None, :, :] * (geo.idx[None, :] < kk[:, None])[:, None, :]
        v, g, pc = _segment_distance(geo, jj, geo.P[kk], dq, sg)
        keys = [("self", int(a), int(b), float(c), int(d)) for a, b, c, d in zip(kk, jj, sg, pc)] if want_keys else None
        out.append((v - sp.clearance, g, keys))
    return out


def all_constraints(phi, sp: Spec, want_keys: bool = False):
    """``(g, G, keys)``: every constraint value, its gradient rows and (when asked) its frozen key."""
    geo = Geometry(phi, sp.ds)
    blocks = _blocks(geo, sp, want_keys)
    if not blocks:
        return np.zeros(0), np.zeros((0, sp.n)), []
    keys = [k for b in blocks for k in b[2]] if want_keys else None
    return np.concatenate([b[0] for b in blocks]), np.vstack([b[1] for b in blocks]), keys


def keyed(phi, sp: Spec, keys):
    """Values and gradient rows of the constraints ``keys`` (frozen pieces), for the KKT Newton."""
    geo = Geometry(phi, sp.ds)
    n = sp.n
    vals = np.empty(len(keys))
    rows = np.empty((len(keys), n))
    e1 = np.array([[1.0, 0.0]])
    for i, key in enumerate(keys):
        kind = key[0]
        if kind in ("tip", "face", "mirror"):
            k = key[1]
            vals[i] = geo.P[k, 0] - (0.0 if kind == "mirror" else sp.xb)
            rows[i] = geo.dnode(np.array([k]), e1)[0]
        elif kind == "top":
            k = key[1]
            fy = np.array([[0.0, float(sp.sd)]])
            vals[i] = sp.sd * (geo.P[k, 1] - geo.P[n, 1]) - sp.depth
            rows[i] = (geo.dnode(np.array([k]), fy) - geo.dnode(np.array([n]), fy))[0]
        elif kind in ("corner", "cylinder"):
            j = np.array([key[1]])
            if kind == "corner":
                q, dq = _corner(geo, sp)
                q, dq = q[:1], dq[:1]
            else:
                q, dq = np.array([[sp.cylinder.x, sp.cylinder.y]]), np.zeros((1, 2, n))
            sign = None if key[2] is None else np.array([key[2]])
            v, g, _ = _segment_distance(geo, j, q, dq, sign, np.array([key[3]]))
            vals[i] = v[0] - (sp.cylinder.radius if kind == "cylinder" else 0.0)
            rows[i] = g[0]
        elif kind == "self":
            k, j = key[1], key[2]
            dq = (geo.T.T * (geo.idx < k)[None, :])[None]
            v, g, _ = _segment_distance(geo, np.array([j]), geo.P[[k]], dq, np.array([key[3]]), np.array([key[4]]))
            vals[i] = v[0] - sp.clearance
            rows[i] = g[0]
        else:  # pragma: no cover - keys come from _blocks
            raise ValueError(f"unknown constraint key {key!r}")
    return vals, rows


def keys_of(phi, sp: Spec, index) -> list:
    """The frozen keys of the constraints at positions ``index`` of :func:`all_constraints`."""
    keys = all_constraints(phi, sp, want_keys=True)[2]
    return [keys[i] for i in index]


def self_pairs(P: np.ndarray, ds: float, clearance: float, reach: float) -> np.ndarray:
    """Node/link pairs (non-adjacent) closer than ``reach``, with the side the node is on."""
    n = P.shape[0] - 1
    mid = 0.5 * (P[:-1] + P[1:])
    d = np.linalg.norm(P[:, None, :] - mid[None, :, :], axis=2)
    k, j = np.nonzero(d < reach + 0.5 * ds)
    keep = (k < j - 1) | (k > j + 2)
    k, j = k[keep], j[keep]
    if k.size == 0:
        return np.zeros((0, 3), dtype=int)
    t = np.diff(P, axis=0)[j] / ds
    nl = np.stack([-t[:, 1], t[:, 0]], axis=1)
    side = np.sign(np.einsum("ij,ij->i", P[k] - P[j], nl)).astype(int)
    side[side == 0] = 1
    return np.stack([k, j, side], axis=1)




def self_crossing(P: np.ndarray, clearance: float) -> bool:
    """Whether the polyline ``P`` crosses itself or brings a node within ``clearance`` of a non-adjacent link
    (the same pairs as the self-contact constraints: node ``k`` against link ``j``, ``k`` not in ``j-1..j+2``)."""
    n = P.shape[0] - 1
    a, b = P[:-1], P[1:]
    d = b - a
    i, j = np.triu_indices(n, k=2)

    def cross(u, v):
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    o1 = cross(d[i], a[j] - a[i])
    o2 = cross(d[i], b[j] - a[i])
    o3 = cross(d[j], a[i] - a[j])
    o4 = cross(d[j], b[i] - a[j])
    hit = (o1 * o2 < 0) & (o3 * o4 < 0)
    if np.any(hit):
        return True
    k = np.arange(n + 1)
    kk, jj = np.meshgrid(k, np.arange(n), indexing="ij")
    far = (kk < jj - 1) | (kk > jj + 2)
    kk, jj = kk[far], jj[far]
    if kk.size == 0:
        return False
    rel = P[kk] - a[jj]
    L2 = np.maximum(np.einsum("ij,ij->i", d[jj], d[jj]), 1e-300)
    u = np.clip(np.einsum("ij,ij->i", rel, d[jj]) / L2, 0.0, 1.0)
    dist = np.linalg.norm(rel - u[:, None] * d[jj], axis=1)
    return bool(np.min(dist) < clearance * (1.0 - 1e-9))
