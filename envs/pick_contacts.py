"""The box's contact forces on each finger of the pick model.

:class:`BoxContactForces` sums, over the contacts between the box and a
finger's geoms, the normal force, the friction force's magnitude and the
normal force's horizontal (squeezing) component.  With elliptic friction cones
(the pick model's) a contact's constraint rows in ``data.efc_force`` are its
contact-frame force (normal, tangent 1, tangent 2, ...) and are read directly;
otherwise each contact's force comes from :func:`mujoco.mj_contactForce`.

It runs on every environment step, so it reads as little as it can: the
contacts' geom pairs always (one ``tolist``), and the constraint forces,
addresses and frames only once a box-finger contact is found (each in one
``tolist``: right after the physics every numpy and MuJoCo attribute call costs
microseconds, issue 18).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

__all__ = ["BoxContactForces"]


class BoxContactForces:
    """Forces of the box on each finger [N], read from a MuJoCo state.

    Parameters
    ----------
    model : mujoco.MjModel
    box_geom : int
        Geom id of the box.
    finger_of_geom : array of int
        For each geom of the model, the finger (0 or 1) it belongs to, or -1.
    """

    def __init__(self, model, box_geom: int, finger_of_geom):
        self.box_geom = int(box_geom)
        self._fog_list = np.asarray(finger_of_geom).tolist()
        self._elliptic = model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
        self._cf = np.zeros(6)

    def __call__(self, model, data) -> list:
        """``[normal_0, friction_0, normal_1, friction_1, side_0, side_1]`` [N].

        ``side_f`` is the horizontal (squeezing) component of finger ``f``'s normal forces; a finger pressing on
        the box's top adds to its normal force but not to its side force.
        """
        if not data.ncon:  # (measured: the MuJoCo reads below cost less after this one, issue 18)
            return [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        fog, bg = self._fog_list, self.box_geom
        con = data.contact
        elliptic = self._elliptic
        hypot = math.hypot
        n0 = t0 = s0 = n1 = t1 = s1 = 0.0
        ef = None
        for i, (g1, g2) in enumerate(con.geom.tolist()):
            f = fog[g2] if g1 == bg else (fog[g1] if g2 == bg else -1)
            if f < 0:
                continue
            if ef is None:  # the first box-finger contact: read the rest, once for all contacts
                frames = con.frame.tolist()  # each contact's frame, its normal first (one read, not a column's)
                if elliptic:
                    adrs = con.efc_address.tolist()
                    ef = data.efc_force.tolist()
                else:
                    ef = self._cf
            if elliptic:
                adr = adrs[i]
                fn, ft = ef[adr], hypot(ef[adr + 1], ef[adr + 2])
            else:
                mujoco.mj_contactForce(model, data, i, ef)
                fn, ft = float(ef[0]), hypot(ef[1], ef[2])
            nx = frames[i][0]  # x component of the contact normal
            if f:
                n1 += fn
                t1 += ft
                s1 += fn * abs(nx)
            else:
                n0 += fn
                t0 += ft
                s0 += fn * abs(nx)
        return [n0, t0, n1, t1, s0, s1]
