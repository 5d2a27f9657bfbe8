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
  the workpiece (the paper's condition (23); MuJoCo has no contact pair there).
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_condition_23", "check_grip_shape"]


def check_condition_23(scene, state) -> None:
    """Grip III condition (23): flag links beyond the contact that reach the workpiece's bottom face.

    The corner contact is only on the links near the initial contact (no pair
    elsewhere), so MuJoCo lets a curling tip pass through the workpiece; the
    theory requires the rod beyond ``gamma`` to stay below the bottom face.
    A node beyond the contact that lies under the box (``|x| < b/2``, finger
    frame) within ``r_link`` of the bottom face or above it violates (23).
    """
    if scene.grip != "III" or not state.held or state.workpiece_pose is None:
        return
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

