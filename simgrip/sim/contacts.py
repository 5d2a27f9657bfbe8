"""Contact pairs between the fingers and the workpiece, and the forces they carry.

Nothing in a simgrip scene collides through MuJoCo's broad phase (every geom
has ``contype = conaffinity = 0``): each contact that can happen is an
explicit ``<pair>`` added by :func:`add_pair`, so there is no finger
self-collision and no search over geoms that can never meet.

Forces are read from MuJoCo's solved constraint forces
(:func:`mujoco.mj_contactForce`, the contact frame's first axis is the normal,
pointing from geom1 to geom2).
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["SCENE_SOLIMP", "SCENE_SOLREF", "add_pair", "normal_force", "pair_contacts"]

#: Contact softness of the scenes' finger-workpiece pairs (stiff: penetration ~1e-5 l at rest).
SCENE_SOLREF = (0.002, 1.0)
SCENE_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


def add_pair(spec: mujoco.MjSpec, name: str, geom1: str, geom2: str, mu: float, *, condim: int = 3,
             spin: float = 0.0, solref=SCENE_SOLREF, solimp=SCENE_SOLIMP):
    """Add the contact pair ``name`` between the geoms named ``geom1`` and ``geom2``.

    ``mu`` is the sliding friction in both tangent directions; ``spin`` the
    torsional friction [m] (used with ``condim >= 4``); no rolling friction.
    Returns the pair's spec.
    """
    pair = spec.add_pair(name=name, geomname1=geom1, geomname2=geom2)
    pair.condim = int(condim)
    pair.friction = [mu, mu, spin, 0.0, 0.0]
    pair.solref = list(solref)
    pair.solimp = list(solimp)
    return pair


def pair_contacts(data: mujoco.MjData, geom1: int, geom2: int) -> list[int]:
    """Indices of the active contacts between geoms ``geom1`` and ``geom2`` (either order)."""
    n = data.ncon
    if n == 0:
        return []
    con = data.contact  # (one view of MuJoCo's contact arrays: each ``data.contact`` builds a new one)
    g1, g2 = con.geom1[:n].tolist(), con.geom2[:n].tolist()
    a, b = int(geom1), int(geom2)
    return [i for i in range(n) if (g1[i] == a and g2[i] == b) or (g1[i] == b and g2[i] == a)]


def normal_force(model: mujoco.MjModel, data: mujoco.MjData, i: int) -> float:
    """Normal force of contact ``i`` [N] (>= 0: pushing the geoms apart)."""
    f = np.zeros(6)
    mujoco.mj_contactForce(model, data, i, f)
    return float(f[0])
