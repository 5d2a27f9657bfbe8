"""Conditions a settled state must meet that the solve itself does not enforce.

Each check takes the scene and a :class:`simgrip.settle.SettledState` and
records what it finds on the state (a flag and a message in ``warnings``):

* :func:`check_condition_23` -- Grip III: the rod beyond the contact stays below
  the workpiece (the paper's condition (23); MuJoCo has no contact pair there).
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_condition_23"]


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
