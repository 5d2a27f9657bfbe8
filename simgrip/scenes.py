"""The paper's problems as MuJoCo scenes: the model layer's builder started where the theory starts.

:func:`simgrip.sim.scene.build_scene` runs no solver; it starts Grip III from
a plain geometric shape.  Friction holds the Grip III contact where it first
touches, so the settled state depends on the start: the problem the paper
poses (contact at ``gamma``, centreline at ``X(gamma) = b/2``) is the one that
starts from the hinge chain's own equilibrium with the contact at
``params.gamma``.  :func:`start_angles` solves for that start
(:func:`simgrip.reference.cradle_start_angles`) and :func:`build_scene` passes
it to the model layer; everything that compares a simulation with the
reference (``compare``, the harness, the figures, the tests) builds its
scenes here.
"""

from __future__ import annotations

import numpy as np

from simgrip.params import DimensionlessParams, PhysicalParams, check_grip
from simgrip.profiles import as_profile
from simgrip.sim import scene as _model
from simgrip.sim.fingers import check_finger_links

__all__ = ["build_scene", "start_angles"]


def start_angles(grip: str, params: PhysicalParams | DimensionlessParams, profile, n_links: int) -> np.ndarray | None:
    """Joint angles [rad] the theory starts ``grip`` from, or None for the model layer's default.

    Grip III: the hinge chain's equilibrium with the contact at ``params.gamma``
    (``n_links`` links).  Other grips: None (the straight finger; the Grip I/II
    settle closes the fingers itself).  Raises ``ValueError`` naming ``gamma``
    when the hinge chain has no such equilibrium.
    """
    if check_grip(grip) != "III":
        return None
    from simgrip.reference import cradle_start_angles

    dimless = params.dimensionless() if isinstance(params, PhysicalParams) else params
    return cradle_start_angles(dimless, as_profile(profile), n_links)


def build_scene(grip: str, params: PhysicalParams | DimensionlessParams, profile, n_links: int, **kw):
    """:func:`simgrip.sim.scene.build_scene` started from :func:`start_angles` unless ``initial_angles`` is given.

    ``grip`` is checked here (:func:`~simgrip.params.check_grip`) and handed down as a
    :class:`~simgrip.params.Grip`, which the layers below take as checked (as ``n_links``, a
    :class:`~simgrip.chain.Count`, for Grip III's start).
    """
    grip = check_grip(grip)
    if kw.get("initial_angles") is None and grip == "III":
        # what start_angles reads is checked first, with the model layer's messages
        if not isinstance(params, (PhysicalParams, DimensionlessParams)):
            raise ValueError(f"params must be PhysicalParams or DimensionlessParams, got {type(params).__name__}")
        profile, n_links = as_profile(profile), check_finger_links(n_links)
        kw["initial_angles"] = start_angles(grip, params, profile, n_links)
    return _model.build_scene(grip, params, profile, n_links, **kw)
