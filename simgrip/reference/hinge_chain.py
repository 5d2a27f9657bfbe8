"""The hinge chain's settled state: :func:`solve_chain`, its energy, and the Grip III start shape.

``n`` rigid links with absolute angles ``phi_0 .. phi_{n-1}``, hinge angles
``q_j = phi_j - phi_{j-1}`` (``phi_{-1} = 0``) and springs from
:func:`simgrip.chain.chain_springs` (``2/ds`` at the clamp with half the rest
angle span, ``1/ds`` elsewhere, in units of ``EI/l``).  Link masses ``ds`` act
at the link midpoints, which gives the separable gravity energy
``sum_i ds (1 - s_{i+1/2}) sin(phi_i)`` (exactly ``sum_i ds Y_mid,i``).  The tip
is the end of the last link.  The Grip III contact is the material point at arc
length ``gamma`` inside link ``m = floor(gamma/ds)``, linear along it:
``X(gamma) = sum_{i<m} ds cos(phi_i) + (gamma - m ds) cos(phi_m)``.  A point
couple ``M_c`` (E3 component) at the contact adds the potential ``-M_c phi``
of the link that carries it: link ``m`` for Grip III, the last link (a tip
couple) for the free rod and Grips I/II.  The workpiece's vertical force on
the contact is ``N2 = -load`` (default ``load = params.M``, its weight share);
a ``load`` of either sign is accepted (:func:`check_load`): a negative one is a
friction force pushing the contact up, i.e. a finger whose friction pulls the
workpiece down (a K-finger grasp's balance may need one,
:mod:`simgrip.gripper.start`).  The load enters only through the
linear term ``load Y(s_c)`` of the energy, so nothing else changes with its
sign.  This is the exact settled state the
MuJoCo chain built from the same springs must reach.  (For Grip III the couple
loads every hinge up to ``m``, i.e. the continuous moment jump is moved to the
end of link ``m``'s cell; that is second order only when ``gamma`` is a link
midpoint and costs ``O(|M_c| ds)`` otherwise.  The contact force is second
order anywhere.)

Order of accuracy (derived; measured in ``tests/test_hinge_chain.py``)
    ``O(ds^2)`` in the tip/contact position, the angles and the contact force:
    the chain samples ``theta`` at link midpoints, its hinge is the central
    difference there, its clamp hinge owns the half cell ``[0, ds/2]`` (hence
    ``2/ds``), and ``X``, ``Y`` and the gravity energy are midpoint rules.  With
    ``1/ds`` at the clamp the first link angle is off by ``O(ds)`` and the whole
    chain converges at first order only.  The stability eigenvalue uses the
    midpoint weights ``ds`` (see :mod:`simgrip.reference.stability`).

Examples
--------
>>> from simgrip import STANDARD, Uniform
>>> eq = solve_chain("III", STANDARD, Uniform(-6.0), 40)
>>> bool(abs(eq.contact[0] - 0.3) < 1e-12)
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.chain import ChainSprings, check_links, link_positions, springs_of
from simgrip.params import M_MAX, DimensionlessParams, Grip, _finite
from simgrip.reference.arguments import check_discrete
from simgrip.reference.minimiser import (
    DiscreteEnergy,
    DiscreteEquilibrium,
    DiscreteError,
    EnergyTerms,
    angles_from_guess,
    energy_terms,
    equilibrium_fields,
    grip_sign,
    minimise,
)

__all__ = ["ChainEquilibrium", "chain_angles", "chain_energy", "check_load", "cradle_start_angles", "solve_chain"]


@dataclass(frozen=True)
class ChainEquilibrium(DiscreteEquilibrium):
    """Settled state of the hinge chain.

    Attributes
    ----------
    grip : str
    n : int
        Number of links; ``ds = 1/n``.
    params : DimensionlessParams
    link_angles : ndarray (n,)
        Absolute link angles ``phi_i`` [rad].
    joint_angles : ndarray (n,)
        Hinge angles ``q_j = phi_j - phi_{j-1}`` (``q_0 = phi_0``).
    nodes : ndarray (n+1, 2)
        Hinge positions and the tip.
    tip : ndarray (2,)
    contact : ndarray (2,) or None
        Tip for I/II, the material point at ``gamma`` for III, None for free.
    N1, N2, energy, min_eigenvalue, gradient_norm, iterations, success
        See :class:`~simgrip.reference.minimiser.DiscreteEquilibrium`; the
        eigenvalue's metric is ``ds`` per link.  ``N2 = -load``, the load solved
        with (``params.M`` unless :func:`solve_chain` was given ``load``).
    gamma : float or None
        Grip III contact arc length used.
    contact_moment : float
        The point moment ``M_c`` applied at the contact (the tip couple for the
        free rod and Grips I/II).
    gravity : float
        Factor on the rod's weight the solution was computed with.
    """

    grip: str
    n: int
    params: DimensionlessParams
    link_angles: np.ndarray
    joint_angles: np.ndarray
    nodes: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    gamma: float | None = None
    contact_moment: float = 0.0
    gravity: float = 1.0

    @property
    def ds(self) -> float:
        return 1.0 / self.n

    @property
    def contact_link(self) -> int | None:
        """Index of the link carrying the Grip III contact."""
        if self.gamma is None:
            return None
        return min(int(math.floor(self.gamma * self.n)), self.n - 1)

    def theta_at(self, s) -> np.ndarray:
        """Link angles, read as samples at link midpoints, interpolated linearly (``theta(0) = 0``)."""
        sm = np.concatenate([[0.0], (np.arange(self.n) + 0.5) / self.n, [1.0]])
        th = np.concatenate([[0.0], self.link_angles, [self.link_angles[-1]]])
        return np.interp(s, sm, th)


def check_load(load, grip: str, params: DimensionlessParams) -> float:
    """The contact's vertical load (``N2 = -load``): ``params.M`` when None, else a finite float of either sign.

    ``|load| <= M_MAX`` (the bound of ``M``); a load on the free rod (no contact) is refused.
    """
    if load is None:
        return params.M
    v = _finite("load", load)
    if grip == "free":
        raise ValueError(f"load: the free rod has no contact to carry a load, got load={load!r}")
    if abs(v) > M_MAX:
        raise ValueError(f"load must lie in [-{M_MAX:g}, {M_MAX:g}] (the range of M), got {load!r}")
    return v


def _chain_problem(grip, params, springs: ChainSprings, gamma, contact_moment, gravity, M):
    n = springs.n
    ds = springs.ds
    smid = (np.arange(n) + 0.5) * ds
    a = gravity * ds * (1.0 - smid)
    lin = np.zeros(n)
    w, c0, m = None, 0.0, None
    if grip in ("free", "I", "II"):
        lin[n - 1] = -float(contact_moment)  # a tip couple turns the last link: potential -C phi_{n-1}
    if grip in ("I", "II"):
        w = np.full(n, ds)
        a = a + M * w
        c0 = -0.5 * params.b
    elif grip == "III":
        m = min(int(math.floor(gamma * n)), n - 1)
        w = np.zeros(n)
        w[:m] = ds
        w[m] = gamma - m * ds
        a = a + M * w
        lin[m] = -float(contact_moment)
        c0 = -0.5 * params.b
    prob = DiscreteEnergy(params.D, np.asarray(springs.stiffness, float), np.asarray(springs.rest, float), a, lin, w, c0,
                          0.5 * params.b, metric=np.full(n, ds))
    unit_rest = np.full(n, ds)
    unit_rest[0] = 0.5 * ds
    return prob, unit_rest, m


def _springs_for(profile, n, springs):
    if springs is None:
        return springs_of(profile, n)
    if not isinstance(springs, ChainSprings) or springs.n != n:
        raise ValueError(f"springs must be a ChainSprings with n = {n}")
    return springs


def chain_energy(
    grip,
    params,
    profile,
    n,
    link_angles,
    N1=0.0,
    *,
    gamma=None,
    contact_moment=0.0,
    gravity=1.0,
    springs=None,
    hessian=True,
    load=None,
) -> EnergyTerms:
    """Chain potential ``V0 - N1 X(s_c)`` with gradient and Hessian in the link angles.

    ``V0`` = springs + gravity on link midpoints + ``load Y(s_c)`` (``N2 = -load``, ``load``
    default ``params.M``, either sign) ``- M_c phi_m``.  ``gravity`` scales the rod's weight
    (1 = physical; 0 for gravity-free checks); ``springs`` overrides :func:`simgrip.chain.chain_springs`.
    """
    grip, params, prof, n, gam, grav = check_discrete(grip, params, profile, "n", n, gamma, gravity)
    sp = _springs_for(prof, n, springs)
    cm = _finite("contact_moment", contact_moment)
    M = check_load(load, grip, params)
    prob, _, _ = _chain_problem(grip, params, sp, gam, cm, grav, M)
    return energy_terms(prob, link_angles, N1, hessian)


def solve_chain(
    grip,
    params,
    profile,
    n,
    *,
    gamma=None,
    contact_moment=0.0,
    guess=None,
    gravity=1.0,
    springs=None,
    load=None,
    stability: str = "value",
) -> ChainEquilibrium:
    """Static equilibrium of the ``n``-link hinge chain (the MuJoCo finger's settled state).

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
    profile : CurvatureProfile, float or callable
    n : int
        Number of links (>= 2).
    gamma : float, optional
        Grip III contact arc length (any value in (0, 1); default ``params.gamma``).
    contact_moment : float
        Point moment ``M_c`` (E3 component, over ``rho g l^2``) applied by the
        workpiece at the contact (finite-radius contact geoms): on the link
        carrying ``gamma`` for Grip III, on the last link (a tip couple) for the
        free rod and Grips I/II; potential ``-M_c phi``.
    guess : optional
        Link angles, a solution with ``theta_at(s)`` (sampled at link midpoints),
        or None.
    gravity : float
        Factor on the rod's own weight (1 physical, 0 gravity free).
    springs : ChainSprings, optional
        Override the springs (for convergence studies of other hinge rules).
    load : float, optional
        The workpiece's vertical load on the contact (over ``rho g l``; the force on
        the rod is ``N2 = -load``, reported as ``N2``).  Default ``params.M`` (its
        weight share; bit-identical to not passing it).  Either sign, ``|load| <=
        M_MAX``: a negative load pushes the contact up (the friction of a finger
        that pulls the workpiece down).  Grips only.
    stability : {"value", "sign", "none"}
        ``min_eigenvalue``: the smallest eigenvalue (default); a value with only its
        sign (``> 0`` exactly when the eigenvalue's is: a start's stability test at a
        fraction of the cost); or NaN (not computed: the angles and forces alone).

    Raises
    ------
    ValueError
        Bad ``grip``, ``n``, ``gamma``, ``guess``, ``load`` or ``stability``.
    DiscreteError
        Newton failed to converge.
    """
    grip, params, n, sp, gam, m, cm, prob_gravity, M, prob, res = _minimised(
        grip, params, profile, n, gamma, contact_moment, guess, gravity, springs, load, stability)
    phi = res.x
    nodes = link_positions(phi, sp.ds)
    tip = nodes[-1].copy()
    contact, gam_out = None, None
    if grip == "III":
        frac = gam - m * sp.ds
        contact = nodes[m] + frac * np.array([math.cos(phi[m]), math.sin(phi[m])])
        gam_out = gam
    elif grip != "free":
        contact = tip.copy()
    return ChainEquilibrium(
        grip=grip, n=n, params=params, link_angles=phi, joint_angles=np.diff(phi, prepend=0.0), nodes=nodes,
        tip=tip, contact=contact, gamma=gam_out, contact_moment=cm, gravity=prob_gravity,
        **equilibrium_fields(prob, res, M, stability),
    )


def _minimised(grip, params, profile, n, gamma, contact_moment, guess, gravity, springs, load, stability="value"):
    """:func:`solve_chain`'s argument checks, discrete problem and minimisation (shared with :func:`chain_angles`):
    ``(grip, params, n, springs, gamma, contact link, contact_moment, gravity, load, problem, Newton result)``."""
    grip, params, prof, n, gam, prob_gravity = check_discrete(grip, params, profile, "n", n, gamma, gravity)
    if stability not in ("value", "sign", "none"):
        raise ValueError(f"stability must be 'value', 'sign' or 'none', got {stability!r}")
    sp = _springs_for(prof, n, springs)
    cm = _finite("contact_moment", contact_moment)
    M = check_load(load, grip, params)
    prob, unit_rest, m = _chain_problem(grip, params, sp, gam, cm, prob_gravity, M)
    smid = (np.arange(n) + 0.5) / n
    g0 = angles_from_guess(guess, smid, n, "n link angles")
    res = minimise(prob, unit_rest, grip_sign(grip, prof), g0)
    return grip, params, n, sp, gam, m, cm, prob_gravity, M, prob, res


def chain_angles(grip, params, profile, n, *, gamma=None, guess=None, gravity=1.0, load=None) -> np.ndarray:
    """The link angles ``phi`` of :func:`solve_chain` alone, bit for bit (the same checks, problem and Newton),
    without its nodes, forces, energy and stability: a start shape (the free settle's) at ~3/4 of the cost.

    Arguments and errors as :func:`solve_chain`'s (``contact_moment = 0``, the chain's own springs).
    """
    return _minimised(grip, params, profile, n, gamma, 0.0, guess, gravity, None, load)[-1].x


def cradle_start_angles(params: DimensionlessParams, profile, n: int) -> np.ndarray:
    """Joint angles of the Grip III start shape: the chain's equilibrium with the contact at ``params.gamma``.

    The scene builder takes these as its initial angles for the cradle (the
    MuJoCo finger then starts on the branch the reference follows).

    Raises
    ------
    ValueError
        Bad inputs, or no Grip III equilibrium with the contact at ``params.gamma``
        (the message names ``gamma``).
    """
    try:
        return solve_chain(Grip.III, params, profile, check_links(n)).joint_angles
    except DiscreteError as exc:
        raise ValueError(f"gamma: no Grip III hinge-chain equilibrium with the contact at gamma = "
                         f"{params.gamma:g} for this kappa profile ({exc})") from exc
