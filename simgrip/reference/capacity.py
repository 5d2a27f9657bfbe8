"""What a grip can hold: feasibility margin, least friction coefficient, largest load.

The one implementation of the paper's load-capacity criteria (Figs. 15 b, 16),
used by the figures as well.  A grip holds its workpiece when the normal force
is positive, friction suffices (``|f| <= mu_s n``) and, for Grip III, the tip
stays below the contact (condition 23).  :func:`margin` folds the three into one
number that is ``>= 0`` exactly where the grip holds; :func:`largest_load`
marches the load ``M`` up along the equilibrium branch and locates the first
zero of the margin (or the fold where the branch ends).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import replace as _dc_replace
from typing import Sequence

from scipy.optimize import brentq

from simgrip.params import M_MAX, DimensionlessParams, _positive, check_grip
from simgrip.profiles import as_profile
from simgrip.reference.arguments import check_failures, check_tol
from simgrip.reference.bvp import BvpProblem
from simgrip.reference.continuation import MAX_JUMP, continue_along, linear_path
from simgrip.reference.elastica import (
    ElasticaError,
    ElasticaSolution,
    check_guess,
    checked_problem,
    grip_side,
    march,
    solve,
    solve_problem,
)

__all__ = ["LoadCapacity", "largest_load", "least_mu", "margin", "margin_terms", "max_load", "track_largest_load"]


def margin_terms(sol: ElasticaSolution) -> dict:
    """The feasibility conditions of a grip solution as numbers that are ``>= 0`` when met.

    ``"friction"``: ``mu_s n - |f|``; ``"contact"``: ``n``; Grip III also
    ``"tip_clear"``: ``Y(gamma) - Y(1)`` (forces over ``rho g l``, heights over ``l``).
    """
    if not isinstance(sol, ElasticaSolution):  # (None raised AttributeError 'no attribute params')
        raise ValueError(f"sol must be an ElasticaSolution (simgrip.reference.solve's answer), got "
                         f"{type(sol).__name__}")
    terms = {"friction": sol.params.mu_s * sol.normal_force - abs(sol.friction_force),
             "contact": sol.normal_force}
    if sol.grip == "III":
        terms["tip_clear"] = float(sol.contact[1] - sol.tip[1])
    return {k: float(v) for k, v in terms.items()}


def margin(sol: ElasticaSolution) -> float:
    """Continuous feasibility margin: ``>= 0`` iff feasible (up to the strict ``n > 0``).

    The least of :func:`margin_terms`; a Grip I/II solution in the other grip's shape
    (``feasibility["grip_shape"]`` False) has at most the tip's height on the wrong side,
    ``grip_side * Y(1) <= 0`` (over ``l``), so that its margin is not positive either.
    """
    m = min(margin_terms(sol).values())
    if sol.grip in ("I", "II") and not sol.feasibility.get("grip_shape", True):
        m = min(m, float(grip_side(sol.grip) * sol.tip[1]))
    return m


def _grip_only(grip: str, what: str) -> None:
    if grip == "free":
        raise ValueError(f"grip must be one of 'I', 'II', 'III' for {what}, got 'free'")


def least_mu(grip: str, params: DimensionlessParams, profile, **kw) -> float:
    """Least friction coefficient that holds ``params.M`` (paper Fig. 16a).

    ``|friction| / normal`` of the equilibrium; ``inf`` where the configuration
    cannot hold at any friction (contact lost, Grip III's tip touching the
    workpiece, or a Grip I/II solution in the other grip's shape).  Keyword
    arguments go to :func:`~simgrip.reference.elastica.solve`.
    """
    _grip_only(check_grip(grip), "least_mu")
    sol = solve(grip, params, profile, **kw)
    if not all(sol.feasibility.get(k, True) for k in ("contact", "tip_clear", "grip_shape")):
        return math.inf
    return sol.required_mu


@dataclass(frozen=True)
class LoadCapacity:
    """Result of :func:`largest_load`.

    Attributes
    ----------
    M : float
        Largest load ``M = m/(rho l)`` held at ``params.mu_s``: 0.0 when none is held
        below ``M_max``, ``inf`` when ``M_max`` is still held, NaN when
        :func:`track_largest_load` skipped a failed point.
    reason : str
        What ends the range: ``"friction"``, ``"contact"`` or ``"tip_clear"`` (that
        condition of :func:`margin_terms` fails beyond ``M``), ``"fold"`` (the
        equilibrium branch ends: the finger snaps through), ``"limit"`` (held at
        ``M_max``), ``"none"`` (nothing held) or ``"failed"``.
    solution : ElasticaSolution or None
        The last held equilibrium the search met, at ``M`` or within the search
        tolerance below it (``M_max`` for ``"limit"``);
        pass the whole result as ``start`` to the search of a neighbouring profile.
    """

    M: float
    reason: str
    solution: ElasticaSolution | None


def largest_load(
    grip: str,
    params: DimensionlessParams,
    profile,
    *,
    start: LoadCapacity | None = None,
    M_max: float = 200.0,
    xtol: float = 1e-8,
    gravity: bool = True,
    tip_load=(0.0, 0.0),
    contact_moment: float = 0.0,
    gamma: float | None = None,
    guess: ElasticaSolution | None = None,
    tol: float = 1e-8,
) -> LoadCapacity:
    """Largest workpiece load ``M`` held at ``params.mu_s`` (paper Figs. 15b, 16b), with the reason.

    The contact force depends on ``M``, so ``M`` is marched up from 0 along the
    equilibrium branch of ``solve(grip, params.replace(M=0), profile)`` (natural
    continuation that refuses jumps of ``theta`` to another branch).  The march
    stops at the first feasible-to-infeasible transition, located with Brent's
    method (to ``xtol``) on :func:`margin`, or at a fold of the branch (the grip
    snaps through beyond it), located by bisection.  If ``M = 0`` is infeasible,
    the first feasible ``M`` of the march is the starting point.

    ``start`` (the result for a neighbouring profile, e.g. the previous point of a
    sweep) starts the march at ``start.M`` instead of 0 when this profile still
    holds that load there: a sweep then costs a few solves per point.  ``guess``
    warm-starts the ``M = 0`` solve; the other keywords are those of
    :func:`~simgrip.reference.elastica.solve`.
    """
    grip, params, P = checked_problem(grip, params, profile, gravity=gravity, tip_load=tip_load,
                                      contact_moment=contact_moment, gamma=gamma)
    _grip_only(grip, "max_load")
    m_top = _positive("M_max", M_max)
    if m_top > M_MAX:  # the search's loads are M values: none above the model's range (simgrip.params)
        raise ValueError(f"M_max must be at most {M_MAX:g} (the model's range of M, simgrip.params), got {M_max!r}")
    search = _Search(grip, params, P, m_top, _positive("xtol", xtol), check_tol(tol))
    return search.run(check_guess(guess), start)


def max_load(grip: str, params: DimensionlessParams, profile, **kw) -> float:
    """Largest workpiece load ``M`` held at ``params.mu_s`` (paper Fig. 16b).

    ``largest_load(...).M``: 0.0 when none is held below ``M_max``, ``inf`` when
    the grip still holds at ``M_max``.  Keywords are those of :func:`largest_load`.
    """
    return largest_load(grip, params, profile, **kw).M


def track_largest_load(
    grip: str,
    params: DimensionlessParams,
    profiles: Sequence,
    guesses: Sequence | None = None,
    *,
    failures: str = "raise",
    M_max: float = 200.0,
    xtol: float = 1e-8,
    tol: float = 1e-8,
    **kw,
) -> list[LoadCapacity]:
    """:func:`largest_load` along a sweep of profiles, each search started from the previous result.

    ``guesses`` (one per profile, ``None`` allowed), e.g. the solutions of a
    :func:`~simgrip.reference.elastica.sweep`, warm-start the ``M = 0`` solves.
    With ``failures="skip"`` a point whose solve fails gives
    ``LoadCapacity(nan, "failed", None)`` instead of raising
    :class:`~simgrip.reference.elastica.ElasticaError`.  Other keywords are those
    of :func:`~simgrip.reference.elastica.solve` (``gravity``, ``gamma``, ...).
    """
    check_failures(failures)
    profiles = [as_profile(p) for p in profiles]
    if guesses is not None and len(guesses) != len(profiles):
        raise ValueError(f"guesses must hold one entry per profile ({len(profiles)}), got {len(guesses)}")
    if not profiles:
        return []
    grip, params, P = checked_problem(grip, params, profiles[0], **kw)
    _grip_only(grip, "max_load")
    M_max, xtol, tol = _positive("M_max", M_max), _positive("xtol", xtol), check_tol(tol)

    def one(i, prof, start):
        guess = None if guesses is None else check_guess(guesses[i])
        return _Search(grip, params, _dc_replace(P, profile=prof), M_max, xtol, tol).run(guess, start)

    return march(profiles, one, failures, failed=LoadCapacity(math.nan, "failed", None),
                 ok=lambda cap: cap.solution is not None)


class _Search:
    """The march in ``M`` and the location of its end, for one checked problem ``P``."""

    def __init__(self, grip, params, P: BvpProblem, M_max: float, xtol: float, tol: float):
        self.grip, self.params, self.P = grip, params, P
        self.M_max, self.xtol, self.tol = M_max, xtol, tol

    def at(self, M: float) -> BvpProblem:
        return _dc_replace(self.P, N2=-M)

    def follow(self, prev: ElasticaSolution, M: float) -> ElasticaSolution | None:
        """Continue ``prev`` to load ``M`` along its own branch, or ``None`` at a fold."""
        raw = continue_along(linear_path(prev._raw.prob, self.at(M)), prev._raw, self.tol,
                             max_jump=MAX_JUMP, h_min=1 / 8, max_tries=12)
        return None if raw is None else ElasticaSolution.from_bvp(self.grip, self.params.replace(M=M), raw)

    def _first(self, guess, start: LoadCapacity | None) -> ElasticaSolution:
        """The march's first point: ``start``'s load when still held there, else ``M = 0``."""
        if start is not None and start.solution is not None and start.solution.params.M > 0.0:
            s = self.follow(start.solution, start.solution.params.M)
            if s is not None and s.feasible:
                return s
        raw = solve_problem(self.at(0.0), guess, self.tol)
        if raw is None:
            raise ElasticaError(f"largest_load: no equilibrium of grip {self.grip!r} at M = 0 for {self.P.profile!r}")
        return ElasticaSolution.from_bvp(self.grip, self.params.replace(M=0.0), raw)

    def run(self, guess, start: LoadCapacity | None) -> LoadCapacity:
        prev = self._first(guess, start)
        M = prev.params.M
        step = max(0.25, 0.2 * M)
        last_ok = prev if prev.feasible else None
        while True:  # march M up along the branch; stop at the first infeasible point or fold
            if M >= self.M_max:
                if prev.feasible:
                    return LoadCapacity(math.inf, "limit", prev)
                return _held(last_ok, "none")
            Mn = min(self.M_max, M + step)
            nxt = self.follow(prev, Mn)
            if nxt is None or (prev.feasible and not nxt.feasible):
                break
            if nxt.feasible:
                last_ok = nxt
            prev, M = nxt, Mn
            step = max(0.25, 0.2 * M)
        if not prev.feasible:  # the branch ends before any load is held
            return _held(last_ok, "none")
        if nxt is None:
            return self._fold(prev, Mn)
        return self._boundary(prev, nxt)

    def _fold(self, lo: ElasticaSolution, b: float) -> LoadCapacity:
        """Bisect the fold between the held ``lo`` and the load ``b`` with no nearby solution."""
        a = lo.params.M
        while b - a > max(self.xtol, 1e-5 * b):
            mid = 0.5 * (a + b)
            s = self.follow(lo, mid)
            if s is None:
                b = mid
            elif not s.feasible:  # the margin crosses zero before the fold
                return self._boundary(lo, s)
            else:
                lo, a = s, mid
        return LoadCapacity(a, "fold", lo)

    def _boundary(self, lo: ElasticaSolution, hi: ElasticaSolution) -> LoadCapacity:
        """Root of the margin between the held ``lo`` and the dropped ``hi``."""
        terms = margin_terms(hi)
        reason = min(terms, key=terms.get)
        a, b = lo.params.M, hi.params.M
        seen: dict = {}

        def phi(Mv):
            s = self.follow(lo, Mv)
            if s is None:
                raise ElasticaError("fold inside the feasibility bracket")
            seen[Mv] = s
            return margin(s)

        if margin(lo) >= 0 > margin(hi):
            try:
                root = float(brentq(phi, a, b, xtol=self.xtol))
            except ElasticaError:
                pass
            else:
                held = [s for s in seen.values() if s.feasible and s.params.M <= root]
                return LoadCapacity(root, reason, max(held, key=lambda s: s.params.M, default=lo))
        while b - a > self.xtol:  # strict n > 0 corner, or a fold inside: bisect the flag
            mid = 0.5 * (a + b)
            s = self.follow(lo, mid)
            if s is not None and s.feasible:
                lo, a = s, mid
            else:
                b = mid
        return LoadCapacity(a, reason, lo)


def _held(last_ok: ElasticaSolution | None, reason: str) -> LoadCapacity:
    if last_ok is None:
        return LoadCapacity(0.0, "none", None)
    return LoadCapacity(last_ok.params.M, reason, last_ok)
