"""Compile once, set in place: a bounded cache of compiled scenes, keyed on their structure.

MuJoCo's compile of a serial chain is costly (``mj_setConst`` solves with the
dense joint-space inertia of the chain: ~35 ms at 256 links, ten times the
settle), and every design point of a sweep used to pay it.  Here a scene of a
given *structure* is compiled once; the next point of the same structure
gets the cached scene with its parameters written into the compiled model in
place:

* hinge stiffness ``(EI/l) * springs.stiffness`` (``D``) and rest angles
  (``qpos_spring``, the profile ``kappa0(s)``), per finger;
* the links' masses and inertias (``rho``); the workpiece's mass, inertia,
  gravity compensation (``M``), size and position (``b``, ``gamma``, the start
  shape);
* the contact pairs' friction (``mu_s``) and the gravity (``g``);
* then ``mujoco.mj_setConst`` where an input of it changed (masses, inertias,
  sizes, the workpiece's placement: ``body_subtreemass``, ``*_invweight0``,
  ``dof_M0``, ``geom_rbound``, ``geom_aabb``) and the compiler's statistics
  (``stat``, ``dof_length``: ``mj_setConst`` leaves them, :func:`_set_stat`
  sums them in the compiler's order); kept otherwise (a curvature or
  stiffness sweep never pays it);
* the data reset (``mj_resetData``) and the start angles set as the fresh
  build sets them.

The result is **bit-identical** to a fresh build (every array of the model
and the settled state: ``tests/test_scene_reuse.py``).  Whatever a settle
changed in the model (time step, damping, ``solref``: the settles write
them) is restored from a pristine copy taken when the entry was last set.

Structure (the key): the builder, the grip, links, fingers, every other
keyword of the builder (bound to its signature with defaults), the finger
length ``l`` (it scales every geom), and what the parameters
decide about the model's elements: the Grip III links paired with the
corner (``contact_window`` around the start's contact).  The K-finger
cradle's corner capsules take their frames from ``fromto``: those are
compiled alone (a spec of just the capsules, ~0.2 ms) and copied in (the K-finger
builders go through the same cache from :mod:`simgrip.gripper.reuse`).
``initial_angles`` is a value, not structure.  A keyword a
builder gains later (a contact mode...) is not trusted until a test compares
it: while it is off its default the scene is built fresh
(:data:`VERIFIED_KEYWORDS`).

Ownership and safety.  The cache is bounded (:data:`CACHE_SIZE` scenes per
thread, least recently used dropped).  A scene handed out is **owned by the
cache**: it is valid until the next call for the same structure in the same
thread, which resets and rewrites it; callers settle it and read the state
(a :class:`~simgrip.settle.SettledState` holds copies, not the scene), or
use :func:`simgrip.scenes.build_scene` for a scene of their own.  Its
``spec`` is None once it has been set in place (the spec would describe the
first build's parameters); an interruption while it is being set (an error,
Ctrl-C, a deadline) drops the entry.  Each
thread has its own cache (``threading.local``; no lock needed, no scene
shared between threads); each process (a Dask worker, a ``multiprocessing``
child) has its own too.  :func:`clear` empties the calling thread's cache.
"""

from __future__ import annotations

import contextlib
import copy
import ctypes
import functools
import inspect
import threading
from collections import OrderedDict

import mujoco
import numpy as np

from simgrip.chain import chain_springs
from simgrip.params import check_grip, check_grip_iii_reach
from simgrip.profiles import as_profile

__all__ = ["CACHE_SIZE", "VERIFIED_KEYWORDS", "build_scene", "cache_info", "clear", "scene"]

#: Compiled scenes kept per thread (least recently used dropped first).  A sweep, a figure or a stress run
#: uses one or a few structures at a time.  Memory per scene: the model twice (its pristine copy), MjData and
#: MjData's arena: 0.13 MB + 16 MB of arena at 32 links, 5 MB + 29 MB of arena at 256 (the arena is
#: allocated, touched only as far as a step uses it).
CACHE_SIZE = 8

_local = threading.local()


class _Entry:
    """A cached scene, the pristine model its parameters were last set into, and the inputs of ``mj_setConst``."""

    __slots__ = ("scene", "template", "const_inputs", "fields", "model", "runs")

    def __init__(self, scene, const_inputs):
        self.scene = scene
        self.const_inputs = const_inputs
        self.snapshot()

    def snapshot(self) -> None:
        """Take the model as it is now (freshly set, not yet settled) as the one to restore."""
        m = self.scene.model
        template = copy.copy(m)
        names = _array_fields(m)
        fields = [(getattr(m, k), getattr(template, k)) for k in names]
        # the model (and the template: its addresses) stay alive with the entry; restore checks it is the scene's
        self.template, self.fields, self.model = template, fields, m
        self.runs = _copy_runs(m, template, names)

    def restore(self) -> None:
        """Undo whatever was written into the model since :meth:`snapshot` (the settles' options, damping...)."""
        m, t = self.scene.model, self.template
        if self.runs is not None and m is self.model:
            for dst, src, size in self.runs:  # the same bytes as the loop below, a few calls (_copy_runs)
                ctypes.memmove(dst, src, size)
        else:
            for dst, src in self.fields:  # same shapes and dtypes: an exact copy (a quarter of np.copyto's call cost)
                dst[...] = src
        mo, to, ms, ts = m.opt, t.opt, m.stat, t.stat  # (one view each: every ``m.opt`` builds a new one)
        for name in _OPTION_FIELDS:
            setattr(mo, name, getattr(to, name))
        for name in ("center", "extent", "meaninertia", "meanmass", "meansize"):
            setattr(ms, name, getattr(ts, name))


_OPTION_FIELDS = tuple(k for k in dir(mujoco.MjOption) if not k.startswith("_"))

#: Bytes between two arrays of a copy run (:func:`_copy_runs`) that may be taken along: MuJoCo pads each array
#: of the model's buffer to its alignment (at most 64 bytes); a wider gap ends the run.
_PAD = 64


def _copy_runs(m: mujoco.MjModel, template: mujoco.MjModel, names) -> list | None:
    """The arrays ``names`` of ``m`` as a few ``(dst address, src address, bytes)`` runs of its buffer, copied
    from ``template`` (``copy.copy(m)``: the same layout in its own buffer), or None where the layout is not
    that (the per-array copy then runs).

    MuJoCo keeps every array of a model in one buffer, in a fixed order, each padded to its alignment; the
    arrays :meth:`_Entry.restore` copies (:func:`_array_fields`) lie there as a few long stretches, broken by
    the tree's sparse layout, which it leaves.  A run joins arrays in address order while the next starts
    less than :data:`_PAD` bytes after the last one ends and no other array of the model (one not to copy,
    non-empty) lies in between; every array must sit at the same offset from the run's start in both models.
    The bytes copied besides the arrays are padding, or arrays the bindings do not show (the names), both
    equal in the template: after :meth:`_Entry.snapshot` only Python writes and ``mj_setConst`` (which
    snapshots again) change a model, and neither writes those.  So the model's bytes after the runs are
    those after the per-array copy (``tests/test_scene_reuse.py`` compares every array with a fresh build's).
    """
    want = set(names)
    rows = []
    for k in _MODEL_ARRAYS or ():
        a = getattr(m, k)
        if not a.size:
            continue
        if k in want:
            b = getattr(template, k)
            if b.nbytes != a.nbytes or not (a.flags.c_contiguous and b.flags.c_contiguous):
                return None
            rows.append((a.ctypes.data, a.nbytes, b.ctypes.data))
        else:
            rows.append((a.ctypes.data, a.nbytes, None))
    if len([r for r in rows if r[2] is not None]) != len(want):
        return None
    rows.sort()
    runs, cur = [], None  # cur: [dst start, dst end, src start]
    for dst, size, src in rows:
        if src is None:  # not to be copied: ends the run
            if cur is not None:
                runs.append(cur)
                cur = None
            continue
        if cur is not None and 0 <= dst - cur[1] < _PAD and src - cur[2] == dst - cur[0]:
            cur[1] = dst + size
        else:
            if cur is not None:
                if dst < cur[1]:  # overlapping arrays: not a layout this knows
                    return None
                runs.append(cur)
            cur = [dst, dst + size, src]
    if cur is not None:
        runs.append(cur)
    return [(a, c, b - a) for a, b, c in runs]


_MODEL_ARRAYS: tuple | None = None  # the names of MjModel's array fields (the same for every model)


#: The sparse-matrix layout of the joint-space inertia and its factors (``M_*``, ``D_*``, ``B_*`` row addresses,
#: counts and column indices, the ``map*`` permutations): integer arrays the compiler derives from the kinematic
#: tree alone, which is part of a cache entry's key; nothing else writes them (MuJoCo reads them in every
#: step).  :meth:`_Entry.restore` does not copy them back: at 256 links they are 1.26 of the model's 1.47 MB
#: of arrays.  ``tests/test_scene_reuse.py`` compares every array of a used model with a fresh build's.
_TREE_LAYOUT_SUFFIXES = ("_colind", "_rowadr", "_rownnz")


def _tree_layout(name: str, v: np.ndarray) -> bool:
    return v.dtype.kind == "i" and (name.startswith(("M_", "D_", "B_")) and name.endswith(_TREE_LAYOUT_SUFFIXES)
                                    or name in ("mapM2D", "mapD2M", "mapM2M"))


def _array_fields(m: mujoco.MjModel) -> list:
    """Names of the model's writable, non-empty array fields but the tree's sparse layout (:func:`_tree_layout`)."""
    global _MODEL_ARRAYS
    if _MODEL_ARRAYS is None:
        names = []
        for k in dir(m):
            if k.startswith("_"):
                continue
            try:
                v = getattr(m, k)
            except Exception:  # pragma: no cover - a property MuJoCo refuses to read
                continue
            if isinstance(v, np.ndarray):
                names.append(k)
        _MODEL_ARRAYS = tuple(names)
    out = []
    for k in _MODEL_ARRAYS:
        v = getattr(m, k)
        if v.size and v.flags.writeable and not _tree_layout(k, v):
            out.append(k)
    return out


def _cache() -> OrderedDict:
    c = getattr(_local, "cache", None)
    if c is None:
        c = _local.cache = OrderedDict()
        _local.hits = _local.misses = 0
    return c


def clear() -> None:
    """Empty the calling thread's cache."""
    _cache().clear()
    _local.hits = _local.misses = 0


def cache_info() -> dict:
    """``{"size", "max_size", "hits", "misses"}`` of the calling thread's cache."""
    c = _cache()
    return {"size": len(c), "max_size": CACHE_SIZE, "hits": _local.hits, "misses": _local.misses}


def _lookup(key):
    c = _cache()
    e = c.get(key)
    if e is not None:
        c.move_to_end(key)
        _local.hits += 1
    else:
        _local.misses += 1
    return e


def _store(key, entry) -> None:
    c = _cache()
    c[key] = entry
    c.move_to_end(key)
    while len(c) > CACHE_SIZE:
        c.popitem(last=False)


def _cached_or_built(key, const_inputs, build):
    """``(entry, None)`` for a structure cached before; else ``(None, build())``, the new scene stored when
    ``key`` is cacheable (its last item, the structure, is not None)."""
    entry = _lookup(key) if key[-1] is not None else None
    if entry is not None:
        return entry, None
    sc = build()
    if key[-1] is not None:
        _store(key, _Entry(sc, const_inputs))
    return None, sc


@contextlib.contextmanager
def _refilled(key, entry, finger_springs, phys, r_link: float):
    """Set a cached entry's scene in place, the part every scene kind shares: the model restored, the links'
    springs, masses and inertias and gravity written; yields the scene for the rest.  An interruption (an error,
    Ctrl-C, a deadline) drops the half-set entry from the cache."""
    try:
        entry.restore()
        sc = entry.scene
        L = phys.length
        _set_links(sc.model, sc.index, finger_springs, phys.EI, phys.rho, L, r_link * L)
        sc.model.opt.gravity = [0.0, 0.0, -phys.g]
        yield sc
    except BaseException:
        _cache().pop(key, None)
        raise


def _freeze(v):
    """A hashable, bit-exact stand-in for a keyword's value (``-0.0`` and ``0.0`` differ)."""
    if isinstance(v, bool) or v is None or isinstance(v, (int, str)):
        return v
    if isinstance(v, float):
        return ("f", v.hex())
    if isinstance(v, np.ndarray) or isinstance(v, (list, tuple)):
        a = np.asarray(v, dtype=float)
        return ("a", a.shape, a.tobytes())
    return ("r", type(v).__name__, repr(v))


#: The builders' keywords whose every value this module sets in place bit-identically (tested in
#: ``tests/test_scene_reuse.py``).  A keyword outside these (one a builder gains later: a contact mode...)
#: enters the key like the others, but while it differs from its default the scene is built fresh every
#: time: a structure the test has not compared is never handed out.  Add it here with a test case.
VERIFIED_KEYWORDS = frozenset({
    "grip", "params", "profile", "n_links", "initial_angles",  # the values set in place
    "fingers", "free_workpiece", "render", "r_tip", "r_link", "r_corner", "contact_window",  # planar structure
    "workpiece", "yaw", "contact_angle", "offset", "workpiece_yaw",  # K-finger structure
})


@functools.lru_cache(maxsize=16)
def _signature(fn) -> inspect.Signature:
    """``inspect.signature(fn)``, computed once per builder (~0.1 ms a call saved per scene; a documented
    bounded cache: its keys are the few builder functions, 16 at most, least recently used dropped)."""
    return inspect.signature(fn)


@functools.lru_cache(maxsize=16)
def _plain_layout(fn) -> tuple | None:
    """``(positional names, {keyword-only name: default})`` of a signature made of positional-or-keyword
    parameters without defaults, then keyword-only ones with defaults (every builder's); None for any other
    (bound by :mod:`inspect`).  Same bounded cache as :func:`_signature`."""
    pos, kwd = [], {}
    for p in _signature(fn).parameters.values():
        if p.kind is p.POSITIONAL_OR_KEYWORD and p.default is p.empty and not kwd:
            pos.append(p.name)
        elif p.kind is p.KEYWORD_ONLY and p.default is not p.empty:
            kwd[p.name] = p.default
        else:
            return None
    return tuple(pos), kwd


def _arguments(fn, args: tuple, kw: dict) -> dict:
    """``fn``'s arguments for ``fn(*args, **kw)``, defaults applied, in its signature's order: what
    ``inspect.Signature.bind`` and ``apply_defaults`` give (and raise), at a tenth of their cost where the
    call fits :func:`_plain_layout` (every positional given, only known keywords)."""
    lay = _plain_layout(fn)
    if lay is not None and len(args) == len(lay[0]) and all(k in lay[1] for k in kw):
        out = dict(zip(lay[0], args))
        for k, d in lay[1].items():
            out[k] = kw[k] if k in kw else d
        return out
    bound = _signature(fn).bind(*args, **kw)
    bound.apply_defaults()
    return dict(bound.arguments)


def _structure(builder, args: tuple, kw: dict, skip: tuple, arguments: dict | None = None) -> tuple | None:
    """The keywords of ``builder`` (defaults applied) but the parameter-valued ones, frozen; None when one
    outside :data:`VERIFIED_KEYWORDS` is not at its default (built fresh, never cached).  ``arguments``:
    :func:`_arguments` of the call, when the caller has them already."""
    sig = _signature(builder)
    if arguments is None:
        arguments = _arguments(builder, args, kw)
    for k, v in arguments.items():
        if k not in VERIFIED_KEYWORDS:
            d = sig.parameters[k].default
            if d is inspect.Parameter.empty or _freeze(v) != _freeze(d):
                return None
    return tuple((k, _freeze(v)) for k, v in arguments.items() if k not in skip)


def _set_links(m, index, springs_list, EI: float, rho: float, length: float, r_link: float) -> None:
    """Hinge stiffness and rest angles of every finger; the links' masses and inertias (as ``add_fingers``)."""
    n = index.n
    ds = length / n
    mass = rho * ds
    inertia_perp = mass * (ds**2 / 12.0 + r_link**2 / 4.0)
    inertia_axis = 0.5 * mass * r_link**2
    jnt = m.dof_jntid[index.joint_dof]
    for f, springs in enumerate(springs_list):
        m.jnt_stiffness[jnt[f]] = (EI / length) * springs.stiffness
        m.qpos_spring[index.joint_qpos[f]] = springs.rest
    m.body_mass[index.link_body] = mass
    m.body_inertia[index.link_body] = [inertia_axis, inertia_perp, inertia_perp]


def _dist(a, b) -> np.ndarray:
    """Row-wise distance of points ``a`` and ``b`` as ``mju_dist3`` sums it."""
    dx = a - b
    return np.sqrt(dx[..., 0] * dx[..., 0] + dx[..., 1] * dx[..., 1] + dx[..., 2] * dx[..., 2])


def _set_stat(m: mujoco.MjModel, d: mujoco.MjData, keep_frame: bool) -> None:
    """The compiler's statistics (``stat``, ``dof_length``) at ``qpos0``, summed in the compiler's order.

    ``mj_setConst`` leaves them; the compiler computes them from the bounding box of the bodies, joint anchors,
    sites and geoms, the bodies' sizes, the masses and the diagonal of the joint-space inertia.
    ``keep_frame``: ``center`` and ``extent`` were given in the spec (the rendering dressing), keep them.
    """
    d.qpos[:] = m.qpos0
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_crb(m, d)
    nb = m.nbody
    if np.any(m.geom_type == mujoco.mjtGeom.mjGEOM_HFIELD):  # pragma: no cover - no scene has one
        raise ValueError("scene reuse: a height field's bound needs the compiler")
    s0, s1 = m.geom_size[:, 0], m.geom_size[:, 1]
    plane = np.where((s0 != 0) | (s1 != 0), np.maximum(s0, s1) * 0.1, 0.01)
    r = np.where(m.geom_rbound > 0, m.geom_rbound, np.where(m.geom_type == mujoco.mjtGeom.mjGEOM_PLANE, plane, 0.0))
    lo = [d.xpos[1:], d.xipos[1:], d.xanchor, d.site_xpos, d.geom_xpos - r[:, None]]
    hi = [d.xpos[1:], d.xipos[1:], d.xanchor, d.site_xpos, d.geom_xpos + r[:, None]]
    xmin = np.minimum(np.min(np.vstack(lo), axis=0), 1e10)
    xmax = np.maximum(np.max(np.vstack(hi), axis=0), -1e10)
    extent = float(m.stat.extent)
    if not keep_frame:
        m.stat.center = (xmin + xmax) * 0.5
        if xmax[0] > xmin[0]:
            extent = max(1e-5, max(xmax[0] - xmin[0], max(xmax[1] - xmin[1], xmax[2] - xmin[2])))
    body = np.zeros(nb)
    jb = m.jnt_bodyid
    dj = _dist(d.xipos[jb], d.xanchor)
    np.maximum.at(body, jb, dj)
    pb = m.body_parentid[jb]
    np.maximum.at(body, pb, _dist(d.xipos[pb], d.xanchor))
    body[0] = 0.0
    gb = m.geom_bodyid
    has = (m.geom_rbound > 0) & (gb > 0)
    np.maximum.at(body, gb[has], m.geom_rbound[has] + _dist(d.xipos[gb[has]], d.geom_xpos[has]))
    if nb > 1:
        body[1:] = np.maximum(body[1:], 1e-5)
        m.stat.meansize = float(np.cumsum(body[1:] / (nb - 1))[-1])
        m.stat.meanmass = float(np.cumsum(m.body_mass[1:])[-1]) / (nb - 1)
    rot = np.isin(m.jnt_type[m.dof_jntid], (mujoco.mjtJoint.mjJNT_BALL, mujoco.mjtJoint.mjJNT_HINGE)) | (
        (m.jnt_type[m.dof_jntid] == mujoco.mjtJoint.mjJNT_FREE) & (np.arange(m.nv) - m.jnt_dofadr[m.dof_jntid] >= 3))
    m.dof_length[:] = np.where(rot, body[m.dof_bodyid], 1.0)
    if not keep_frame:
        m.stat.extent = max(extent, 2 * m.stat.meansize)
    if m.nv:
        m.stat.meaninertia = float(np.cumsum(d.M[m.M_rowadr + m.M_rownnz - 1])[-1]) / m.nv


def _set_body_pos(m, body: int, pos) -> None:
    """A body's position; a free joint's ``qpos0`` and ``qpos_spring`` start where the body is (the compiler's)."""
    m.body_pos[body] = pos
    for j in range(int(m.body_jntadr[body]), int(m.body_jntadr[body]) + int(m.body_jntnum[body])):
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            a = int(m.jnt_qposadr[j])
            for q in (m.qpos0, m.qpos_spring):
                q[a:a + 3] = m.body_pos[body]
                q[a + 3:a + 7] = m.body_quat[body]


def _finish(entry, const_inputs, start) -> None:
    """``mj_setConst`` if its inputs changed (then the new model is the one to restore), reset, start angles."""
    sc = entry.scene
    m, d = sc.model, sc.data
    if const_inputs != entry.const_inputs:
        mujoco.mj_setConst(m, d)
        # the rendering dressing gives center and extent in the spec: the compiler keeps those
        _set_stat(m, d, keep_frame=bool(getattr(sc, "render", False)))
        entry.snapshot()
        entry.const_inputs = const_inputs
    sc.spec = None  # the spec describes the parameters of the first build, no longer the model's
    mujoco.mj_resetData(m, d)
    start(sc)


# ---------------------------------------------------------------------------
# planar scenes


def scene(grip: str, params, profile, n_links: int, *, forward: bool = True, **kw):
    """:func:`simgrip.sim.scene.build_scene` through the cache (same arguments, same checks, same result).

    A scene of a structure seen before (see the module docstring) is the cached one with ``params``,
    ``profile`` and ``initial_angles`` set in place: bit-identical to a fresh build, at a fraction of its
    cost.  The scene returned is owned by the cache (valid until the next call for its structure in this
    thread).  ``forward=False``: a cached scene's start angles are set without ``mj_forward`` (0.6 ms at
    256 links), for a caller that settles at once: every settle path computes what it reads from the
    state it sets, so the settled state is bit-identical to a fresh build's
    (``tests/test_scene_reuse.py``); the scene's data before that is not a fresh build's.
    """
    from simgrip.sim import scene as S
    from simgrip.sim.fingers import check_finger_links
    from simgrip.sim.workpiece import inertial_mass, workpiece_inertia

    grip = check_grip(grip)
    dimless, phys = S.check_params(params)
    prof = as_profile(profile)
    n = check_finger_links(n_links)
    a = _arguments(S.build_scene, (grip, params, profile, n_links), kw)
    fingers = a["fingers"]
    if fingers not in (1, 2) or isinstance(fingers, bool):  # the builder's message
        return S.build_scene(grip, params, profile, n_links, **kw)
    r_tip = S.check_positive("r_tip", a["r_tip"], 0.05)
    r_link = S.check_positive("r_link", a["r_link"], 0.05)
    r_corner = S.check_positive("r_corner", a["r_corner"], 0.05)
    window = S.check_positive("contact_window", a["contact_window"], 1.0)
    if grip == "III":
        check_grip_iii_reach(dimless.gamma, dimless.b)
    springs = chain_springs(prof, n)
    given = a["initial_angles"]
    q0 = S._start_angles(grip, dimless, prof, n, given)
    place = S._placement(grip, q0, springs, dimless, phys, r_tip, r_link, r_corner, window, given is not None)

    key = ("scene", grip, n, phys.length.hex(), None if place is None else tuple(int(i) for i in place.links),
           _structure(S.build_scene, (grip, params, profile, n_links), kw,
                      ("grip", "params", "profile", "n_links", "initial_angles"), a))
    L = phys.length
    mass = phys.m * fingers
    imass = inertial_mass(mass, fingers, phys.rho, L) if place is not None else 0.0
    const_inputs = (phys.rho.hex(),) if place is None else (
        phys.rho.hex(), imass.hex(), place.half.tobytes(), float(place.center_z).hex())

    entry, sc = _cached_or_built(key, const_inputs, lambda: S.build_scene(grip, params, profile, n_links, **kw))
    if entry is None:
        return sc

    with _refilled(key, entry, [springs] * fingers, phys, r_link) as sc:
        m = sc.model
        if place is not None:
            wb = sc.workpiece_body
            hx, hy, hz = (float(v) for v in place.half)
            _set_body_pos(m, wb, [0.0, 0.0, float(place.center_z)])
            m.body_mass[wb] = imass
            m.body_inertia[wb] = workpiece_inertia("box", (hx, hy, hz), imass)
            m.body_gravcomp[wb] = 1.0 - mass / imass if mass < imass else 0.0
            m.geom_size[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "workpiece_box")] = [hx, hy, hz]
            if grip == "III":
                for f, g in enumerate(sc.workpiece_geoms):  # fromto (+-hx, -+hy, -hz): centre (+-hx, 0, -hz)
                    m.geom_pos[g] = [hx if f == 0 else -hx, 0.0, -hz]
            m.pair_friction[:, :2] = phys.mu_s
        sc.params, sc.physical, sc.profile, sc.springs = dimless, phys, prof, springs
        sc.box_half = place.half if place is not None else np.zeros(3)
        _finish(entry, const_inputs, lambda s: S.set_joint_angles(s, q0, forward=forward))
    return entry.scene


def build_scene(grip: str, params, profile, n_links: int, **kw):
    """:func:`simgrip.scenes.build_scene` (Grip III started from the hinge chain) through the cache."""
    if kw.get("initial_angles") is None and check_grip(grip) == "III":
        from simgrip.scenes import start_angles
        from simgrip.sim.fingers import check_finger_links
        from simgrip.params import DimensionlessParams, PhysicalParams

        if not isinstance(params, (PhysicalParams, DimensionlessParams)):
            raise ValueError(f"params must be PhysicalParams or DimensionlessParams, got {type(params).__name__}")
        kw["initial_angles"] = start_angles(grip, params, as_profile(profile), check_finger_links(n_links))
    return scene(grip, params, profile, n_links, **kw)
