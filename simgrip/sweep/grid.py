"""The grid of a design sweep: six axes (kappa, D, M, mu, b, gamma), each one value or an inclusive linspace.

A :class:`SweepGrid` is the full Cartesian product of its axes in a fixed
order, :data:`AXES`, the first axis varying slowest (``itertools.product``), so
point ``i`` and its parameters follow from the grid alone: rows of
``sweep.csv`` come in this order whatever ran them.  Axis values are checked
when the grid is made: each must be a valid value of its parameter
(:class:`simgrip.params.DimensionlessParams`, :class:`simgrip.profiles.Uniform`);
combinations that a grip cannot build (e.g. a Grip III corner that misses the
rod) are the points' business (status ``rejected``).

``contact`` (:data:`CONTACTS`) is the settle's contact model: ``"point"`` (the paper's point contact, Newton's
default), ``"surface"`` (MuJoCo's contact point on the tip sphere; the dynamics' only one) or ``"full"`` (every
link and the tip touch the workpiece and the finger itself, :mod:`simgrip.settle.full_contact`; Grips I/II,
optionally grasped at ``box_depth``).  A full-contact sweep has no BVP beside its points (``reference``
``"none"``): the point-contact BVP is another problem past the onset, and the free-boundary reference
(:mod:`simgrip.reference.full_contact`) is not run per point.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from simgrip.chain import check_link_count, check_links
from simgrip.params import DimensionlessParams, _finite, check_grip
from simgrip.profiles import Uniform

__all__ = ["AXES", "CONTACTS", "DEFAULTS", "check_contact", "default_contact", "SweepGrid", "SweepPoint", "axis_count",
           "parse_axis", "make_grid"]

#: Swept parameters in grid order (the CLI option of each is ``--<name>``; ``mu`` is ``mu_s``).
AXES = ("kappa", "D", "M", "mu", "b", "gamma")
#: Values of the axes not given (the CLI's defaults: the paper's standard case).
DEFAULTS = {"D": 1.0, "M": 5.0, "mu": 1.0, "b": 0.6, "gamma": 0.8}
#: Settle methods (:func:`simgrip.settle.settle`).
METHODS = ("newton", "dynamics")
#: Grips a sweep can run: the free rod holds nothing.
SWEEP_GRIPS = ("I", "II", "III")
#: References a sweep can compare with: the elastica BVP (default), or none (the simulation only).
REFERENCES = ("bvp", "none")
#: Contact models of a sweep (:func:`simgrip.settle.settle`'s ``contact``; ``"full"``: :mod:`simgrip.sim.full_contact`).
CONTACTS = ("point", "surface", "full")


def default_contact(method: str) -> str:
    """The settle's own contact for ``method``: ``"point"`` (Newton) or ``"surface"`` (dynamics)."""
    return "point" if method == "newton" else "surface"


def check_contact(grip: str, method: str, contact, box_depth, reference) -> tuple[str, float | None, str]:
    """``(contact, box_depth, reference)`` of a sweep, validated; ``contact`` None: the method's default,
    ``reference`` None: ``"bvp"``, or ``"none"`` with ``contact="full"``.  ValueError naming ``contact``,
    ``box_depth`` or ``reference``."""
    if contact is None:
        contact = default_contact(method)
    c = str(contact).strip().lower() if isinstance(contact, str) else contact
    if c not in CONTACTS:
        raise ValueError(f"contact must be one of {CONTACTS}, got {contact!r}")
    if method == "dynamics" and c == "point":
        raise ValueError("contact: 'point' needs method newton (the dynamics' friction acts at MuJoCo's surface "
                         "contact: 'surface')")
    if c == "full" and grip not in ("I", "II"):
        raise ValueError(f"contact: 'full' sweeps Grips I and II (the full-contact settle has no Grip III), "
                         f"got {grip!r}")
    if box_depth is not None:
        if c != "full":
            raise ValueError("box_depth: needs contact 'full'")
        from simgrip.sim.full_contact import check_grasp

        box_depth, _ = check_grasp(grip, "full", box_depth, None)
    if reference is None:
        reference = "none" if c == "full" else "bvp"
    if c == "full" and str(reference).strip().lower() == "bvp":
        raise ValueError("reference: 'bvp' (the point-contact BVP) is not the full-contact problem's reference; a "
                         "full-contact sweep runs with reference 'none' (the free-boundary reference: simgrip solve "
                         "GRIP --contact full, or compare --contact full --box-depth D, per point)")
    return c, box_depth, reference
#: Most points of one continuation segment (:meth:`SweepGrid.segments`): the first is solved cold, the others
#: warm from their neighbour.  32 puts a cold start (~4x a warm one at n = 32) at ~10 % of the BVP's time and
#: still cuts a 300-point line into 10 tasks for the workers.
SEGMENT_POINTS = 32


def _number(name: str, what: str, value) -> float:
    """``value`` (a number, or the command line's text of one) as a finite float; ValueError naming the axis and
    the part (``the value``, ``START``, ...)."""
    if isinstance(value, str):  # the CLI's words ('-7', 'nan'): read here; _finite refuses text elsewhere
        try:
            value = float(value)
        except ValueError:
            pass  # _finite names it
    return _finite(f"{name}: {what}", value)


def axis_count(name: str, values) -> int:
    """Number of values axis ``name`` would have, from the option alone (one value, or ``START STOP NUM``).

    Nothing is allocated: ``NUM`` is checked as a number (``ValueError``
    naming ``name`` and ``NUM`` for NaN, inf, a non-integer or a value below 1)
    and returned as an exact Python int, however large (``1e300`` included);
    the bounds on it are :func:`simgrip.sweep.budget.check_sweep`'s.
    """
    if name not in AXES:
        raise ValueError(f"axis must be one of {AXES}, got {name!r}")
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
        values = [values]
    values = list(values)
    if len(values) == 1:
        return 1
    if len(values) != 3:
        raise ValueError(f"{name} takes one value or START STOP NUM, got {len(values)} values {values!r}")
    num_f = _number(name, "NUM", values[2])
    if num_f != int(num_f) or num_f < 1:
        raise ValueError(f"{name}: NUM must be an integer >= 1, got {values[2]!r}")
    return int(num_f)


def parse_axis(name: str, values) -> tuple[float, ...]:
    """Values of axis ``name`` from one value or ``(START, STOP, NUM)`` (inclusive linspace).

    ``NUM`` is an integer >= 1 and at most
    :data:`~simgrip.sweep.budget.MAX_AXIS_VALUES` (checked before any array
    exists, :func:`axis_count`); ``STOP >= START`` when ``NUM > 1`` (``NUM = 1``
    gives ``START``).  Every value is checked as a value of its parameter.
    Raises ``ValueError`` naming ``name``.
    """
    from simgrip.sweep.budget import MAX_AXIS_VALUES

    num = axis_count(name, values)
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
        values = [values]
    values = list(values)
    if len(values) == 1:
        out = (_number(name, "the value", values[0]),)
    else:
        start = _number(name, "START", values[0])
        stop = _number(name, "STOP", values[1])
        if num > MAX_AXIS_VALUES:
            raise ValueError(f"{name}: NUM = {values[2]!r}: at most {MAX_AXIS_VALUES} values on one axis "
                             "(every value is listed in sweep.json)")
        if num == 1 and stop != start:  # np.linspace would give START alone: a STOP that is not used is a mistake
            raise ValueError(f"{name}: NUM = 1 is START alone, but STOP {stop!r} differs from START {start!r}: "
                             "give one value instead")
        if num > 1 and stop < start:
            raise ValueError(f"{name}: STOP must not be below START when NUM > 1, got START {start!r}, STOP {stop!r}")
        if num > 1 and stop == start:
            raise ValueError(f"{name}: STOP equals START with NUM = {num}: give one value instead")
        out = tuple(float(v) for v in np.linspace(start, stop, num)) if num > 1 else (start,)
    for v in out:
        _check_value(name, v)
    return out


def _check_value(name: str, v: float) -> None:
    """``ValueError`` naming ``name`` when ``v`` is not a valid value of that parameter."""
    if name == "kappa":
        Uniform(v)
    else:
        key = "mu_s" if name == "mu" else name
        try:
            DimensionlessParams(**{key: v})
        except ValueError as exc:
            msg = str(exc)
            raise ValueError(msg if msg.startswith(name) else f"{name}: {msg}") from None


@dataclass(frozen=True)
class SweepPoint:
    """One grid point: what a worker needs to settle and solve it (picklable)."""

    index: int
    grip: str
    kappa: float
    D: float
    M: float
    mu: float
    b: float
    gamma: float
    links: int
    method: str
    reference: str = "bvp"
    contact: str | None = None
    box_depth: float | None = None
    #: ``(axis, value)``: the grid point after this one on its line (the run along the fastest-varying swept
    #: axis that :meth:`SweepGrid.segments` cuts), that axis's next value; ``None`` at a line's end.  A segment
    #: that ends before its line does checks its walk there (:func:`simgrip.sweep.reference.segment_references`);
    #: the simulation does not read it.
    after: tuple | None = None

    def settle_options(self) -> dict:
        """Keywords of :func:`simgrip.compare.simulate` for the point's contact: none for the method's default
        contact (a sweep without ``contact`` settles as before), else ``contact`` (and ``box_depth``)."""
        if self.contact in (None, default_contact(self.method)):
            return {}
        out = {"contact": self.contact}
        if self.box_depth is not None:
            out["box_depth"] = self.box_depth
        return out

    def params(self) -> DimensionlessParams:
        """The point's :class:`DimensionlessParams` (validated)."""
        return DimensionlessParams(D=self.D, M=self.M, b=self.b, mu_s=self.mu, gamma=self.gamma)

    def values(self) -> dict:
        """``{axis: value}`` in :data:`AXES` order."""
        return {a: getattr(self, a) for a in AXES}


@dataclass(frozen=True)
class SweepGrid:
    """A sweep's definition: grip, axis values (each a non-empty tuple), links per finger, settle method,
    reference (``"bvp"``: the elastica BVP beside every point; ``"none"``: the simulation only; None: ``"bvp"``,
    ``"none"`` for full contact), contact (:data:`CONTACTS`; None: the method's own, :func:`default_contact`) and
    the full-contact grasp depth ``box_depth`` (over ``l``, in ``(0, 1]``; None: the box stays below the palm)."""

    grip: str
    axes: dict
    links: int
    method: str = "newton"
    reference: str | None = "bvp"
    contact: str | None = None
    box_depth: float | None = None

    def __post_init__(self):
        grip = check_grip(self.grip)
        if grip not in SWEEP_GRIPS:
            raise ValueError(f"grip must be one of {SWEEP_GRIPS} for a sweep (the free rod holds nothing), got {self.grip!r}")
        object.__setattr__(self, "grip", grip)
        if set(self.axes) != set(AXES):
            raise ValueError(f"axes must give every one of {AXES}, got {sorted(self.axes)}")
        object.__setattr__(self, "axes", {a: tuple(float(v) for v in self.axes[a]) for a in AXES})
        for a in AXES:
            if not self.axes[a]:
                raise ValueError(f"{a}: the axis has no values")
        object.__setattr__(self, "links", check_links(self.links))
        method = str(self.method).strip().lower()
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {self.method!r}")
        object.__setattr__(self, "method", method)
        contact, depth, reference = check_contact(grip, method, self.contact, self.box_depth, self.reference)
        object.__setattr__(self, "contact", contact)
        object.__setattr__(self, "box_depth", depth)
        reference = str(reference).strip().lower()
        if reference not in REFERENCES:
            raise ValueError(f"reference must be one of {REFERENCES}, got {self.reference!r}")
        object.__setattr__(self, "reference", reference)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values of each axis, in :data:`AXES` order."""
        return tuple(len(self.axes[a]) for a in AXES)

    @property
    def size(self) -> int:
        """Number of points."""
        return math.prod(self.shape)

    @property
    def swept(self) -> tuple[str, ...]:
        """Axes with more than one value, in :data:`AXES` order (the map uses the first two)."""
        return tuple(a for a in AXES if len(self.axes[a]) > 1)

    def point(self, index: int) -> SweepPoint:
        """Point ``index`` (grid order)."""
        idx = np.unravel_index(int(index), self.shape)
        vals = {a: self.axes[a][i] for a, i in zip(AXES, idx)}
        return SweepPoint(index=int(index), grip=self.grip, links=self.links, method=self.method,
                          reference=self.reference, contact=self.contact, box_depth=self.box_depth,
                          after=self._after(int(index)), **vals)

    def points(self):
        """Every point, in grid order."""
        for i, combo in enumerate(itertools.product(*(self.axes[a] for a in AXES))):
            yield SweepPoint(i, self.grip, *combo, links=self.links, method=self.method, reference=self.reference,
                             contact=self.contact, box_depth=self.box_depth, after=self._after(i))

    def _after(self, index: int) -> tuple | None:
        """``SweepPoint.after`` of point ``index``: the fastest-varying swept axis and its value at the next
        point on the line (the axes after it have one value each, so the position on the line is ``index``
        modulo the line's length); ``None`` at a line's end or without a swept axis."""
        swept = self.swept
        if not swept:
            return None
        values = self.axes[swept[-1]]
        pos = index % len(values)
        return None if pos == len(values) - 1 else (swept[-1], values[pos + 1])

    def segments(self, max_points: int = SEGMENT_POINTS):
        """The grid cut into continuation segments: ``(start, stop)`` index ranges (``stop`` exclusive), in order.

        A segment is a run of consecutive points along the grid's fastest-varying swept axis (the last of
        :data:`AXES` with more than one value; the kappa axis of a kappa-only sweep), never across the end of
        such a line, at most ``max_points`` long, cut from the line's start.  The cut depends on the grid
        alone, so a point's warm start (its segment predecessor) is the same for any number of workers and
        any batch size; segments are contiguous in grid order (saved batches stay runs of points).
        """
        if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 1:
            raise ValueError(f"max_points must be a positive integer, got {max_points!r}")
        line = self.shape[AXES.index(self.swept[-1])] if self.swept else 1
        for a in range(0, self.size, line):
            for k in range(0, line, max_points):
                yield a + k, a + min(k + max_points, line)

    def spec(self) -> dict:
        """JSON-able definition (the identity of a sweep: ``--resume`` checks it).  ``reference`` appears
        only when it is not the default ``"bvp"``, ``contact`` when it is not the method's own and ``box_depth``
        when given (so that sweeps saved before those options resume)."""
        out = {"grip": self.grip, "links": self.links, "method": self.method,
               "axes": {a: list(self.axes[a]) for a in AXES}}
        if self.reference != "bvp":
            out["reference"] = self.reference
        if self.contact != default_contact(self.method):
            out["contact"] = self.contact
        if self.box_depth is not None:
            out["box_depth"] = self.box_depth
        return out


def make_grid(grip: str, *, kappa, D=None, M=None, mu=None, b=None, gamma=None, links: int,
              method: str = "newton", reference: str | None = "bvp", contact: str | None = None,
              box_depth: float | None = None) -> SweepGrid:
    """A :class:`SweepGrid` from axis specifications (see :func:`parse_axis`); ``None`` takes :data:`DEFAULTS`.

    The grid's size is computed from the ``NUM`` values alone and checked
    (:func:`simgrip.sweep.budget.check_sweep`: points, values per axis, the
    client's memory) before any axis is built; ``ValueError`` names the
    option(s) and gives the estimate.  Time and disk are checked by
    :func:`~simgrip.sweep.run.run_sweep`, which knows the workers and the folder.
    """
    from simgrip.sweep.budget import check_sweep

    given = {"kappa": kappa, "D": D, "M": M, "mu": mu, "b": b, "gamma": gamma}
    if kappa is None:
        raise ValueError("kappa is required (--kappa K or --kappa START STOP NUM)")
    specs = {a: DEFAULTS[a] if v is None else v for a, v in given.items()}
    counts = {a: axis_count(a, v) for a, v in specs.items()}
    links = check_link_count(links)  # [2, MAX_LINKS], as every command's --links
    check_sweep(counts, links, str(method).strip().lower(), workers=None)
    axes = {a: parse_axis(a, v) for a, v in specs.items()}
    return SweepGrid(grip=grip, axes=axes, links=links, method=method, reference=reference, contact=contact,
                     box_depth=box_depth)
