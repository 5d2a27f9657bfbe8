"""``simgrip solve GRIP --contact full``: the reference with every contact unilateral, as one record.

Which contact set occurs is found by the constrained chain (:mod:`simgrip.reference.constrained`, ``n``
links, continued from the point-contact range); then:

* only the tip touches: the paper's point-contact BVP (:func:`simgrip.reference.elastica.solve`);
* the tip and the box's corner (Grips I/II past the onset): the free-boundary BVP
  (:func:`simgrip.reference.free_boundary.solve_corner`);
* anything else (the self-touching spiral of the free rod, a cylinder wrap, a contact interval): no smooth
  BVP is built here; the constrained chain itself is the reference, and the record says so.
"""

from __future__ import annotations

import numpy as np

from simgrip.reference.constrained import DEFAULT_DEPTH, solve_constrained

__all__ = ["full_contact_record"]


def _label(c) -> str:
    """``corner@link10``, ``face@node31``, ``self@node0/link23``: where a contact acts on the chain."""
    if c.kind == "self":
        return f"self@node{c.index}/link{c.other}"
    return f"{c.kind}@{'link' if c.kind in ('corner', 'cylinder') else 'node'}{c.index}"


def _hold(rec: dict, params, N: float, friction: float, valid: bool) -> None:
    """``least_mu``: the least mu_s that holds the box at this grasp, ``|F_f| / N`` (the tip's friction carries the
    weight and the frictionless corner's push on the box: :mod:`simgrip.reference.hold_full`; inf where no friction
    holds it), and ``held`` at the given mu_s."""
    least = abs(float(friction)) / float(N) if (valid and N > 0) else float("inf")
    rec.update(least_mu=least, held=bool(params.mu_s >= least))


def full_contact_record(grip: str, params, profile, n: int = 32, depth: float = DEFAULT_DEPTH) -> dict:
    """A flat record: the contact set, the normal force ``N`` (the tip's), the tip, the contact points'
    arc lengths and forces, which reference produced them, and the chain's own values at ``n`` links.
    ``depth``: the tip below the box's top edge (I) / above its bottom edge (II), over ``l``.

    Raises
    ------
    ValueError
        Grip III (not covered), or bad arguments.
    ConstrainedError, FreeBoundaryError, ElasticaError
        A solver failed (the CLI exits 1).
    """
    if grip == "III":
        raise ValueError("grip: --contact full covers the free rod and Grips I/II (Grip III's cradle is a "
                         "corner contact already), got III")
    from simgrip.reference.elastica import solve
    from simgrip.reference.free_boundary import solve_corner

    from simgrip.reference.constrained import Box

    ch = solve_constrained(grip, params, profile, n, box=Box(depth=depth) if grip != "free" else None)
    kinds = ch.kinds()
    rec = {"grip": grip, "contact": "full", "links": n, "depth": float(depth) if grip != "free" else None}
    contact_set = (["tip"] if grip != "free" and ch.N > 0 else []) + [_label(c) for c in ch.contacts]
    rec["contact_set"] = " + ".join(contact_set) if contact_set else "none"
    if grip != "free" and not kinds:
        sol = solve(grip, params, profile)
        rec.update(reference="point-contact BVP (only the tip touches)", N=sol.normal_force,
                   friction=sol.friction_force, tip_x=float(sol.tip[0]), tip_y=float(sol.tip[1]))
        _hold(rec, params, sol.normal_force, sol.friction_force, bool(sol.feasibility.get("grip_shape", True)))
    elif grip != "free" and kinds == {"corner": 1}:
        b = solve_corner(grip, params, profile, ch, depth=float(depth))
        rec.update(reference="free-boundary BVP (tip + box corner)", N=b.N, friction=b.friction,
                   tip_x=float(b.tip[0]), tip_y=float(b.tip[1]), corner_gamma=b.gamma,
                   corner_fx=float(b.corner_force[0]), corner_fy=float(b.corner_force[1]), valid=b.valid)
        _hold(rec, params, b.N, b.friction, b.valid)
    else:
        rec.update(reference=f"constrained chain, n = {n} (no smooth BVP for this contact set)",
                   N=ch.N if grip != "free" else None, friction=ch.tip_friction if grip != "free" else None,
                   tip_x=float(ch.tip[0]), tip_y=float(ch.tip[1]),
                   self_contacts=kinds.get("self", 0),
                   contact_force_total=float(sum(np.linalg.norm(c.force) for c in ch.contacts)))
    rec.update(chain_N=ch.N if grip != "free" else None, chain_tip_x=float(ch.tip[0]), chain_tip_y=float(ch.tip[1]),
               chain_kkt_residual=ch.kkt_residual)
    return rec
