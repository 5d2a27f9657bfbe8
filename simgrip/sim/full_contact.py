"""``contact="full"``: every link of every finger may touch the workpiece, itself and the other fingers.

The default scenes collide only through explicit ``<pair>`` elements
(:mod:`simgrip.sim.contacts`): the tip sphere with the box face (I, II), a few
links with the corner (III).  A full-contact scene instead lets MuJoCo's
broad phase find the contacts, filtered by ``contype``/``conaffinity`` bits:

==========================  ==========  ===============  ==========================================
geoms                       contype     conaffinity      collide with
==========================  ==========  ===============  ==========================================
finger links and tips       ``FINGER``  ``FINGER|WORK``  the workpiece, every finger (itself too)
workpiece (box, cylinder,   ``WORK``    ``FINGER``       the fingers only
sphere, corners)
everything else (palm,      unchanged   unchanged        nothing of the above (bit 0 is not used)
floor of the dressing)
==========================  ==========  ===============  ==========================================

MuJoCo drops a pair whose bodies are parent and child (``filterparent``), so
the hinge's two links never collide; it also drops two geoms of one body (a
link's capsule and the tip sphere).  Links two apart (``i`` and ``i + 2``) stay
candidates: they cannot touch while both hinges between them turn by less than
``pi / 2`` and ``ds > r_i + r_{i+2}`` (:func:`next_but_one_separated` derives
it), but no hinge angle is bounded a priori (a coarse chain at large curvature
folds by more), so excluding them would be a guess; their cost is one
bounding-box test each (:func:`candidate_pairs` counts what remains).

Each colliding geom carries the grip's friction ``mu_s`` (MuJoCo takes the
larger of two geoms' frictions: rod on rod and rod on workpiece both use
``mu_s``), ``condim = 3`` and the scenes' stiff contact softness
(:data:`~simgrip.sim.contacts.SCENE_SOLREF`); the settle rewrites the softness
from its own time step (:mod:`simgrip.settle.full_contact`).

Workpiece geometry in the planar Grips I/II (:func:`full_box_centre`): a real
box of width ``b`` (faces at ``x = +-(b/2 - r_tip)``, so a touching tip sphere
has its centre at ``X = b/2`` as in the point-contact scene), depth
:data:`~simgrip.sim.workpiece.BOX_DEPTH` and height
:data:`~simgrip.sim.workpiece.BOX_HEIGHT`, whose face nearest the palm lies
``box_gap`` below it (Grip I; above it for Grip II).  The point-contact scene's
box is centred on the tip and reaches through the palm: only its side face is
ever touched there, which a real box cannot allow once every link collides.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.sim.contacts import SCENE_SOLIMP, SCENE_SOLREF

__all__ = [
    "CONTACT_MODES",
    "DEFAULT_BOX_GAP",
    "FINGER_BIT",
    "WORKPIECE_BIT",
    "candidate_pairs",
    "check_contact_mode",
    "check_grasp",
    "colliding_geoms",
    "enable_full_contact",
    "full_box_centre",
    "grasp_depth",
    "next_but_one_separated",
]

#: Contact modes a scene is built in: ``"pairs"`` (explicit pairs, the default of the point and surface
#: settles) or ``"full"`` (every link may touch).
CONTACT_MODES = ("pairs", "full")
#: contype/conaffinity bit of the finger geoms (bit 0, MuJoCo's default, is left to the dressing).
FINGER_BIT = 1 << 1
#: contype/conaffinity bit of the workpiece geoms.
WORKPIECE_BIT = 1 << 2
#: Grips I/II with full contact: gap over ``l`` between the palm plane (the fingers' roots, ``z = 0``) and the
#: box's near face.  The standard case's point-contact shapes (D = 1, M = 5, b = 0.6) dip at most 0.11 l below
#: the palm while ``X < b/2`` over their valid range (kappa in [-8, -2]; measured at n = 32), and their tips lie
#: at 0.2 l (kappa = -10) to 0.73 l below it: a gap of 0.15 l clears the first and keeps the tip on the side
#: face.
DEFAULT_BOX_GAP = 0.15


def check_contact_mode(contact) -> str:
    """The scene's contact mode: ``None``, ``"point"``, ``"surface"`` or ``"pairs"`` give ``"pairs"``; ``"full"``
    gives ``"full"``; ValueError naming ``contact`` otherwise."""
    if contact is None or contact in ("point", "surface", "pairs"):
        return "pairs"
    if contact == "full":
        return "full"
    raise ValueError(f"contact must be 'point', 'surface' or 'full', got {contact!r}")


def check_grasp(grip: str, mode: str, box_depth, extra_friction) -> tuple[float | None, bool]:
    """The full-contact grasp protocol of Grips I/II, validated: ``(box_depth, extra_friction)``.

    ``box_depth`` (over ``l``, in ``(0, 1]``) or None.  Given, the box is *grasped at that depth*: the tip's
    centre ``box_depth`` below the box's top edge (Grip II: above its bottom edge), measured in the centreline
    convention of :mod:`simgrip.reference.constrained` (the edge where a link's centreline touches the face:
    the top face plus ``r_link``, as the side face plus ``r_tip`` is the tip's ``X = b/2``).  The settle
    (:mod:`simgrip.settle.full_contact`) closes the finger frictionless over the box, then moves the held box
    until ``top - Y_tip = box_depth`` (a hand pushing the object into its grip), then releases it with friction:
    a sticking tip keeps the depth while the box hangs on it.  None: the box stays where ``box_gap`` put it.

    ``extra_friction``: whether contacts other than the tip's on the workpiece (and self contacts) carry the
    friction ``mu_s``.  With friction at several contacts the static problem is indeterminate: the box's
    weight may be shared by the friction of any of them in any proportion the sticking history left (the
    contact forces are not fixed by the balance), so N depends on the path and on the step (measured, Grip I
    kappa -10 with the box ``box_gap`` below the palm: N = 39.8, 43.0, 45.2, 43.9 at n = 16 ... 128).
    Frictionless extra contacts make it determinate: the theory's model (the free-boundary elastica of
    :mod:`simgrip.reference.free_boundary`), where the tip's friction alone carries the box.  Default
    (None): False when ``box_depth`` is given (the comparison with the theory), True otherwise (every contact
    real).  ValueError naming the parameter otherwise (both need ``contact="full"`` and Grip I or II).
    """
    if box_depth is not None:
        if mode != "full" or grip not in ("I", "II"):
            raise ValueError("box_depth: only a full-contact Grip I/II scene (contact='full') is grasped at a depth")
        try:
            v = float(box_depth)
        except (TypeError, ValueError):
            raise ValueError(f"box_depth must be a real number, got {box_depth!r}") from None
        if isinstance(box_depth, bool) or not (math.isfinite(v) and 0.0 < v <= 1.0):
            raise ValueError(f"box_depth must lie in (0, 1] (over l), got {box_depth!r}")
        box_depth = v
    if extra_friction is None:
        return box_depth, box_depth is None
    if not isinstance(extra_friction, (bool, np.bool_)):
        raise ValueError(f"extra_friction must be True or False, got {extra_friction!r}")
    if mode != "full" and not extra_friction:
        raise ValueError("extra_friction: only a full-contact scene (contact='full') has contacts besides the tip's")
    return box_depth, bool(extra_friction)


def enable_full_contact(spec: mujoco.MjSpec, finger_geoms, workpiece_geoms, mu: float, root_bodies=()) -> None:
    """Make the named geoms of ``spec`` collide through the broad phase (see the module docstring).

    ``finger_geoms``, ``workpiece_geoms``: geom names; ``mu``: sliding friction ``mu_s`` (both tangents);
    ``root_bodies``: the first link's body of every finger.  Every finger is clamped at the same point (the palm
    centre), so the first links of two fingers overlap by construction there: each pair of them is excluded
    (MuJoCo's ``<exclude>``); a first link and another finger's second link are ``ds sin(angle between the
    fingers)`` apart at the clamp and stay candidates.
    """
    roots = list(root_bodies)
    for i, a in enumerate(roots):
        for b in roots[i + 1:]:
            spec.add_exclude(bodyname1=a, bodyname2=b)
    for names, ctype, caff in ((finger_geoms, FINGER_BIT, FINGER_BIT | WORKPIECE_BIT),
                               (workpiece_geoms, WORKPIECE_BIT, FINGER_BIT)):
        for name in names:
            g = spec.geom(name)
            if g is None:
                raise ValueError(f"spec has no geom named {name!r}")
            g.contype, g.conaffinity = ctype, caff
            g.condim = 3
            g.friction = [float(mu), 0.0, 0.0]
            g.solref = list(SCENE_SOLREF)
            g.solimp = list(SCENE_SOLIMP)
            g.margin = 0.0
            g.gap = 0.0


def colliding_geoms(model: mujoco.MjModel) -> np.ndarray:
    """Ids of the geoms that take part in full contact (finger or workpiece bit set)."""
    bits = FINGER_BIT | WORKPIECE_BIT
    return np.flatnonzero((model.geom_contype & bits) | (model.geom_conaffinity & bits))


def candidate_pairs(model: mujoco.MjModel, finger_of_geom) -> dict:
    """The geom pairs MuJoCo's broad phase may test in a full-contact model, counted by kind.

    A pair is a candidate when the bits match (``contype1 & conaffinity2 || contype2 & conaffinity1``), the
    geoms are on different bodies, the bodies are not parent and child and not excluded (MuJoCo's filters).
    ``finger_of_geom``: the finger of each geom, -1 for others (:class:`~simgrip.sim.fingers.FingerIndex`).
    Returns ``{"total", "finger_workpiece", "self", "finger_finger", "all_pairs"}`` (``all_pairs``: ``g (g-1) / 2``
    of the ``g`` colliding geoms).  ``O(g^2)`` in Python: a report, not part of any settle.
    """
    ids = colliding_geoms(model)
    body, parent = model.geom_bodyid, model.body_parentid
    owner = np.asarray(finger_of_geom)
    excluded = {int(x) for x in model.exclude_signature}
    out = {"finger_workpiece": 0, "self": 0, "finger_finger": 0}
    for k, a in enumerate(ids):
        for b in ids[k + 1:]:
            if not ((model.geom_contype[a] & model.geom_conaffinity[b]) or
                    (model.geom_contype[b] & model.geom_conaffinity[a])):
                continue
            ba, bb = body[a], body[b]
            if ba == bb or parent[ba] == bb or parent[bb] == ba:
                continue
            if ((int(ba) << 16) + int(bb)) in excluded or ((int(bb) << 16) + int(ba)) in excluded:
                continue
            fa = owner[a] if a < owner.size else -1
            fb = owner[b] if b < owner.size else -1
            if fa < 0 or fb < 0:
                out["finger_workpiece"] += 1
            elif fa == fb:
                out["self"] += 1
            else:
                out["finger_finger"] += 1
    out["total"] = sum(out.values())
    out["all_pairs"] = len(ids) * (len(ids) - 1) // 2
    return out


def next_but_one_separated(n: int, r_link: float, r_tip: float = 0.0) -> bool:
    """Whether links ``i`` and ``i + 2`` (radii over ``l``) are kept apart by geometry, given hinges below ``pi/2``.

    Derivation: let link ``i + 1`` run from ``A`` to ``B`` (``|B - A| = ds = 1/n``) with unit tangent ``t``.  Link
    ``i`` ends at ``A`` along ``u`` with ``u . t = cos q_{i+1}``, so every point of it is ``A - lambda u``
    (``lambda >= 0``) and ``(x - A) . t <= 0`` when ``|q_{i+1}| < pi/2``; likewise link ``i + 2`` (and a tip sphere's
    centre at its end) lies in ``(x - B) . t >= 0`` when ``|q_{i+2}| < pi/2``.  The two half-planes are ``ds``
    apart, so the centrelines are at least ``ds`` apart and the capsules cannot touch when ``ds > 2 max(r_link,
    r_tip)``.  No hinge angle is bounded a priori, so this is a statement about states, not a filter.
    """
    return 1.0 / n > 2.0 * max(r_link, r_tip)


def full_box_centre(grip: str, gap: float, half_z: float) -> float:
    """Height [m] of the box centre with its near face ``gap`` [m] from the palm plane: below it (Grip I, III),
    above it (Grip II)."""
    if not (math.isfinite(gap) and gap > 0.0):
        raise ValueError(f"box_gap must be positive and finite, got {gap!r}")
    return (gap + half_z) if grip == "II" else -(gap + half_z)


def grasp_depth(scene, qpos=None) -> float:
    """The grasp depth over ``l`` at ``qpos`` (default: the scene's): Grip I ``top - Y_tip``, Grip II
    ``Y_tip - bottom``, where ``top``/``bottom`` is the box's face offset by ``r_link`` outward (the centreline
    convention of :func:`~simgrip.sim.full_contact.check_grasp`) and ``Y_tip`` the first finger's tip node."""
    m, d = scene.model, scene.data
    q = d.qpos if qpos is None else qpos
    if scene.grip not in ("I", "II") or scene.workpiece_body < 0:
        raise ValueError(f"grip: a grasp depth needs Grip I or II's box, got {scene.grip!r}")
    L = scene.length
    phi = np.cumsum(q[scene.index.joint_qpos[0]])
    y_tip = float(np.sum(np.sin(phi))) * L / scene.n
    zc = float(m.body_pos[scene.workpiece_body][2])
    for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos):
        if name == "z":
            zc += float(q[qa])
    face = float(scene.box_half[2]) + scene.r_link * L
    return ((zc + face - y_tip) if scene.grip == "I" else (y_tip - (zc - face))) / L
