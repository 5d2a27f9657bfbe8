"""A K-finger gripper beside the planar elastica every finger solves (``simgrip compare --fingers K``).

Where the scene is the same for every finger — Grip I or II, a cylinder or a
box centred on the palm axis (no ``offset``, no ``workpiece_yaw``), one
curvature for all fingers, the contact on a vertical face (``contact_angle``
0) — each finger is the paper's planar problem: the workpiece's weight share
``M`` per finger, the contact at ``X = b/2``.  Its reference is the planar BVP
with the couple of the finger's own contact (``contact_moment``, as for the
planar ``compare``).  Other scenes (an offset or turned workpiece, one
curvature per finger, a sphere touched off its equator, the Grip III cradle)
have no single planar reference; :func:`compare_gripper` refuses them with a
``ValueError`` naming the option, and ``simulate --fingers`` prints them.
"""

from __future__ import annotations

from simgrip.params import DimensionlessParams, as_dimensionless, check_grip
from simgrip.profiles import as_profile

__all__ = ["compare_gripper"]


def _planar_scene_or_raise(grip: str, profile, workpiece: str, contact_angle: float, offset, workpiece_yaw: float):
    """``ValueError`` naming the option that makes the fingers' problems differ from the paper's planar one."""
    if grip not in ("I", "II"):
        raise ValueError(f"grip: compare --fingers compares Grips I and II with the planar BVP (the Grip III cradle "
                         f"has no planar reference here); got {grip!r}: use simulate --fingers")
    if isinstance(profile, (list, tuple)):
        raise ValueError("kappa_per_finger: compare --fingers needs one curvature for every finger (each finger "
                         "then solves the same planar problem); use simulate --fingers")
    if str(workpiece).strip().lower() not in ("box", "cylinder", "sphere"):
        return  # build_gripper names a bad workpiece itself
    if contact_angle != 0.0:
        raise ValueError("contact_angle: compare --fingers compares contacts on the equator (contact_angle 0), where "
                         "the planar BVP's vertical face applies; use simulate --fingers")
    if any(float(v) != 0.0 for v in offset) or workpiece_yaw != 0.0:
        raise ValueError("offset: compare --fingers needs the workpiece centred and unturned (offset 0 0, "
                         "workpiece_yaw 0): each finger then solves the same planar problem; use simulate --fingers")


def compare_gripper(grip: str, params: DimensionlessParams, profile, links: int, *, fingers: int,
                    workpiece: str = "cylinder", contact_angle: float = 0.0, offset=(0.0, 0.0),
                    workpiece_yaw: float = 0.0, **settle_kw) -> dict:
    """Settle the K-finger gripper and compare every finger with the planar BVP.

    Returns ``{"simulation", "reference", "difference", "fingers", "warnings"}``:
    ``simulation`` is :func:`simgrip.gripper.gripper_record` (finger 0's fields
    at the top level), ``reference`` the planar BVP's record
    (:func:`simgrip.report.elastica_record`, with finger 0's contact couple),
    ``difference`` simulation minus reference of the shared numeric fields, and
    ``fingers`` one ``{"finger", "normal_force", "reference_normal_force",
    "relative_difference"}`` per finger (forces over ``rho g l``).  Dropped
    workpieces are compared with the BVP's verdict only (``feasible``).
    ``ValueError`` names the option of a scene without one planar reference
    (see the module docstring).  ``warnings``, as the planar compare's
    (:func:`simgrip.compare.compare`): a reference on another branch than finger
    0's settled shape (:func:`simgrip.compare.branch_warnings`; a held state's
    reference starts from that shape, :func:`simgrip.compare.chain_reference`)
    and the verdicts that disagree (:func:`simgrip.compare.verdict_warnings`).
    """
    from simgrip.compare import branch_warnings, chain_reference, reference_validity, verdict_warnings
    from simgrip.gripper.simulate import gripper_record, simulate_gripper
    from simgrip.reference import elastica
    from simgrip.report import difference, elastica_record

    grip = check_grip(grip)
    params = as_dimensionless(params)  # PhysicalParams too, as simulate_gripper (before any work)
    if not isinstance(profile, (list, tuple)):
        profile = as_profile(profile)
    _planar_scene_or_raise(grip, profile, workpiece, contact_angle, offset, workpiece_yaw)
    state = simulate_gripper(grip, params, profile, links, fingers=fingers, workpiece=workpiece,
                             contact_angle=contact_angle, offset=offset, workpiece_yaw=workpiece_yaw, **settle_kw)
    sim = gripper_record(state, params, profile)
    # an impossible state (valid False: not held) was held by the settle: its reference is on its branch too
    solved = state.held or not getattr(state, "valid", True)
    first = state.records[0] if (solved and state.records) else None
    moment = float(first.moment) if first is not None else 0.0
    if first is not None:
        sol = chain_reference(grip, params, profile, state.link_angles[0], float(first.N1), contact_moment=moment)
        ref_warnings = branch_warnings(state.tip, state.links, sol)
    else:
        sol, ref_warnings = elastica.solve(grip, params, profile), []
    ref = elastica_record(sol)
    ref_warnings = ref_warnings + reference_validity(ref, sol)
    per_finger = []
    for rec in sim["fingers"]:
        n_ref = ref.get("normal_force")
        n_sim = rec.get("normal_force")
        rel = None
        if sim["held"] and isinstance(n_ref, float) and n_ref != 0.0 and isinstance(n_sim, float):
            rel = (n_sim - n_ref) / abs(n_ref)
        per_finger.append({"finger": len(per_finger), "normal_force": n_sim, "reference_normal_force": n_ref,
                           "relative_difference": rel})
    return {"simulation": sim, "reference": ref, "difference": difference(sim, ref), "fingers": per_finger,
            "warnings": ref_warnings + verdict_warnings(sim, ref)}
