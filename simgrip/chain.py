"""The hinge-chain discretisation of a finger: springs, rest angles and masses.

A finger of length ``l`` becomes ``n`` rigid links of length ``ds = l/n``.  Link
``i`` (``0 <= i < n``) covers ``s in [i ds, (i+1) ds]`` and has absolute angle
``phi_i`` (counter-clockwise from ``E1``).  Hinge ``j`` sits at node
``s_j = j ds`` and carries the relative angle ``q_j = phi_j - phi_{j-1}`` with
``phi_{-1} = 0`` (the clamp).

Derivation (second order in ``ds``).  The link angle approximates the tangent at
the link's midpoint, ``phi_i ~ theta((i + 1/2) ds)``.  Split the bending energy
``int EI/2 (theta' - kappa0)^2 ds`` into the cells between link midpoints:

* interior hinge ``j = 1..n-1`` owns ``[(j - 1/2) ds, (j + 1/2) ds]`` (length ds);
  the midpoint rule there gives ``EI/(2 ds) (q_j - beta_j)^2`` with
  ``beta_j = int_{(j-1/2)ds}^{(j+1/2)ds} kappa0 ds``;
* the clamp hinge ``j = 0`` owns only ``[0, ds/2]`` (half a cell), so
  ``EI/2 * (ds/2) * (q_0/(ds/2) - kappa0)^2 = (2 EI/ds)/2 * (q_0 - beta_0)^2`` with
  ``beta_0 = int_0^{ds/2} kappa0 ds``: **twice the stiffness, half the rest angle
  span**;
* the last half cell ``[l - ds/2, l]`` is moment free (``theta'(l) = kappa0(l)``)
  and needs no hinge.

Gravity acts on each link's mass ``rho ds`` at its midpoint, and the tip is the
end of the last link, so ``X(l) = sum ds cos(phi_i)`` is the midpoint rule for
``int cos(theta)``: every piece is second order.

Everything here is dimensionless unless a :class:`~simgrip.params.PhysicalParams`
is used by the caller to scale it (stiffness ``EI/ds`` [N m/rad]).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simgrip.profiles import CurvatureProfile, as_profile

__all__ = ["ChainSprings", "Count", "chain_springs", "springs_of", "MIN_LINKS", "check_link_count", "check_links",
           "link_positions"]

#: Fewest links a finger may have (one clamp hinge plus one interior hinge).
MIN_LINKS = 2


class Count(int):
    """A count that :func:`check_links` has checked: an ``int >= MIN_LINKS``, handed back unchanged by it.

    A plain ``int`` to every reader (arithmetic on it gives ``int``); a layer handed one does not check it
    again (issue 21: arguments checked once where they enter).  Bounds that depend on where the count is
    used (MuJoCo's body depth, the reference's ``MAX_COUNT``) are still compared there.
    """

    __slots__ = ()


def check_links(n, name: str = "links") -> int:
    """Return ``n`` as an int (a :class:`Count`), or raise ``ValueError`` naming ``name`` if it is not an
    integer >= 2.  A :class:`Count` is returned as it is."""
    if type(n) is Count:
        return n
    return _parse_count(n, name)


def check_link_count(value, name: str = "links") -> Count:
    """``value`` as a link count in ``[2, MAX_LINKS]`` (:func:`check_links`, then :data:`simgrip.params.MAX_LINKS`);
    ``ValueError`` naming ``name`` otherwise.  What every command's ``--links`` and the simulation API are checked
    with (the reference chains take more: :func:`check_links`)."""
    from simgrip.params import MAX_LINKS

    n = check_links(value, name)
    if n > MAX_LINKS:
        raise ValueError(f"{name} must be at most {MAX_LINKS}, got {n!r} (the chain's error at {MAX_LINKS} links is "
                         f"already below the contact tolerance; see simgrip.params)")
    return n


def _parse_count(n, name: str) -> Count:
    """The check itself: ``n`` as a :class:`Count`, ValueError naming ``name``."""
    try:
        ni = int(n)
    except (TypeError, ValueError, OverflowError):  # OverflowError: int(inf)
        raise ValueError(f"{name} must be an integer >= {MIN_LINKS}, got {n!r}") from None
    if ni != n or ni < MIN_LINKS:
        raise ValueError(f"{name} must be an integer >= {MIN_LINKS}, got {n!r}")
    return Count(ni)


@dataclass(frozen=True)
class ChainSprings:
    """Springs of an ``n``-link chain, dimensionless.

    Attributes
    ----------
    n : int
        Number of links.
    ds : float
        Link length over ``l``.
    stiffness : ndarray, shape (n,)
        Hinge stiffness over ``EI/l``: ``2/ds`` for the clamp hinge, ``1/ds`` otherwise.
        Multiply by ``EI/l`` [N m] for N m/rad.
    rest : ndarray, shape (n,)
        Rest angle of each hinge [rad] (the integrated intrinsic curvature).
    nodes : ndarray, shape (n,)
        Arc length ``s/l`` of each hinge.
    """

    n: int
    ds: float
    stiffness: np.ndarray
    rest: np.ndarray
    nodes: np.ndarray


def chain_springs(profile: CurvatureProfile | float, n: int) -> ChainSprings:
    """Stiffness factors and rest angles of an ``n``-link chain for ``profile``.

    See the module docstring for the derivation; ``rest[0]`` integrates the
    curvature over ``[0, ds/2]`` and ``rest[j]`` over ``[(j-1/2) ds, (j+1/2) ds]``.
    """
    return springs_of(as_profile(profile), check_links(n))


def springs_of(prof: CurvatureProfile, n: int) -> ChainSprings:
    """:func:`chain_springs` for an already checked profile and link count (no checks)."""
    ds = 1.0 / n
    nodes = np.arange(n) * ds
    lo = np.maximum(nodes - 0.5 * ds, 0.0)
    hi = nodes + 0.5 * ds
    rest = np.asarray(prof.integral(lo, hi), dtype=float)
    stiffness = np.full(n, 1.0 / ds)
    stiffness[0] = 2.0 / ds
    return ChainSprings(n=n, ds=ds, stiffness=stiffness, rest=rest, nodes=nodes)


def link_positions(link_angles: np.ndarray, ds: float) -> np.ndarray:
    """Node positions ``(n+1, 2)`` of a chain with absolute link angles ``phi`` [rad], base at the origin."""
    phi = np.asarray(link_angles, dtype=float)
    steps = ds * np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    return np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
