"""``compare --contact full --box-depth D``: the full-contact simulation against the free-boundary reference.

The scene is Grip I/II grasped at a depth (:func:`simgrip.sim.full_contact.check_grasp`): the box hangs on the
sticking tip, its edge ``D`` from it, the other contacts frictionless -- the problem the reference of
:func:`simgrip.reference.full_contact.full_contact_record` solves (the contact set from the constrained chain
at the same ``n``, then the point-contact BVP, the tip + corner free-boundary BVP, or the chain itself).

Both records carry the theory's quantities: ``normal_force`` and ``friction_force`` are the tip's (the
simulation sums the contacts within ``3 r_tip`` of its tip node: the tip sphere and the last capsule's end;
its resultant over every contact with the workpiece stays in ``resultant_normal_force`` and
``resultant_friction_force``), ``required_mu`` is ``|friction| / N`` at the tip.  The reference also gives the
constrained chain's ``N`` at the simulation's ``n`` (``chain_normal_force``): the same discrete problem up to the
capsules' rounding (radius ``r``) at the box's edge and at the hinges, so the two agree to ``O(ds) + O(r)``, not
to the settle's tolerance (measured at kappa -10: 0.35 % at n = 16, 0.12 % at n = 32 with the depth corrected for
the edge's rounding).
"""

from __future__ import annotations

import math

from simgrip.settled import settled_record, simulate, tip_forces  # tip_forces re-exported (__all__)

__all__ = ["compare_full", "tip_forces"]


def compare_full(grip: str, params, profile, links: int, *, box_depth: float, progress=None, **settle_kw) -> dict:
    """Simulate the grasp at ``box_depth`` and compare it with the free-boundary reference (module docstring).

    Returns ``{"simulation", "reference", "difference", "warnings"}`` as :func:`simgrip.compare.compare`.
    ValueError for Grip III or the free rod (no box to grasp), or bad arguments; the reference's solver errors
    (``ConstrainedError``, ``FreeBoundaryError``, ``ElasticaError``) propagate (the CLI exits 1).
    """
    from simgrip.report import difference
    from simgrip.reference.full_contact import full_contact_record

    if grip not in ("I", "II"):
        raise ValueError(f"grip: a grasp at a depth needs Grip I or II's box, got {grip!r}")
    state = simulate(grip, params, profile, links, progress=progress, box_depth=box_depth, **settle_kw)
    sim = settled_record(state, params, profile)
    from simgrip.sim.scene import DEFAULT_R_TIP

    sim["resultant_normal_force"], sim["resultant_friction_force"] = sim["normal_force"], sim["friction_force"]
    if state.held:
        N, F = tip_forces(state, DEFAULT_R_TIP)
        sim["normal_force"], sim["friction_force"] = N, F
        sim["required_mu"] = abs(F) / N if N > 0 else math.inf
    rec = full_contact_record(grip, params, profile, n=links, depth=box_depth)
    N_ref, F_ref = float(rec["N"]), float(rec["friction"])
    ref = {"source": rec["reference"], "grip": grip, "contact_set": rec["contact_set"], "depth": rec["depth"],
           "tip": [float(rec["tip_x"]), float(rec["tip_y"])], "normal_force": N_ref, "friction_force": F_ref,
           "required_mu": abs(F_ref) / N_ref if N_ref > 0 else math.inf,
           "feasible": bool(N_ref > 0 and abs(F_ref) <= params.mu_s * N_ref and rec.get("valid", True)),
           "held": bool(N_ref > 0 and abs(F_ref) <= params.mu_s * N_ref),
           "chain_normal_force": rec.get("chain_N"), "chain_tip": [rec["chain_tip_x"], rec["chain_tip_y"]]}
    for k in ("corner_gamma", "corner_fx", "corner_fy"):
        if k in rec:
            ref[k] = rec[k]
    warnings = []
    if bool(sim.get("feasible")) != ref["feasible"]:
        warnings.append(f"the verdicts disagree: simulation feasible {sim.get('feasible')}, reference "
                        f"{ref['feasible']} (required mu: simulation {sim.get('required_mu', math.nan):.4g}, "
                        f"reference {ref['required_mu']:.4g}, mu_s = {params.mu_s:g})")
    return {"simulation": sim, "reference": ref, "difference": difference(sim, ref), "warnings": warnings}
