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
  gripper's margin, :data:`simgrip.settle.gripper_state.FRICTION_MARGIN`),
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

import numpy as np

__all__ = ["DEPTH_FRACTION", "check_condition_23", "check_contact_depth", "check_friction_cone", "check_grip_shape",
           "check_reach", "check_tip_contact"]

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
    why (the K-finger gripper's :func:`simgrip.settle.gripper_start.warn_unreached`).
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
    at a Grip III corner) within :data:`simgrip.settle.gripper_state.FRICTION_MARGIN`
    (2 %) of ``mu_s`` or beyond: a
    sticking contact saturated in MuJoCo's contact frame (whose normal at a Grip
    III corner is the carrying link's, not the rod's at ``gamma``) holds where the
    BVP's ``|f| <= mu_s n`` may not, and MuJoCo's soft cone creeps; the settles
    and the BVP may give different verdicts there.  ``M = 0`` with ``mu_s = 0`` is the
    cone's boundary itself (``|F_f| = mu_s N = 0``), held or not: the K-finger
    gripper's message (:func:`simgrip.settle.gripper_state.warn_friction_boundary`).
    """
    from simgrip.settle.gripper_state import FRICTION_MARGIN  # one margin for every settle (lazy: no cycle)

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
