"""The planar elastica of a finger whose tip touches a sphere off its equator (inclined contact).

Problem.  ``K >= 2`` identical fingers, spaced evenly around the palm axis,
hold a sphere by their tips (Grips I, II).  The sphere is centred on the
axis; the tip centres lie on the sphere of diameter ``b`` (through them, as
the box's width and the cylinder's diameter are measured); at finger ``k``
the outward normal in the finger's plane ``(E1, E2)`` has elevation ``beta``:
``n = (cos beta, sin beta)``, and the in-plane tangent is ``t = n x E3 =
(-sin beta, cos beta)``.  Forces over ``rho g l``, lengths over ``l``.

Derivation.

1. The sphere acts on the rod only at the tip: ``F = N n + F_f t`` (``N``
   along the normal, pushing on the rod when ``> 0``; ``F_f`` the friction in
   the finger's plane; no out-of-plane component: each finger's plane is a
   plane of symmetry of the grip).
2. The sphere's equilibrium.  Its weight is ``K M``; the fingers' forces on
   it are ``-F_k``.  The horizontal components cancel (evenly spaced
   fingers: ``sum_k E1_k = 0``), so the vertical balance is ``sum_k F_k . E2
   = -K M`` and, the fingers being alike, ``N2 = F . E2 = -M`` per finger.
   The moments about the centre cancel too: ``-F_k`` acts at ``(b/2) n_k``,
   so its moment is ``-(b/2) F_f (n_k x t_k) = (b/2) F_f E3_k`` and ``sum_k
   E3_k = 0``.
3. The rod.  It is clamped at the palm and loaded at its tip by ``(N1, N2)
   = F`` with ``N2 = -M`` and ``N1`` the unknown reaction that puts the tip on
   the sphere: ``X(1) = (b/2) cos beta``.  That is the paper's Grip I/II
   boundary-value problem (tip on a vertical face at ``X = b/2``, friction
   carrying ``M``) with ``b`` replaced by ``b cos beta``
   (:func:`simgrip.reference.elastica.solve`); a finite tip radius adds its
   couple exactly as there (``contact_moment``).
4. The contact.  ``N = N1 cos beta + N2 sin beta`` and ``F_f = -N1 sin beta
   + N2 cos beta``; the sphere is held iff ``N > 0`` and ``|F_f| <= mu_s N``.
   The sphere's centre sits at ``Y(1) - (b/2) sin beta``.

With sticking friction ``beta`` is not fixed by statics: every ``beta``
whose cone holds is an equilibrium, and where the tips first touch decides.
So, as Grip III's ``gamma``, the simulation's own ``beta`` is the input.
``beta = 0`` is the vertical face (box, cylinder).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.params import DimensionlessParams, check_grip
from simgrip.reference.elastica import ElasticaSolution, solve

__all__ = ["InclinedContact", "solve_inclined"]


@dataclass(frozen=True)
class InclinedContact:
    """A finger's tip on a sphere at the contact elevation ``contact_angle`` (dimensionless).

    Attributes
    ----------
    grip : {"I", "II"}
    contact_angle : float
        ``beta`` [rad], the outward normal's elevation in the finger's plane.
    rod : ElasticaSolution
        The rod's BVP (Grip I/II at width ``b cos beta``): shape, ``tip``, ``N1``, ``N2``.
    N1, N2 : float
        Force on the rod along ``E1`` (away from the palm axis) and ``E2`` (up).
    normal_force, friction_force : float
        Its components along ``n`` and ``t = (-sin beta, cos beta)``.
    required_mu : float
        ``|friction_force| / normal_force`` (inf when ``normal_force <= 0``).
    feasible : bool
        The rod's solution exists, ``normal_force > 0`` and ``|friction_force| <= mu_s normal_force``.
    tip : ndarray (2,)
        ``(X(1), Y(1))``.
    centre_height : float
        The sphere's centre ``Y(1) - (b/2) sin beta``.
    """

    grip: str
    contact_angle: float
    rod: ElasticaSolution
    N1: float
    N2: float
    normal_force: float
    friction_force: float
    required_mu: float
    feasible: bool
    tip: np.ndarray
    centre_height: float


def solve_inclined(grip: str, params: DimensionlessParams, profile, contact_angle: float, *,
                   contact_moment: float = 0.0, **solve_kw) -> InclinedContact:
    """Solve a finger holding a sphere of diameter ``params.b`` at contact elevation ``contact_angle``.

    Parameters
    ----------
    grip : {"I", "II"}
    params : DimensionlessParams
        ``M`` is the sphere's mass per finger; ``b`` its diameter through the tip centres.
    profile : CurvatureProfile, float or callable
    contact_angle : float
        ``beta`` [rad], ``|beta| < pi/2``.
    contact_moment : float
        Tip couple of the finite tip radius (E3, over ``rho g l^2``), as in
        :func:`simgrip.reference.elastica.solve`.
    solve_kw
        Passed on to :func:`simgrip.reference.elastica.solve`.

    Raises
    ------
    ValueError
        ``grip`` not I or II, ``contact_angle`` out of range, bad ``params``.
    ElasticaError
        The rod's BVP does not converge.
    """
    g = check_grip(grip)
    if g not in ("I", "II"):
        raise ValueError(f"grip must be 'I' or 'II' for a tip on a sphere, got {grip!r}")
    try:
        beta = float(contact_angle)
    except (TypeError, ValueError):
        raise ValueError(f"contact_angle must be a real number (radians), got {contact_angle!r}") from None
    if not (math.isfinite(beta) and abs(beta) < 0.5 * math.pi):
        raise ValueError(f"contact_angle must lie in (-pi/2, pi/2), got {contact_angle!r}")
    if not isinstance(params, DimensionlessParams):
        raise ValueError(f"params must be DimensionlessParams, got {type(params).__name__}")
    rod = solve(g, params.replace(b=params.b * math.cos(beta)), profile, contact_moment=contact_moment, **solve_kw)
    N1, N2 = float(rod.N1), float(rod.N2)
    c, s = math.cos(beta), math.sin(beta)
    normal = N1 * c + N2 * s
    friction = -N1 * s + N2 * c
    need = abs(friction) / normal if normal > 0 else math.inf
    tip = np.array(rod.tip, dtype=float)
    return InclinedContact(
        grip=g, contact_angle=beta, rod=rod, N1=N1, N2=N2, normal_force=normal, friction_force=friction,
        required_mu=need, feasible=bool(normal > 0 and need <= params.mu_s), tip=tip,
        centre_height=float(tip[1] - 0.5 * params.b * s),
    )
