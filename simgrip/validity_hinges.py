"""A hinge turned by half a turn or more: the one self-violation a chain's node positions cannot show.

A finger's nodes are the same for a hinge angle ``phi`` and ``phi - 2 pi``, so
:func:`simgrip.validity.chain_violations` (which measures the nodes) sees a gently curved finger where a hinge has
wound a whole turn: ``simgrip simulate I --kappa -55.27 --links 8`` rests each hinge at ``-6.9 rad``, and the
settled chain passed every geometric check as held.  To reach ``|phi| >= pi`` from the straight finger the
two links at that hinge must pass through each other (their capsules share the hinge; at ``|phi| = pi`` the
second lies on the first), whatever the load: no rod does that, and a rod at such a curvature would wind round
itself instead, which the chain, one hinge per link, cannot represent.  The clamp hinge (the first, between the
palm and the first link) is not a fold of the finger and is not checked here.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["folded_hinges"]


def folded_hinges(joint_angles, who: str = "finger") -> list[tuple[str, str]]:
    """``("folded", message)`` for each finger with a hinge between two links turned by ``pi`` or more.

    ``joint_angles``: the settled hinge angles [rad], one row per finger (``(K, n)``; one row ``(n,)`` is one
    finger), the clamp hinge first.  The message names the finger, the hinges and the largest angle.
    """
    q = np.atleast_2d(np.asarray(joint_angles, dtype=float))
    out = []
    for f, row in enumerate(q):
        bad = np.flatnonzero(np.abs(row[1:]) >= math.pi) + 1
        if bad.size:
            k = int(bad[np.argmax(np.abs(row[bad]))])
            more = f" (and {bad.size - 1} more)" if bad.size > 1 else ""
            out.append(("folded", f"{who} {f}: hinge {k}{more} turned {row[k]:.3g} rad, half a turn or more: its "
                                  f"two links have passed through each other (the chain cannot represent a rod "
                                  f"this curved; use more links)"))
    return out
