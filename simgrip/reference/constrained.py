"""Full contact on the hinge chain: its own energy minimised under non-penetration constraints.

An independent reference for enveloping grasps (issue 17): the chain of
:mod:`simgrip.reference.hinge_chain` (same springs, rest angles, gravity on link
midpoints and the workpiece's load on the tip, i.e. the same energy ``V0``,
built by :func:`simgrip.reference.hinge_chain._chain_problem`) minimised over
its ``n`` link angles by a general-purpose optimiser (SciPy's SLSQP), not the
settle's Newton, subject to inequality constraints ``g(phi) >= 0``:

* **Grips I/II, the box.**  The centreline stays outside the workpiece's
  centreline region (the box inflated by the capsule radius, whose sharp
  corner stands for the rounded one: ``r_link = 2e-3 l`` is far below ``ds``):
  ``{X < b/2, Y < top}`` for Grip I (box below the palm, ``top`` its top face),
  ``{X < b/2, Y > bottom}`` for Grip II.  The tip presses the side face:
  ``X(l) >= b/2``.  The box hangs on the tip (the symmetric reduction: it is
  free to move vertically and the tip sticks to the face), so its faces move
  with the tip: ``top = Y(l) + depth`` (I), ``bottom = Y(l) - depth`` (II);
  ``depth`` (over ``l``) is how far the tip sits from the top (bottom) face.
  The load ``M`` acts on the tip (the potential ``M Y(l)``), so the box's
  vertical balance is exact: the tip's friction is ``-M`` minus the vertical
  components of the other (frictionless) contacts on the box.  Constraints:
  every node outside the region (``max(X - b/2, Y - top) >= 0``) and the box's
  corner on the box side of every link (its signed distance to the link,
  the segment's when it projects outside), so no link cuts the corner.
* **A cylinder** (axis normal to the plane; centre, radius ``R``) fixed in the
  plane: every link's distance to the centre ``>= R``.
* **Self-contact**: every node at least ``clearance`` (``2 r_link``) from every
  non-adjacent link (point-to-segment distance), candidate pairs gathered
  within a few links' length and refreshed until no pair is violated.
* **The mirror finger** (``mirror=True``): the other finger of the symmetric
  pair is this one mirrored in ``X = 0``; the rod may touch it but not cross:
  ``X >= 0`` at every node past the root.

Every extra contact is frictionless (the tip's friction carries what the box's
balance leaves).  The multipliers (contact forces over ``rho g l``) come from a
non-negative least-squares fit of the KKT stationarity on the near-active
constraints, after a Newton polish of the KKT system on the active set (the
active pieces frozen), so a solution is a KKT point to ~1e-10.  The point-contact
chain (:func:`~simgrip.reference.hinge_chain.solve_chain`) is the special case
where only the tip is active: then both agree to the solver's tolerance.

The free rod with a cylinder and/or self-contact has no tip constraint.
Grip III is not covered (its full-contact problem is the cradle's corner plus
the rest of the rod; out of scope here).

What it finds (standard case D = 1, M = 5, b = 0.6, uniform kappa, ``depth = 0.4``; tests in
``tests/test_constrained.py`` and ``tests/test_free_boundary.py``):

* Grip I, kappa = -10: the tip on the side face and the box's top corner on one link (the point-contact
  chain loops through the box); n = 32: N = 19.87244, tip (0.3, -0.47795); n = 64: N = 19.87183; the
  free-boundary BVP (:mod:`simgrip.reference.free_boundary`): N = 19.88035, tip (0.3, -0.478353).
* Grip II, kappa = 10: the box's bottom corner rests on the rod.
* The free rod at kappa = -9: a spiral whose tip and root press on other turns (no smooth BVP is built:
  this chain is the reference).
* A cylinder (0.2, -0.2), R = 0.15, kappa = -10: a wrapped arc plus the tip (:mod:`simgrip.reference.wrap`).

The minimiser is local and the path matters (a closing finger): the default start continues from the
point-contact chain (or rest shape) in the curvature's scale.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import lsq_linear, minimize

from simgrip.chain import link_positions
from simgrip.params import DimensionlessParams, _finite
from simgrip.reference.contact_geometry import Geometry, Spec, all_constraints, keyed, self_crossing, self_pairs
from simgrip.reference.arguments import check_discrete
from simgrip.reference.hinge_chain import _chain_problem, _springs_for
from simgrip.reference.minimiser import DiscreteError, grip_sign, minimise

__all__ = ["Box", "Cylinder", "ConstrainedError", "ConstrainedEquilibrium", "Contact", "DEFAULT_CLEARANCE",
           "DEFAULT_DEPTH", "solve_constrained"]

#: Default self-contact clearance over ``l``: twice the scene's link capsule radius (``2e-3 l``).
DEFAULT_CLEARANCE = 4e-3
#: Default distance of the tip from the box's top face (Grip I) or bottom face (Grip II), over ``l``.
DEFAULT_DEPTH = 0.4
#: A constraint counts as active (in the contact set) at most this far from its bound (over ``l``).
ACTIVE_GAP = 1e-7


class ConstrainedError(RuntimeError):
    """The constrained minimiser did not reach a KKT point."""


@dataclass(frozen=True)
class Box:
    """The Grip I/II box in the centreline's terms: side face at ``X = b/2``, the top (I) / bottom (II)
    face ``depth`` above (I) / below (II) the tip, moving with it."""

    depth: float = DEFAULT_DEPTH

    def __post_init__(self):
        d = _finite("depth", self.depth)
        if not 0.0 < d < 2.0:
            raise ValueError(f"depth must lie in (0, 2) (over l), got {self.depth!r}")
        object.__setattr__(self, "depth", d)


@dataclass(frozen=True)
class Cylinder:
    """A round workpiece fixed in the finger's plane: centre ``(x, y)`` and radius over ``l`` (centreline terms)."""

    x: float
    y: float
    radius: float

    def __post_init__(self):
        for name in ("x", "y", "radius"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        if not self.radius > 0.0:
            raise ValueError(f"radius must be > 0, got {self.radius!r}")
        if math.hypot(self.x, self.y) <= self.radius:
            raise ValueError("cylinder: the finger's root (0, 0) lies inside it (centre distance <= radius)")


@dataclass(frozen=True)
class Contact:
    """One active constraint: ``kind`` ('tip', 'face', 'top', 'bottom', 'corner', 'cylinder', 'self',
    'mirror'), the node or link it acts on, ``other`` (the other link for 'self'), its point [x, y] and
    the force on the rod (over ``rho g l``, E1/E2 components)."""

    kind: str
    index: int
    point: np.ndarray
    force: np.ndarray
    other: int | None = None


@dataclass(frozen=True)
class ConstrainedEquilibrium:
    """A KKT point of the constrained chain.

    ``link_angles`` [rad], ``nodes`` (n+1, 2), ``tip``; ``N`` the tip's normal force (E1, Grips I/II;
    0 for the free rod), ``tip_friction`` its vertical force on the rod (``-M`` minus the box's other
    vertical contact forces); ``contacts`` the active constraints with their forces; ``energy`` ``V0``;
    ``kkt_residual`` the stationarity residual over the largest gradient term; ``keys`` the active
    constraints (frozen pieces; a warm start's contact set).
    """

    grip: str
    n: int
    params: DimensionlessParams
    link_angles: np.ndarray
    nodes: np.ndarray
    tip: np.ndarray
    N: float
    tip_friction: float
    contacts: tuple
    energy: float
    kkt_residual: float
    keys: tuple = field(repr=False, default=())

    def kinds(self) -> dict:
        """How many active contacts of each kind."""
        out: dict = {}
        for c in self.contacts:
            out[c.kind] = out.get(c.kind, 0) + 1
        return out

    def contact_links(self, kind: str) -> list:
        return sorted(c.index for c in self.contacts if c.kind == kind)


# ---------------------------------------------------------------------------
# the solve


def _problem(grip, params, profile, n, box, cylinder, self_contact, mirror, clearance):
    grip, params, prof, n, _, grav = check_discrete(grip, params, profile, "n", n, None, 1.0)
    if grip == "III":
        raise ValueError("grip: full contact covers the free rod and Grips I/II, got 'III'")
    sp_chain = _springs_for(prof, n, None)
    prob, unit_rest, _ = _chain_problem(grip, params, sp_chain, None, 0.0, grav,
                                        params.M if grip != "free" else 0.0)
    if grip in ("I", "II"):
        box = Box() if box is None else box
        if not isinstance(box, Box):
            raise ValueError(f"box must be a Box, got {type(box).__name__}")
    elif box is not None:
        raise ValueError("box: the free rod has no box (give a cylinder, or grip 'I'/'II')")
    if cylinder is not None and not isinstance(cylinder, Cylinder):
        raise ValueError(f"cylinder must be a Cylinder or None, got {type(cylinder).__name__}")
    clearance = _finite("clearance", clearance)
    if not 0.0 < clearance < 1.0 / n:
        raise ValueError(f"clearance must lie in (0, ds) = (0, {1.0 / n:g}), got {clearance!r}")
    sd = {"I": 1, "II": -1}.get(grip, 0)
    spec = Spec(n=n, ds=1.0 / n, xb=0.5 * params.b, sd=sd, depth=box.depth if box else 0.0, cylinder=cylinder,
                mirror=bool(mirror), clearance=clearance, pairs=np.zeros((0, 3), dtype=int))
    return grip, params, prof, prob, unit_rest, spec, bool(self_contact)


#: Where the KKT Newton on the active set does not converge (a contact at a hinge, where the link's distance
#: switches pieces), SLSQP's own point is returned if its relative KKT residual (reported as
#: ``kkt_residual``) is at most this: a relative force error of that size, far below the chain's
#: discretisation error at any n the module is used for (O(1/n^2) >= 6e-5 at n = 128).
KKT_FALLBACK = 1e-5

#: SLSQP sees only the constraints within this gap (over ``l``) of their bound at its start; a solve that
#: violates one left out is repeated with all of them.
BAND = 0.05


def _slsqp(prob, spec, x0, maxiter):
    """SLSQP from ``x0`` on the constraints near their bound (all of them if a left-out one is violated)."""
    g0 = all_constraints(x0, spec)[0]
    for sel in (np.nonzero(g0 < BAND)[0], np.arange(g0.size)):
        memo = {}

        def cached(x):
            key = x.tobytes()
            if key not in memo:
                memo.clear()
                memo[key] = all_constraints(x, spec)
            return memo[key]

        kw = dict(method="SLSQP", jac=prob.gradient, options=dict(ftol=1e-10, maxiter=maxiter))
        if sel.size:
            kw["constraints"] = [dict(type="ineq", fun=lambda x, s=sel: cached(x)[0][s],
                                      jac=lambda x, s=sel: cached(x)[1][s])]
        res = minimize(prob.energy, x0, **kw)
        if float(np.min(all_constraints(res.x, spec)[0], initial=0.0)) > -1e-9:
            break
    return res


def _nnls(prob, x, g, G):
    """NNLS multipliers of the constraints within 1e-6 of their bound, and the relative KKT residual."""
    grad = prob.gradient(x)
    act = np.nonzero(g < 1e-6)[0]
    lam = np.zeros(g.size)
    if act.size:
        lam[act] = _nonneg_lsq(G[act].T, grad)
    return lam, _kkt(prob, x, grad, G.T @ lam)


def _nonneg_lsq(A, b) -> np.ndarray:
    """``argmin |A y - b|`` over ``y >= 0`` (bounded-variable least squares; SciPy's ``nnls`` aborted the
    process on some rank-deficient systems here)."""
    if A.shape[1] == 0:
        return np.zeros(0)
    return lsq_linear(A, b, bounds=(0.0, np.inf), method="bvls", tol=1e-14).x


def _candidates(x, spec):
    """Every constraint with its key, plus, at a node sitting on the box's corner, both faces (the node
    then carries a force anywhere in the corner's normal cone); a link's distance to the corner through
    its end node (zero gradient there) is left to the node's rows."""
    g, G, keys = all_constraints(x, spec, want_keys=True)
    keep = [i for i, k in enumerate(keys) if not (k[0] == "corner" and k[3] != 0 and g[i] < 1e-7)]
    g, G, keys = g[keep], G[keep], [keys[i] for i in keep]
    extra = []
    for k in keys:
        if k[0] in ("face", "top"):
            other = ("top" if k[0] == "face" else "face", k[1])
            v, _ = keyed(x, spec, [other])
            if abs(v[0]) < 1e-7:
                extra.append(other)
    if extra:
        v, rows = keyed(x, spec, extra)
        g, G, keys = np.concatenate([g, v]), np.vstack([G, rows]), keys + extra
    return g, G, keys


def _kkt(prob, x, grad, force) -> float:
    """Relative stationarity residual: over the largest sum of the terms' magnitudes (spring moments,
    loads; :meth:`~simgrip.reference.minimiser.DiscreteEnergy.scale`) or of the contact forces."""
    scale = max(prob.scale(x, 0.0), float(np.max(np.abs(force), initial=0.0)), 1e-300)
    return float(np.max(np.abs(grad - force))) / scale


def _kkt_newton(prob, spec, x, keys, mu=None, iterations=30):
    """Newton on the KKT system of the active constraints ``keys`` (pieces frozen).

    The Lagrangian's Hessian is ``V0``'s (analytic) plus a forward difference (step 1e-7) of the active
    constraints' gradients; its error only makes the rate linear with a factor ~1e-7.  Returns
    ``(x, mu, residual)`` or None when it does not converge to a relative residual of 1e-11.
    """
    n, m = x.size, len(keys)
    y = x.copy()
    if mu is None:
        _, Ga = keyed(y, spec, keys)
        mu = _nonneg_lsq(Ga.T, prob.gradient(y))
    for _ in range(iterations):
        ga, Ga = keyed(y, spec, keys)
        grad = prob.gradient(y)
        r = _kkt(prob, y, grad, Ga.T @ mu)
        if r < 1e-11 and float(np.max(np.abs(ga), initial=0.0)) < 1e-12:
            return y, mu, r
        H = prob.hessian(y)
        h = 1e-7
        for i in range(n):
            yp = y.copy()
            yp[i] += h
            H[:, i] -= (keyed(yp, spec, keys)[1].T @ mu - Ga.T @ mu) / h
        H = 0.5 * (H + H.T)
        K = np.block([[H, -Ga.T], [Ga, np.zeros((m, m))]])
        try:
            step = np.linalg.solve(K, -np.concatenate([grad - Ga.T @ mu, ga]))
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(step)):
            return None
        scale = min(1.0, 0.5 / max(float(np.max(np.abs(step[:n]))), 1e-300))  # at most half a radian a step
        y = y + scale * step[:n]
        mu = mu + scale * step[n:]
    return None


def _accept(prob, spec, y, mu, keys):
    """A KKT point of the whole problem: every constraint met, every active multiplier >= 0."""
    g = all_constraints(y, spec)[0]
    return (float(np.min(g, initial=0.0)) > -1e-10 and (mu.size == 0 or float(np.min(mu)) >= -1e-10)
            and not self_crossing(link_positions(y, spec.ds), spec.clearance * (1.0 - 1e-6)))


def _start(grip, params, prof, prob, spec, guess):
    n = spec.n
    if guess is None:
        return None
    if isinstance(guess, ConstrainedEquilibrium):
        if guess.n != n:
            raise ValueError(f"guess has n = {guess.n}, expected {n}")
        return np.array(guess.link_angles, float)
    if hasattr(guess, "link_angles") and np.size(guess.link_angles) == n:
        return np.array(guess.link_angles, float)
    if hasattr(guess, "theta_at"):
        return np.asarray(guess.theta_at((np.arange(n) + 0.5) / n), float)
    x = np.asarray(guess, float)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        raise ValueError(f"guess must be {n} finite link angles or a solution, got shape {x.shape}")
    return x


def _feasible_start(grip, params, prof, prob, spec, unit_rest):
    """The point-contact chain (Grips) or the rest shape (free rod) if it meets every constraint, else
    ``(x, t0)``: the last shape along ``t kappa0`` (t rising from 0, warm started) that meets every
    constraint with the tip pressing (``N >= 0``), from which :func:`solve_constrained` continues."""
    def base(t, guess):
        res = minimise(prob.with_(rest=t * prob.rest), unit_rest, grip_sign(grip, prof), guess)
        return res.x, -res.chi

    def ok(x, N):
        return (N >= 0.0 and float(np.min(all_constraints(x, spec)[0], initial=0.0)) >= 0.0
                and not self_crossing(link_positions(x, spec.ds), spec.clearance))

    x, N = base(1.0, None)
    if ok(x, N):
        return x, None
    best, t0, guess = None, None, None
    for t in np.linspace(0.0, 1.0, 41):
        try:
            xt, Nt = base(t, guess)
        except DiscreteError:
            if best is not None:
                break
            continue
        guess = xt
        if ok(xt, Nt):
            best, t0 = xt, t
        elif best is not None:
            break
    if best is None:
        raise ConstrainedError("no feasible start: no point-contact shape along t*kappa0 meets the constraints")
    return best, t0


def _solve_one(prob, spec, x, self_on, keys, mu, maxiter):
    """Active-set Newton from the guess's contact set, else SLSQP then Newton on the set SLSQP found."""
    reach = 4.0 * spec.ds
    if self_on:
        spec.pairs = self_pairs(link_positions(x, spec.ds), spec.ds, spec.clearance, reach)
    if keys is not None:
        out = _kkt_newton(prob, spec, x, keys, mu)
        if out is not None and _accept(prob, spec, out[0], out[1], keys):
            return out[0], keys
    for _ in range(10):
        res = _slsqp(prob, spec, x, maxiter)
        x = res.x
        if not self_on:
            break
        new = self_pairs(link_positions(x, spec.ds), spec.ds, spec.clearance, reach)
        known = {(int(a), int(b)) for a, b, _ in spec.pairs}
        if all((int(a), int(b)) in known for a, b, _ in new):
            break
        spec.pairs = np.unique(np.vstack([spec.pairs, new]), axis=0)
    g, G, keys = _candidates(x, spec)
    lam, kkt = _nnls(prob, x, g, G)
    act = np.nonzero((g < 1e-6) & (lam > 0.0))[0]
    keys = [keys[i] for i in act]
    out = _kkt_newton(prob, spec, x, keys, lam[act])
    if out is not None and _accept(prob, spec, out[0], out[1], keys):
        return out[0], keys
    if (not res.success and res.status != 8) or kkt > KKT_FALLBACK or float(np.min(g, initial=0.0)) < -1e-8:
        raise ConstrainedError(f"no KKT point: SLSQP {res.message!r}, relative residual {kkt:.2e}, "
                               f"least gap {float(np.min(g, initial=0.0)):.2e}")
    return x, keys


#: The homotopy's largest and least steps in the curvature's scale ``t`` (halved on a failed step).  A rod
#: curling onto itself (the free rod with no workpiece) takes the small one throughout: a larger step lets
#: SLSQP jump a turn of the spiral past another and land on a different self-contact state.
HOMOTOPY_STEP, SPIRAL_STEP, HOMOTOPY_MIN_STEP = 0.1, 0.02, 1e-3


def _homotopy(prob, spec, x, t0, self_on, maxiter):
    """From the feasible shape ``x`` at ``t0`` to ``t = 1`` (rest angles ``t * rest``), a step halved where a
    solve fails (SLSQP can jump through a contact from a far start; the step that fails is retried)."""
    big = SPIRAL_STEP if (spec.sd == 0 and spec.cylinder is None) else HOMOTOPY_STEP
    keys, t, dt = None, t0, big
    while t < 1.0:
        tn = min(1.0, t + dt)
        try:
            xn, kn = _solve_one(prob.with_(rest=tn * prob.rest), spec, x, self_on, keys, None, maxiter)
        except ConstrainedError:
            dt *= 0.5
            if dt < HOMOTOPY_MIN_STEP:
                raise
            continue
        x, keys, t = xn, kn, tn
        dt = min(big, 1.5 * dt)
    return x, keys


def solve_constrained(grip, params, profile, n, *, box=None, cylinder=None, self_contact=True, mirror=None,
                      clearance=DEFAULT_CLEARANCE, guess=None, maxiter=2000) -> ConstrainedEquilibrium:
    """The ``n``-link chain's energy minimised with every contact unilateral (see the module docstring).

    Parameters
    ----------
    grip : {"free", "I", "II"}
    params, profile, n
        As for :func:`~simgrip.reference.hinge_chain.solve_chain`.
    box : Box, optional
        Grips I/II's box (default ``Box()``: the tip ``DEFAULT_DEPTH`` below the top face (I) / above the
        bottom face (II), moving with it).
    cylinder : Cylinder, optional
        A fixed round workpiece in the plane.
    self_contact : bool
        Keep non-adjacent links ``clearance`` apart.
    mirror : bool, optional
        Keep ``X >= 0`` (the other finger of the pair, mirrored in ``X = 0``); default True for the grips,
        False for the free rod (a single finger).
    guess : ConstrainedEquilibrium, link angles (n,) or a solution with ``theta_at``, optional
        Start.  From a :class:`ConstrainedEquilibrium` its contact set is tried first (active-set Newton).
        Default: the point-contact chain (Grips) or the rest shape (free rod) when it meets every
        constraint, else a continuation in the curvature's scale from the last shape that does (a finger
        closing on the workpiece).  The minimiser is local: the answer depends on the path.

    Raises
    ------
    ValueError
        Bad arguments (named).
    ConstrainedError
        No KKT point reached.
    """
    if mirror is None:
        mirror = grip != "free"
    grip, params, prof, prob, unit_rest, spec, self_on = _problem(grip, params, profile, n, box, cylinder,
                                                                  self_contact, mirror, clearance)
    x = _start(grip, params, prof, prob, spec, guess)
    keys = mu = None
    if isinstance(guess, ConstrainedEquilibrium):
        keys = list(guess.keys)
    if x is None:
        x, t0 = _feasible_start(grip, params, prof, prob, spec, unit_rest)
        if t0 is not None:
            x, keys = _homotopy(prob, spec, x, t0, self_on, maxiter)
    x, keys = _solve_one(prob, spec, x, self_on, keys, mu, maxiter)
    return _equilibrium(grip, params, prob, spec, x, keys)


def _equilibrium(grip, params, prob, spec, x, keys) -> ConstrainedEquilibrium:
    """The state at ``x`` with the contact forces of the active set ``keys`` (NNLS multipliers)."""
    geo = Geometry(x, spec.ds)
    grad = prob.gradient(x)
    if keys:
        _, Ga = keyed(x, spec, keys)
        mu = _nonneg_lsq(Ga.T, grad)
        kkt = _kkt(prob, x, grad, Ga.T @ mu)
    else:
        mu, kkt = np.zeros(0), _kkt(prob, x, grad, np.zeros_like(grad))
    contacts = []
    N, Ff = 0.0, (-params.M if grip != "free" else 0.0)
    for key, lm in zip(keys, mu):
        kind = key[0]
        if lm <= 0.0:
            continue
        if kind == "tip":
            N = float(lm)
        elif kind in ("face", "mirror"):
            k = key[1]
            contacts.append(Contact(kind, k, geo.P[k].copy(), np.array([lm, 0.0])))
        elif kind == "top":
            k = key[1]
            f = np.array([0.0, float(spec.sd) * lm])
            Ff -= f[1]  # the box's balance: its other contacts' vertical forces go to the tip's friction
            contacts.append(Contact("top" if spec.sd > 0 else "bottom", k, geo.P[k].copy(), f))
        elif kind in ("corner", "cylinder"):
            j = key[1]
            q = np.array([spec.xb, geo.P[-1, 1] + spec.sd * spec.depth]) if kind == "corner" else \
                np.array([spec.cylinder.x, spec.cylinder.y])
            t = geo.tangent(j)
            u = float(np.clip(np.dot(q - geo.P[j], t), 0.0, spec.ds))
            p = geo.P[j] + u * t
            d = p - q
            if np.linalg.norm(d) > 1e-9:
                dn = d / np.linalg.norm(d)
            else:  # the corner on the centreline: pushed along the link's normal, away from the box
                nl = np.array([-t[1], t[0]])
                dn = nl if np.dot(nl, [1.0, float(spec.sd)]) > 0 else -nl
            f = lm * dn
            if kind == "corner":
                Ff -= f[1]
            contacts.append(Contact(kind, j, p, f))
        elif kind == "self":
            k, j = key[1], key[2]
            t = geo.tangent(j)
            contacts.append(Contact("self", k, geo.P[k].copy(), lm * key[3] * np.array([-t[1], t[0]]), other=j))
    return ConstrainedEquilibrium(grip=grip, n=spec.n, params=params, link_angles=x, nodes=geo.P,
                                  tip=geo.P[-1].copy(), N=N, tip_friction=Ff, contacts=tuple(contacts),
                                  energy=float(prob.energy(x)), kkt_residual=kkt, keys=tuple(keys))
