"""Conditions a settled state must meet that the solve itself does not enforce.

Each check takes the scene and a :class:`simgrip.settle.SettledState` and
records what it finds on the state (a flag and a message in ``warnings``):

* :func:`check_grip_shape` -- Grips I/II: the state is the grip asked for.  Both
  grips are the same equations (the tip on the face ``X(l) = b/2``, the
  workpiece's weight as tip friction); they differ by where the tip is: Grip I
  hangs the workpiece below the palm (``Y(l) < 0``), Grip II carries it above
  (``Y(l) > 0``, Fig. 2 of the paper).  A finger that curls the wrong way (e.g.
  ``kappa > 0`` in Grip I) can still press on the face and hold the workpiece,
  in the other grip's shape; such a state is not the grip asked for:
  ``held`` is set False, ``grip_matched`` False and a ``wrong grip`` message
  goes to ``warnings``.
* :func:`check_condition_23` -- Grip III: the rod beyond the contact stays below
  the workpiece (MuJoCo has no contact pair there) and the tip stays below the
  contact, ``Y(l) < Y(gamma)`` (the paper's condition (23) as the BVP applies it).
  Either violation sets ``tip_clear`` False with a message in ``warnings``.
* :func:`check_reach` -- a dropped state whose finger, unloaded, does not reach
  the workpiece: Grips I/II its tip outside the face (``X(l) > b/2``), so it
  never pressed on it; Grip III its whole rod short of the corner (``max X <
  b/2``).  The BVP, which prescribes the contact at ``X = b/2``, may still hold
  there.  A message says so (the verdicts may differ, and why).
* :func:`check_tip_contact` -- Grip III: a contact at the tip (``gamma = 1``) is
  Grip III degenerated to a tip contact, outside the Grip III BVP (``0 < gamma <
  1``); a message says so (the comparison then has no reference).
* :func:`check_friction_cone` -- every grip: a hold at the friction cone's edge
  (the required ``mu`` within ``FRICTION_MARGIN`` of ``mu_s``, or beyond; the K-finger
  gripper's margin, :data:`simgrip.gripper.state.FRICTION_MARGIN`),
  where the settles' friction models and the BVP's may answer differently.
* :func:`check_contact_depth` -- every grip: no contact is pressed deeper than
  :data:`DEPTH_FRACTION` of the finger geom's radius, and (Grips I/II) no tip's
  centre lies past the workpiece's face.  A violation sets ``contact_ok`` False
  with a message in ``warnings``: the state is not a surface contact of the rod
  (issue 16: a stiff finger's tip pressed through the face).

Why condition (23) is the paper's ``Y(l) < Y(gamma)`` and not only "no link
touches the box": a tip that curls up beyond the contact has to pass under the
box, and one that ends beyond its far edge (``X(l) < -b/2``, e.g. Grip III at
``kappa = -4, b = 0.1``: ``X(l) = -0.144``) has crossed the palm axis ``X = 0``,
where the mirror finger (the symmetric reduction's other half, in the same
plane) crosses too: the two rods pass through each other.  The paper excludes
those shapes with (23); so does the reference (``feasibility["tip_clear"]``),
and so the simulation's verdict agrees with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip import intersection as isect
from simgrip.link_pairs import (BATCH_FINGERS, BATCH_LINKS, all_finger_pairs, all_self_pairs, finger_pair_contacts,
                                finger_self_pairs)
from simgrip.validity_hinges import folded_hinges
from simgrip.intersection import self_clear, self_clear_below  # noqa: F401  (re-exported: the proof's home)

__all__ = ["DEPTH_FRACTION", "SELF_LIMIT_FACTOR", "SOLID_LIMIT_FACTOR", "Solid", "chain_violations", "check_condition_23",
           "check_contact_depth", "check_friction_cone", "check_grip_shape", "check_reach", "check_tip_contact",
           "check_valid", "mark_invalid", "planar_solid", "self_clear", "self_clear_below", "self_gap_links",
           "state_violations", "VIOLATION_KINDS"]

#: A contact pressed deeper than this fraction of the finger geom's radius (``r_tip`` for Grips I/II,
#: ``r_link`` for III) is not a surface contact of the rod: half its cross-section is inside the
#: workpiece and the reading of the contact on the centreline is off by more than half a radius
#: (``1e-3 l`` by default, three times the ``n = 32`` chain's tip error vs the BVP).  The static settle
#: keeps contacts ``<= 1e-5 l`` deep (:data:`simgrip.settle.newton.PEN_STIFFEN`); the dynamics
#: ``~1e-5 l`` at the standard case.
DEPTH_FRACTION = 0.5


def check_condition_23(scene, state) -> None:
    """Grip III condition (23): the tip below the contact, and no link beyond the contact in the workpiece.

    ``Y(l) < Y(gamma)`` for every finger (the paper's (23), as the reference's
    ``feasibility["tip_clear"]``; see the module docstring), and:

    The corner contact is only on the links near the initial contact (no pair
    elsewhere), so MuJoCo lets a curling tip pass through the workpiece; the
    theory requires the rod beyond ``gamma`` to stay below the bottom face.
    A node beyond the contact that lies under the box (``|x| < b/2``, finger
    frame) within ``r_link`` of the bottom face or above it violates (23).
    """
    if scene.grip != "III" or not state.held or state.workpiece_pose is None:
        return
    for f, c in enumerate(state.contacts):
        tip_y, at_y = float(state.tip[f][1]), float(c.point[1])
        if not tip_y < at_y:
            state.tip_clear = False
            state.warnings.append(
                f"finger {f}: condition (23) violated: the tip (Y(l) = {tip_y:.4g} l, X(l) = {float(state.tip[f][0]):.4g} l) "
                f"is not below the contact (Y(gamma) = {at_y:.4g} l at gamma = {c.gamma:.4f}); the paper's Grip III "
                f"assumes it is" + (" (this tip has crossed the palm axis X = 0, where the mirror finger's rod is)"
                                    if float(state.tip[f][0]) < 0.0 else "")
            )
    L = scene.length
    bottom = state.workpiece_pose[1] - scene.box_half[2] / L
    half = scene.box_half[0] / L
    for f, c in enumerate(state.contacts):
        nodes = state.nodes[f]
        s = np.arange(scene.n + 1) / scene.n
        beyond = nodes[s > c.gamma + 1e-12]
        x = beyond[:, 0] - state.workpiece_pose[0] * scene.mirror[f]
        bad = (np.abs(x) < half) & (beyond[:, 1] + scene.r_link >= bottom)
        if np.any(bad):
            state.tip_clear = False
            state.warnings.append(
                f"finger {f}: the rod beyond the contact (s > {c.gamma:.4f}) reaches the workpiece's bottom face "
                f"(condition (23) violated: the tip passes through the box, no contact pair there)"
            )


def check_grip_shape(scene, state) -> None:
    """Grips I/II: a held state with the tip on the other grip's side of the palm is not held.

    Grip I needs ``Y(l) < 0`` (tip below the palm), Grip II ``Y(l) > 0``, for
    every finger (in its own frame).  See the module docstring.
    """
    if scene.grip not in ("I", "II") or not state.held:
        return
    want = -1.0 if scene.grip == "I" else 1.0
    for f in range(state.fingers):
        y = float(state.tip[f][1])
        if not y * want > 0.0:
            other = "II" if scene.grip == "I" else "I"
            side = "above" if y > 0 else "below"
            state.held = False
            state.grip_matched = False
            state.warnings.append(
                f"wrong grip: finger {f} settled in Grip {other}'s shape (tip {side} the palm, Y(l) = {y:.4g} l) "
                f"while Grip {scene.grip} was asked for; the state is reported as not held"
            )
            return



def check_contact_depth(scene, state) -> None:
    """Flag a held state whose contact is deeper than :data:`DEPTH_FRACTION` of its radius or whose tip passed the face.

    Depth: each finger's ``contact.penetration`` (over ``l``) against
    ``DEPTH_FRACTION * r`` with ``r`` the radius of the finger's contact geom
    (``r_tip`` for Grips I/II, ``r_link`` for III).  Grips I/II also check the
    geometry itself: the tip's centre must stay outside the workpiece's face
    (``X(l) >= x_c + half``, ``x_c`` the workpiece's centre in the finger's frame),
    whether or not MuJoCo reports the contact.  A violation sets ``contact_ok``
    False and puts a message naming it in ``warnings``; ``held`` is left as the
    solve found it (the comparison with the reference reports the state not feasible).
    """
    if not state.held or state.workpiece_pose is None:
        return
    L = scene.length
    r = float(scene.r_tip if scene.grip in ("I", "II") else scene.r_link)
    for f, c in enumerate(state.contacts):
        if c.penetration > DEPTH_FRACTION * r:
            state.contact_ok = False
            state.warnings.append(
                f"finger {f}: contact {c.penetration:.3g} l deep, more than {DEPTH_FRACTION:g} of the finger's radius "
                f"({r:.3g} l): the rod is pressed into the workpiece, not a surface contact (the verdict is not trusted)"
            )
    if scene.grip not in ("I", "II"):
        return
    half = float(scene.box_half[0]) / L
    for f in range(state.fingers):
        face = float(state.workpiece_pose[0]) * float(scene.mirror[f]) + half
        x = float(state.tip[f][0])
        if x < face:
            state.contact_ok = False
            state.warnings.append(
                f"finger {f}: the tip passed the workpiece's face (tip centre X(l) = {x:.4g} l, face at {face:.4g} l): "
                f"the state is not a grip (the verdict is not trusted)"
            )



def check_reach(scene, state) -> None:
    """A dropped state whose unloaded finger does not reach the workpiece says so.

    Grip III: the rod's largest ``X`` (its nodes) short of the corner at ``b/2``:
    the BVP's held state has the rod pressed out to the corner (e.g. ``kappa =
    -10, D = 1e4``: a curl of radius 0.1 l, ``n = 5e5``), which the settle, let
    go there, does not keep.  Grips I/II:

    A dropped state's finger is at its unloaded equilibrium (the workpiece gone):
    if that tip lies outside the face (``X(l) > b/2``, the finger's frame), closing
    from it the finger never presses on the workpiece, so nothing holds it.  The
    elastica BVP prescribes the tip on the face (``X(l) = b/2``) and can still
    find a held equilibrium there (the finger pulled onto the face), which the
    simulation cannot close into: the verdicts may differ, and the message says
    why (the K-finger gripper's :func:`simgrip.gripper.start.warn_unreached`).
    """
    if state.held or not state.grip_matched or not scene.has_workpiece:
        return
    face = 0.5 * float(scene.params.b)
    if scene.grip == "III":
        reach = float(np.max(np.asarray(state.nodes[0], dtype=float)[:, 0]))
        if reach < face:
            state.warnings.append(
                f"not held: the unloaded finger reaches at most X = {reach:.4g} l, short of the workpiece's corner at "
                f"X = {face:.4g} l; the BVP, which puts the contact at X(gamma) = b/2, may find a held equilibrium "
                f"with the rod pressed out to the corner that this finger, let go there, does not keep")
        return
    if scene.grip not in ("I", "II"):
        return
    tip_x = float(state.tip[0][0])
    if tip_x > face:
        state.warnings.append(
            f"not held: the unloaded finger's tip is at X = {tip_x:.4g} l, outside the workpiece's face at "
            f"X = {face:.4g} l, so closing from it the finger never presses on the workpiece; the BVP, which puts "
            f"the tip on the face, may find a held equilibrium there that this finger cannot close into")


def check_tip_contact(scene, state) -> None:
    """Grip III: a held state whose contact is at the tip (``gamma = 1``) says so.

    The corner then rests on the finger's tip: Grip III degenerated to a tip
    contact, which the Grip III BVP (the contact inside the rod, ``0 < gamma <
    1``) does not describe; :func:`simgrip.compare.compare` gives no reference.
    """
    if scene.grip != "III" or not state.held:
        return
    for f, c in enumerate(state.contacts):
        if float(c.gamma) >= 1.0:
            state.warnings.append(
                f"finger {f}: the contact is at the tip (gamma = {float(c.gamma):.4g}): Grip III has degenerated to "
                f"a tip contact, which the Grip III BVP (0 < gamma < 1) does not describe; there is no reference "
                f"for this state")
            return


def check_friction_cone(scene, state) -> None:
    """A held state at the friction cone's edge says so (``state.warnings``).

    The required ``mu`` in the theory's frame (``contact.required_mu``: the rod's
    at a Grip III corner) within :data:`simgrip.gripper.state.FRICTION_MARGIN`
    (2 %) of ``mu_s`` or beyond: a
    sticking contact saturated in MuJoCo's contact frame (whose normal at a Grip
    III corner is the carrying link's, not the rod's at ``gamma``) holds where the
    BVP's ``|f| <= mu_s n`` may not, and MuJoCo's soft cone creeps; the settles
    and the BVP may give different verdicts there.  ``M = 0`` with ``mu_s = 0`` is the
    cone's boundary itself (``|F_f| = mu_s N = 0``), held or not: the K-finger
    gripper's message (:func:`simgrip.gripper.state.warn_friction_boundary`).
    """
    from simgrip.gripper.state import FRICTION_MARGIN  # one margin for every settle (lazy: no cycle)

    mu = float(scene.params.mu_s)
    if scene.has_workpiece and float(scene.params.M) == 0.0 and mu == 0.0:
        state.warnings.append("M = 0 with mu_s = 0: the workpiece needs no friction and has none (|F_f| = mu_s N = 0, "
                              "the friction cone's boundary); the hold is neutral, so the settles and the BVP "
                              "(which counts the boundary as feasible) may give different verdicts")
        return
    if not state.held or mu <= 0.0 or not state.contacts:
        return
    need = max(float(c.required_mu) for c in state.contacts)
    if need >= (1.0 - FRICTION_MARGIN) * mu:
        state.warnings.append(
            f"held at the friction cone's edge: the contact needs mu = {need:.4g} of mu_s = {mu:g} (within "
            f"{FRICTION_MARGIN:.0%} or beyond; the rod's frame"
            + (" at the corner; MuJoCo's contact frame: "
               f"{max(float(c.required_mu_contact) for c in state.contacts):.4g}" if scene.grip == "III" else "")
            + "); there the settles' friction models and the BVP's |f| <= mu_s n may give different verdicts")


# ---------------------------------------------------------------------------
# what a valid state is: no link through another, a finger or the workpiece (issue 17)

#: Two links' capsules (radius ``r_link`` each) may overlap by as much as one contact may sink
#: (:data:`DEPTH_FRACTION` of the geom's radius, the bound :func:`check_contact_depth` puts on every contact):
#: their centrelines closer than ``(2 - DEPTH_FRACTION) r_link`` are a link through another.
SELF_LIMIT_FACTOR = 2.0 - DEPTH_FRACTION
#: A link capsule (or the tip sphere) whose least signed distance to the workpiece's solid is below
#: ``(1 - DEPTH_FRACTION) r`` overlaps it by more than a contact may sink: the rod is inside the workpiece.
SOLID_LIMIT_FACTOR = 1.0 - DEPTH_FRACTION
#: What :func:`chain_violations` names: the centreline crossing itself, two links of one finger closer than
#: their capsules allow, two fingers through each other, a link or the tip inside the workpiece.  (Grip III's
#: condition (23), the paper's verdict on the shape, is :func:`check_condition_23`'s: ``tip_clear`` False,
#: not feasible, on every path; a rod that enters the box beyond the contact is also a ``workpiece`` one.)
VIOLATION_KINDS = ("self_crossing", "self_overlap", "fingers", "workpiece")


def self_gap_links(n: int, r_link: float) -> int:
    """Least index gap ``j - i`` of two links of one ``n``-link finger whose capsules are compared.

    A rod of radius ``r`` bends no tighter than a radius ``r`` (its inner fibre would vanish); on such a
    circle two cross-sections an arc ``g >= pi r`` apart are ``2 r sin(g / 2r) = 2 r`` apart at ``g = pi r``
    and stay farther than ``(2 - DEPTH_FRACTION) r`` until the rod has turned through most of a full turn
    (a real self-contact).  Closer links (arc gap between their near ends below ``pi r``) are within the
    limit whatever the shape, through the links between them, and are not compared (their crossing still
    is, :func:`simgrip.intersection.crossing_pairs`).  At least 2 (adjacent links share a node).
    """
    return max(2, 1 + int(math.ceil(math.pi * float(r_link) * int(n) - 1e-12)))


def _ranges(idx) -> str:
    idx = sorted(set(int(i) for i in idx))
    out, start = [], None
    for k, i in enumerate(idx):
        if start is None:
            start = i
        if k + 1 == len(idx) or idx[k + 1] != i + 1:
            out.append(f"{start}" if start == i else f"{start}-{i}")
            start = None
    return ", ".join(out)


@dataclass(frozen=True)
class Solid:
    """The workpiece's solid in a common frame: ``local = rot @ (p - centre)`` (lengths over ``l``).

    ``kind`` ``"box"`` (``half``: half sizes, 2 or 3), ``"cylinder"`` (3-D, about local ``z``:
    ``half = (radius, half height)``) or ``"sphere"`` (``half = (radius,)``); ``corners``: points in the
    local frame with radius ``corner_radius`` (the Grip III edge capsules, planar).
    """

    kind: str
    centre: np.ndarray
    rot: np.ndarray
    half: np.ndarray
    corners: np.ndarray | None = None
    corner_radius: float = 0.0

    def local(self, p) -> np.ndarray:
        return (np.asarray(p, dtype=float) - self.centre) @ self.rot.T

    def sdf(self, local_points) -> np.ndarray:
        """Signed distance of points given in the local frame (negative inside)."""
        if self.kind == "box":
            v = isect.box_sdf(local_points, self.half)
        elif self.kind == "cylinder":
            v = isect.cylinder_sdf(local_points, float(self.half[0]), float(self.half[1]))
        else:
            v = isect.sphere_sdf(local_points, float(self.half[0]))
        if self.corners is not None:
            for c in self.corners:
                v = np.minimum(v, np.linalg.norm(local_points - c, axis=-1) - self.corner_radius)
        return v

    def segment_sdf(self, a, b, below: float | None = None) -> np.ndarray:
        """Least signed distance along segments ``a b`` (common frame), exact for planar boxes and balls.

        ``below``: only values under it are wanted; segments whose bounding box stays farther than that
        from the solid's (axis by axis, a lower bound of the distance) get the bound, not the exact value.
        """
        la, lb = self.local(a), self.local(b)
        v = np.full(len(la), np.inf)
        todo = np.arange(len(la))
        if below is not None and self.kind != "sphere":
            ext = np.array(self.half, dtype=float)
            if self.kind == "cylinder":
                ext = np.array([ext[0], ext[0], ext[1]])
            if self.corners is not None:
                ext = ext + self.corner_radius
            lo, hi = np.minimum(la, lb), np.maximum(la, lb)
            gap = np.maximum.reduce(np.maximum(np.maximum(lo - ext, -ext - hi), 0.0), axis=1)  # <= the true distance
            v = gap.copy()
            todo = (gap < below).nonzero()[0]
            if todo.size == 0:
                return v
        la, lb = la[todo], lb[todo]
        if self.kind == "box" and la.shape[1] == 2:
            w = isect.segment_box_sdf_2d(la, lb, self.half)[0]
        elif self.kind == "sphere":
            z = np.zeros_like(la)
            w = isect.segment_distances(la, lb, z, z) - float(self.half[0])
        else:
            w = isect.segment_min_sdf(lambda q: isect.box_sdf(q, self.half) if self.kind == "box" else
                                      isect.cylinder_sdf(q, *map(float, self.half)), la, lb)[0]
        if self.corners is not None:
            for c in self.corners:
                cc = np.broadcast_to(c, la.shape)
                w = np.minimum(w, isect.segment_distances(la, lb, cc, cc) - self.corner_radius)
        v[todo] = w
        return v

    def clipped(self, lo: float | None = None, hi: float | None = None) -> "Solid | None":
        """The solid with its local vertical extent (last axis; cylinder: its axis) cut to ``[lo, hi]``; None if empty."""
        if self.kind == "sphere":
            return self
        k = len(self.half) - 1
        bottom, top = -float(self.half[k]), float(self.half[k])
        bottom = bottom if lo is None else max(bottom, float(lo))
        top = top if hi is None else min(top, float(hi))
        if not top > bottom:
            return None
        half = np.array(self.half, dtype=float)
        half[k] = 0.5 * (top - bottom)
        shift = np.zeros(self.rot.shape[0])
        shift[-1] = 0.5 * (top + bottom)
        corners = None if self.corners is None else self.corners - shift
        return Solid(self.kind, self.centre + shift @ self.rot, self.rot, half, corners, self.corner_radius)


def chain_violations(planar, world, *, r_link: float, r_tip: float | None, solid: Solid | None,
                     base_sines=None, contact_links=None, who: str = "finger", batch: bool | None = None
                     ) -> list[tuple[str, str]]:
    """Every way a set of fingers passes through itself, another or the workpiece: ``(kind, message)`` pairs.

    ``kind`` is one of :data:`VIOLATION_KINDS`; empty: a valid state.

    ``planar``: each finger's centreline in its own plane ``(n+1, 2)`` over ``l`` (the self checks);
    ``world``: the same nodes in one common frame ``(n+1, d)`` (the finger-finger and workpiece checks;
    the fingers share their base, the palm's centre); ``r_link``, ``r_tip`` (None: no tip sphere) over
    ``l``; ``solid`` the workpiece (None: none); ``base_sines[f][g]`` the sine of half the angle between
    fingers ``f`` and ``g`` at the base (1 for mirrored planar fingers).  Tolerances:
    :data:`SELF_LIMIT_FACTOR`, :data:`SOLID_LIMIT_FACTOR`, :func:`self_gap_links`.

    The geoms that carry the workpiece's contact (the tip sphere; ``contact_links[f]``, the indices of
    finger ``f``'s links with a contact pair, Grip III) are pressed into it by the contact law: how deep is
    :func:`check_contact_depth`'s verdict (``contact_ok``, deeper than :data:`DEPTH_FRACTION` of the
    radius); they are an impossible state here only once their centre (line) is inside the solid.  The
    last link's piece inside the tip sphere is the tip's (it ends at the sphere's centre).

    ``batch``: measure every pair of links of all the fingers at once (:mod:`simgrip.link_pairs`; the same answer);
    None (default) where that is the faster way (at least :data:`~simgrip.link_pairs.BATCH_FINGERS` fingers of at most
    :data:`~simgrip.link_pairs.BATCH_LINKS` links each, all alike), False never (a finger and a pair of fingers at a
    time, pruned), True wherever the fingers are alike.
    """
    out: list[tuple[str, str]] = []

    def add(kind: str, message: str) -> None:
        out.append((kind, message))

    K = len(planar)
    limit = SELF_LIMIT_FACTOR * float(r_link)
    nodes = [np.asarray(w, dtype=float) for w in world]
    n = len(nodes[0]) - 1 if K else 0
    planes = [np.asarray(p, dtype=float) for p in planar]
    selfs = batched = None  # a few short fingers: every pair of links measured at once (simgrip.link_pairs)
    if batch is None:
        batch = K >= BATCH_FINGERS and n <= BATCH_LINKS
    if (batch and n > 0 and all(p.shape == (n + 1, 2) for p in planes)
            and all(w.ndim == 2 and w.shape == nodes[0].shape for w in nodes)):
        selfs = all_self_pairs(planes, limit, self_gap_links(n, r_link))
        batched = all_finger_pairs(nodes, limit, base_sines)
    for f in range(K):
        P = planes[f]
        found = selfs[f] if selfs is not None else finger_self_pairs(P, limit, self_gap_links(len(P) - 1, r_link))
        if found is None:
            continue
        ci, cj, i, j, dist = found
        if ci.size:
            pairs = ", ".join(f"{int(i)}/{int(j)}" for i, j in list(zip(ci, cj))[:4]) + (" ..." if ci.size > 4 else "")
            add("self_crossing", f"{who} {f}: the centreline crosses itself ({ci.size} crossing(s), links {pairs}): a self-crossing "
                       f"the chain has no contact to prevent; not a physical state")
        if i.size and not ci.size:
            k = int(np.argmin(dist))
            add("self_overlap", f"{who} {f}: {i.size} pair(s) of links closer than their capsules allow (links {int(i[k])} and "
                       f"{int(j[k])}: centrelines {float(dist[k]):.3g} l apart, less than (2 - {DEPTH_FRACTION:g}) r_link = "
                       f"{limit:.3g} l): the finger passes through itself")
    for f in range(K):
        for g in range(f + 1, K):
            if batched is not None:
                i, j, dist = batched[(f, g)]
            else:
                sine = 1.0 if base_sines is None else float(base_sines[f][g])
                i, j, dist = finger_pair_contacts(nodes[f], nodes[g], limit, sine)
            if i.size:
                k = int(np.argmin(dist))
                add("fingers", f"{who}s {f} and {g} pass through each other ({i.size} pair(s) of links closer than "
                           f"{limit:.3g} l; links {int(i[k])} and {int(j[k])}: {float(dist[k]):.3g} l apart)")
    if solid is None:
        return out
    for f in range(K):
        W = np.asarray(world[f], dtype=float)
        a, b = W[:-1].copy(), W[1:].copy()
        if r_tip is not None:  # the last link up to the tip sphere's surface
            step = b[-1] - a[-1]
            h = math.sqrt(float(step.dot(step)))  # (np.linalg.norm's sqrt(x . x) of a 1-D float vector)
            b[-1] = a[-1] + step * max(0.0, 1.0 - float(r_tip) / h) if h > 0 else a[-1]
        v = solid.segment_sdf(a, b, below=SOLID_LIMIT_FACTOR * float(r_link))
        lim = np.full(len(a), SOLID_LIMIT_FACTOR * float(r_link))
        if contact_links is not None and len(contact_links[f]):
            lim[np.asarray(contact_links[f], dtype=int)] = 0.0
        bad = (v < lim).nonzero()[0]  # (np.nonzero's answer, without its wrapper)
        if bad.size:
            k = int(bad[np.argmin(v[bad])])
            add("workpiece", f"{who} {f}: link(s) {_ranges(bad)} inside the workpiece (deepest: link {k}, its centreline "
                       f"{max(0.0, -float(v[k])):.3g} l inside, its capsule {float(r_link) - float(v[k]):.3g} l deep; a "
                       f"link without contact may sink {DEPTH_FRACTION:g} r_link = {DEPTH_FRACTION * float(r_link):.3g} l, "
                       f"one carrying the contact its radius): the rod enters the workpiece")
        if r_tip is not None:
            t = float(solid.sdf(solid.local(W[-1:]))[0])
            if t < 0.0:
                add("workpiece", f"{who} {f}: the tip sphere's centre is {-t:.3g} l inside the workpiece (the sphere "
                           f"{float(r_tip) - t:.3g} l deep, more than its radius r_tip = {float(r_tip):.3g} l): the tip "
                           f"enters the workpiece")
    return out


def _rot2(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s], [-s, c]])  # world -> local for a body turned by +angle


def planar_solid(scene, state, finger: int = 0) -> Solid | None:
    """The workpiece's solid in finger ``finger``'s frame (``X`` away from the palm centre, ``Y`` up; over ``l``).

    The simulation's box is :data:`~simgrip.sim.workpiece.BOX_HEIGHT` tall only so that a tip can slide
    along it while closing; its part on the palm's side of the contact is not the workpiece's (the finger
    reaches out from the palm above it, Grip I).  The solid kept is the least one the grip implies: the box's
    column from its far end to the contact level (Grips I/II: the face carries the tip sphere at its equator,
    ``Y(l)``, the contact point's height; Grip III: a band ``2 r_link`` high above the bottom edge
    that the corner capsules round, plus those capsules).
    """
    if not scene.has_workpiece or state.workpiece_pose is None:
        return None
    L = scene.length
    mir = float(scene.mirror[finger])
    pose = np.asarray(state.workpiece_pose, dtype=float)
    centre = np.array([pose[0] * mir, pose[1]])
    angle = float(pose[2]) if pose.size > 2 else 0.0
    # MuJoCo's ry turns x toward -z; in the finger's frame (x mirrored) the turn's sign flips with the mirror
    rot = _rot2(-angle * mir)
    half = np.array([float(scene.box_half[0]), float(scene.box_half[2])]) / L
    if scene.grip in ("I", "II"):
        full = Solid("box", centre, rot, half)
        tips = full.local(np.asarray(state.tip, dtype=float).reshape(-1, 2))[:, 1]
        # the face carries the tip sphere at its equator: the contact point is at the tip centre's height,
        # so the face need reach no further (a rod that comes down over the box onto its top edge is legal)
        # (np.max's and np.min's reductions, without their wrappers)
        return (full.clipped(hi=float(np.maximum.reduce(tips))) if scene.grip == "I" else
                full.clipped(lo=float(np.minimum.reduce(tips))))
    corners = np.array([[half[0], -half[1]], [-half[0], -half[1]]])
    band = 2.0 * float(scene.r_link)
    return Solid("box", centre, rot, half, corners, float(scene.r_corner)).clipped(hi=-half[1] + band)


def state_violations(scene, state) -> list[tuple[str, str]]:
    """``(kind, message)`` of every violation of a planar settled state (:func:`check_valid`'s, recomputed).

    Pure: reads the state's nodes, pose and the solve's own verdict (``held`` as the solve left it, or an
    earlier :func:`check_valid`'s: a state it marked invalid has a contact but ``held`` False) and changes nothing.
    """
    planar = [np.asarray(state.nodes[f], dtype=float) for f in range(state.fingers)]
    world = [p * np.array([float(scene.mirror[f]), 1.0]) for f, p in enumerate(planar)]
    held = bool(state.held) or (not getattr(state, "valid", True) and bool(state.contacts))
    # a dropped workpiece is not there: only a held one is a solid the fingers may not enter
    solid = planar_solid(scene, state) if held else None  # finger 0's frame (mirror +1), ``world``'s
    r_tip = float(scene.r_tip) if scene.grip in ("I", "II") else None
    found = chain_violations(planar, world, r_link=float(scene.r_link), r_tip=r_tip, solid=solid,
                             contact_links=None if solid is None else _contact_links(scene))
    return found + folded_hinges(state.joint_angles)  # what the nodes cannot show (simgrip.validity_hinges)


def check_valid(scene, state) -> None:
    """The settled state is a physical one: no self-crossing, no link through another, a finger or the workpiece.

    Runs on every planar settle's answer (:func:`simgrip.settle._finish`, last, after
    :func:`check_condition_23`): each finger's centreline against itself, the two mirrored fingers (a
    two-finger scene) against each other and, when the workpiece is held (a dropped one is gone), every
    link capsule and the tip against its solid (:func:`planar_solid`).  A violation sets ``valid`` False, ``held`` False (an impossible state holds
    nothing) and puts ``invalid state: ...`` messages naming the links and the depth in ``warnings``;
    ``valid`` stays True otherwise.  See docs/validation.md ("What a valid state is").
    """
    mark_invalid(state, [m for _, m in state_violations(scene, state)])


def _contact_links(scene) -> list:
    """Per finger: the indices of the links whose geoms have a contact pair with the workpiece (Grip III).

    A function of the scene's contact geoms and link geoms alone: kept on the scene with the model and index
    it was read from and the contact geoms' values (read only; computed again when any of them changed)."""
    d = getattr(scene, "__dict__", None)
    model, index = getattr(scene, "model", None), getattr(scene, "index", None)
    if d is None or model is None or index is None:
        return _contact_links_fresh(scene)
    geoms = tuple(np.asarray(g).tobytes() for g in scene.contact_geoms)
    memo = d.get("_validity_contact_links")
    if memo is not None and memo[0] is model and memo[1] is index and memo[2] == geoms:
        return memo[3]
    out = _contact_links_fresh(scene)
    for a in out:
        a.setflags(write=False)
    d["_validity_contact_links"] = (model, index, geoms, out)
    return out


def _contact_links_fresh(scene) -> list:
    """:func:`_contact_links` computed from the scene (no memo)."""
    out = []
    for f in range(scene.fingers):
        pair = {int(g) for g in np.asarray(scene.contact_geoms[f]).ravel()}
        out.append(np.array([k for k, g in enumerate(np.asarray(scene.index.link_geom[f]).ravel()) if int(g) in pair],
                            dtype=np.intp))
    return out


def mark_invalid(state, found: list[str]) -> None:
    """Record ``found`` (messages; empty: valid) on ``state``: ``valid``, ``held`` False and the warnings."""
    state.valid = not found
    if found:
        state.held = False
        for m in found:  # a replicated planar state (the K-finger symmetry skip) may carry the same message
            msg = f"invalid state: {m}; reported not held, not feasible"
            if msg not in state.warnings:
                state.warnings.append(msg)
