"""The ``nodes`` and ``contacts`` fields of a simulation record (``simulate --json``), for every contact mode.

* ``nodes``: each finger's centreline, ``n + 1`` points over ``l``: ``[x, z]`` in the finger's own frame
  (planar; ``x`` away from the palm centre, ``z`` up) or ``[x, y, z]`` in the scene's frame (K fingers).
* ``contacts``: one record per contact on a finger (dimensionless: lengths over ``l``, forces over
  ``rho g l``): ``finger``, ``link`` (0-based), ``arc_length`` (over ``l``), ``with`` (``"workpiece"``,
  ``"self"``, ``"finger K"``), ``point``, ``normal`` (unit, the direction in which the contact pushes
  this finger), ``normal_force`` (>= 0 pressing), ``friction_force`` and ``force`` (the contact's whole
  force on the finger, ``[x, z]`` or ``[x, y, z]``).  Planar ``friction_force`` is the component along
  ``(-normal_z, normal_x)`` (the normal turned by +90 degrees: ``E2`` for a Grip I/II face whose normal is
  ``E1``, so it equals the theory's ``N2`` there and ``-f`` for Grip III's ``f`` along ``e1``).

Point and surface contact (one contact per finger, the paper's) come from the settled state's
:class:`~simgrip.settle.state.FingerContact`; full contact (``contact="full"``) from every MuJoCo contact
the settle ended with (:func:`simgrip.settle.full_contact.contact_set`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["brief_record", "contact_records", "node_records"]


def node_records(state) -> list:
    """``nodes`` of a planar :class:`~simgrip.settle.state.SettledState`: per finger, ``n + 1`` ``[x, z]``."""
    nodes = np.asarray(state.nodes, dtype=float)
    return [[[float(x), float(z)] for x, z in finger] for finger in nodes]


def contact_records(state) -> list:
    """``contacts`` of a planar settled state (see the module docstring)."""
    full = getattr(state, "contact_set", None)
    if full is not None:
        keys = ("finger", "link", "arc_length", "with", "point", "normal", "normal_force", "friction_force",
                "force", "depth", "other_link", "other_arc_length")
        return [{k: c[k] for k in keys if k in c} for c in full]
    out = []
    n = int(state.links)
    for f, c in enumerate(state.contacts if state.held else []):
        gamma = float(c.gamma)
        if state.grip in ("I", "II"):
            normal = np.array([1.0, 0.0])  # the face pushes the rod along +E1 (N > 0)
        else:
            normal = np.array([-math.sin(c.theta), math.cos(c.theta)])  # e2 at gamma
        force = np.array([c.N1, c.N2], dtype=float)
        tangent = np.array([-normal[1], normal[0]])
        out.append({
            "finger": f,
            "link": min(int(gamma * n), n - 1),
            "arc_length": gamma,
            "with": "workpiece",
            "point": [float(c.point[0]), float(c.point[1])],
            "normal": [float(normal[0]), float(normal[1])],
            "normal_force": float(force @ normal),
            "friction_force": float(force @ tangent),
            "force": [float(force[0]), float(force[1])],
            "depth": float(c.penetration),
        })
    return out


def brief_record(record: dict) -> dict:
    """A record for the table: the centreline (``nodes``) left to --json, the contacts counted by kind."""
    out = {k: v for k, v in record.items() if k not in ("nodes", "contacts")}
    if "contacts" in record:
        kinds: dict = {}
        for c in record["contacts"]:
            kinds[c["with"]] = kinds.get(c["with"], 0) + 1
        out["contacts"] = (f"{len(record['contacts'])} (" + ", ".join(f"{k} {v}" for k, v in kinds.items()) + ")"
                           if kinds else "0") + "; --json lists them and the centreline"
    return out
