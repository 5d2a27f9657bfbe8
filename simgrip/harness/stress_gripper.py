"""K-finger cases of the stress run: off-centre, turned workpieces and unequal fingers (``simgrip stress``).

There is no closed form for these grasps, so each case is checked for what must
hold (:func:`run_gripper_case`):

* the settle ends: a state, or a named error (``rejected``: a ValueError
  naming an input; ``unsettled``: :class:`~simgrip.settle.SettleError`);
* a returned state is finite and converged, its static residual within its
  tolerance; a held workpiece is balanced: its net force within the residual
  (to round-off) and its net moment within ``sqrt(3)`` tolerances (the
  rotation rows are in its body frame);
* it is deterministic: the same case built and settled again gives
  bit-identical ``qpos`` and step count;
* it ends within the per-case wall-clock guard (a hang is a failure).

A drop, or a settle that does not end, is explained from its start
(:func:`diagnose_start`, :mod:`simgrip.gripper.start`): ``start_mu``
(the largest friction coefficient the start's forces need at a finger),
``start_balanced`` / ``start_residual`` (whether a start with the workpiece
level balances it at all), ``start_min_eigenvalue`` (the smallest
eigenvalue of the statics' second variation on the workpiece's admissible
motions, negative: unstable) and ``start_growth`` (the largest eigenvalue
modulus of the settle's one-step map linearised about the start, above
``1 + UNSTABLE_GROWTH``: unstable), both from
:mod:`simgrip.gripper.stability`.  Its
``drop_reason`` is the first that applies of ``"wrong grip"`` (held, but a
tip settled on the other grip's side of the palm, so reported not held:
:func:`simgrip.validity.check_grip_shape`), ``"friction"`` (``start_mu >
mu_s``), ``"unbalanced start"`` (no balanced start with the workpiece level:
the dynamics had to find one, and its ``start_mu`` and ``start_growth`` are
about a state that is not an equilibrium), ``"unstable start"``
(a negative ``start_min_eigenvalue``: the workpiece leaves an unstable
equilibrium exponentially, at the rate ``start_growth`` per step) and ``"unexplained"`` (a balanced, stable start
whose friction suffices: a finding, not an expected drop).

:func:`make_gripper_cases` draws the cases from a seeded generator
(:func:`numpy.random.default_rng`), so a run is reproducible and its cases do
not depend on how the run is spread over processes: grips I and II in turn,
a cylinder (``K`` = 3, 4, 5) or a box (``K`` = 2, 4), one uniform curvature
per finger (a base curling onto the workpiece, each finger within
``+-KAPPA_SPREAD`` of it), ``D``, ``M``, ``mu_s``, ``b``, ``n``, and the
workpiece off the palm axis by up to :data:`OFFSET_FRACTION` of its
half-width (``K = 2``: along the fingers' plane only, see
:mod:`simgrip.gripper.placement`) and turned (box: up to
:data:`MAX_BOX_YAW`).
"""

from __future__ import annotations

import math
import time
import traceback
import warnings

import numpy as np

from simgrip.harness.case_guard import CaseTimeout as _Timeout
from simgrip.harness.case_guard import deadline as _deadline
from simgrip.harness.case_guard import names_an_input

__all__ = ["DROP_REASONS", "GRIPPER_SHAPES", "default_gripper_cases", "diagnose_start", "gripper_counts",
           "make_gripper_cases", "run_gripper_case"]

#: ``(workpiece, K)`` pairs drawn, in turn.
GRIPPER_SHAPES = (("cylinder", 3), ("box", 4), ("cylinder", 4), ("box", 2), ("cylinder", 5))
#: Each finger's curvature within this of the case's base curvature.
KAPPA_SPREAD = 0.3
#: The workpiece's centre off the palm axis by at most this fraction of its half-width.
OFFSET_FRACTION = 0.1
#: Largest turn of a box about its axis [rad] (its fingers stay on flat faces).
MAX_BOX_YAW = 0.15
#: Inputs a rejection may name (beyond simgrip.harness.stress.INPUT_NAMES).
GRIPPER_INPUTS = ("offset", "workpiece_yaw", "workpiece", "kappa_per_finger", "contact_angle")
#: Why a case dropped or did not settle, in the order they are tested (see the module docstring).
DROP_REASONS = ("wrong grip", "friction", "unbalanced start", "unstable start", "unexplained")


def make_gripper_cases(count: int, seed: int = 0, max_links: int = 32) -> list[dict]:
    """``count`` K-finger cases (see the module docstring); ids ``0 .. count-1``.

    ``max_links`` caps ``n`` (drawn from 8, 16, 32).  ValueError naming ``count``, ``seed`` or ``max_links``.
    """
    for name, value, lowest in (("count", count, 0), ("seed", seed, 0), ("max_links", max_links, 2)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lowest:
            raise ValueError(f"{name} must be an integer >= {lowest}, got {value!r}")
    rng = np.random.default_rng([int(seed), 13])
    out = []
    for i in range(int(count)):
        grip = ("I", "II")[i % 2]
        shape, K = GRIPPER_SHAPES[(i // 2) % len(GRIPPER_SHAPES)]
        base = float(rng.uniform(-8.0, -4.0) if grip == "I" else rng.uniform(3.5, 7.0))
        kappas = [round(base + float(rng.uniform(-KAPPA_SPREAD, KAPPA_SPREAD)), 6) for _ in range(K)]
        b = float(rng.uniform(0.4, 0.8))
        radius = OFFSET_FRACTION * (0.5 * b - 2e-3) * float(rng.uniform(0.0, 1.0))
        angle = 0.0 if K == 2 else float(rng.uniform(-math.pi, math.pi))
        radius *= 1.0 if K != 2 else float(rng.choice([-1.0, 1.0]))
        yaw_lim = MAX_BOX_YAW if shape == "box" else math.pi
        out.append(dict(
            kind="gripper", id=i, grip=grip, workpiece=shape, fingers=K, kappas=kappas,
            D=float(10 ** rng.uniform(-0.5, 0.5)), M=float(rng.uniform(0.5, 8.0)),
            mu_s=float(10 ** rng.uniform(0.0, 0.5)), b=b,
            n=int(min(max_links, int(rng.choice([8, 16, 32])))),
            offset=[radius * math.cos(angle), radius * math.sin(angle)],
            workpiece_yaw=float(rng.uniform(-yaw_lim, yaw_lim)),
        ))
    return out


def _scene(case: dict):
    from simgrip.params import DimensionlessParams
    from simgrip.gripper.scene import uniform_profiles
    from simgrip.gripper.reuse import build_gripper  # one compile per structure, set in place

    params = DimensionlessParams(D=case["D"], M=case["M"], b=case["b"], mu_s=case["mu_s"])
    return build_gripper(case["grip"], params, list(uniform_profiles(case["kappas"], case["fingers"])), case["n"],
                         fingers=case["fingers"], workpiece=case["workpiece"], offset=case["offset"],
                         workpiece_yaw=case["workpiece_yaw"])


def _settle(case: dict):
    from simgrip.gripper.settle import settle_gripper

    return settle_gripper(_scene(case))


def diagnose_start(case: dict) -> dict:
    """The start's ``start_mu``, ``start_balanced``, ``start_residual``, ``start_growth`` and the ``drop_reason``
    they give (see the module docstring; all but ``"wrong grip"``); the first three None when the start holds
    nothing."""
    from simgrip.gripper.stability import start_growth, start_stiffness
    from simgrip.gripper.start import start_forces

    f = start_forces(_scene(case))
    growth = start_growth(_scene(case))
    out = dict(start_mu=None, start_balanced=None, start_residual=None, start_min_eigenvalue=None,
               start_growth=None if growth is None else float(growth), drop_reason="unexplained")
    if f is None:
        return out
    stiff = start_stiffness(_scene(case)) if case["workpiece"] != "sphere" else None
    if stiff is not None:
        out["start_min_eigenvalue"] = stiff.min_eigenvalue
    out.update(start_mu=f.max_required_mu, start_balanced=f.balanced, start_residual=f.residual)
    if f.max_required_mu > case["mu_s"]:
        out["drop_reason"] = "friction"
    elif not f.balanced:
        out["drop_reason"] = "unbalanced start"
    elif stiff is not None and not stiff.stable:
        out["drop_reason"] = "unstable start"
    return out


def _check(st) -> str | None:
    """Why a returned state breaks what must hold, or None."""
    arrays = [st.qpos, st.tip, st.force_balance, st.moment_balance]
    forces = [v for r in st.records for v in (r.N1, r.N2, r.N3)]
    if not (all(np.all(np.isfinite(a)) for a in arrays) and np.all(np.isfinite(forces))
            and math.isfinite(st.residual)):
        return "non-finite settled state returned"
    if not st.converged or not st.residual <= st.tolerance:
        return f"state returned with converged={st.converged}, residual {st.residual:.3g} (tolerance {st.tolerance:.3g})"
    if st.held:
        weight = st.fingers * max(1.0, float(np.max(np.abs([r.N2 for r in st.records] or [0.0]))))
        if not np.max(np.abs(st.force_balance)) <= st.residual + 1e-12 * (1.0 + weight):
            return f"force balance {np.max(np.abs(st.force_balance)):.3g} above the residual {st.residual:.3g}"
        if not np.linalg.norm(st.moment_balance) <= math.sqrt(3.0) * st.tolerance:
            return f"moment balance {np.linalg.norm(st.moment_balance):.3g} above sqrt(3) x {st.tolerance:.3g}"
    return None


def run_gripper_case(case: dict, *, timeout_s: float = 60.0) -> dict:
    """Build and settle one K-finger case twice; the case with ``outcome``, ``error``, ``held``, ``steps``..."""
    from simgrip.settle import SettleError

    rec = dict(case)
    rec.update(outcome=None, error=None, error_type=None, steps=None, residual=None, held=None, penetration=None,
               time_s=None, grip_matched=None, start_mu=None, start_balanced=None, start_residual=None,
               start_min_eigenvalue=None, start_growth=None, drop_reason=None)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), _deadline(timeout_s):
            warnings.simplefilter("error", RuntimeWarning)
            st = _settle(case)
            again = _settle(case)
        rec.update(steps=int(st.steps), residual=float(st.residual), held=bool(st.held),
                   penetration=float(st.penetration), grip_matched=bool(st.grip_matched))
        # issue 17: the geometric check recomputed from the returned state (simgrip.validity_shapes), beside
        # what the state says (valid): an impossible state returned as valid is counted
        from simgrip.validity_shapes import gripper_violations

        rec.update(valid=bool(getattr(st, "valid", True)),
                   invalid_kinds=sorted({k for k, _ in gripper_violations(_scene(case), st)}))
        why = _check(st)
        if why is None and not (np.array_equal(st.qpos, again.qpos) and st.steps == again.steps):
            why = "not deterministic: the same case settled twice differs"
        if why is None:
            rec["outcome"] = "settled"
        else:
            rec.update(outcome="failed", error=why, error_type="check")
    except _Timeout:
        rec.update(outcome="failed", error=f"no answer within {timeout_s:g} s (hang)", error_type="Timeout")
    except ValueError as exc:
        named = names_an_input(str(exc)) or any(k in str(exc) for k in GRIPPER_INPUTS)
        rec.update(outcome="rejected" if named else "failed", error=str(exc) if named else
                   f"unnamed ValueError: {exc}\n{traceback.format_exc(limit=4)}", error_type=type(exc).__name__)
    except SettleError as exc:
        rec.update(outcome="unsettled", error=str(exc), error_type=type(exc).__name__)
    except Exception as exc:  # noqa: BLE001 - anything else is a failure, recorded
        rec.update(outcome="failed", error=f"{exc}\n{traceback.format_exc(limit=4)}", error_type=type(exc).__name__)
    if rec["outcome"] == "unsettled" or (rec["outcome"] == "settled" and not rec["held"]):
        try:
            with warnings.catch_warnings(), _deadline(timeout_s):
                rec.update(diagnose_start(case))
            if rec["grip_matched"] is False:
                rec["drop_reason"] = "wrong grip"
        except Exception as exc:  # noqa: BLE001 - a diagnosis that fails is said, never the case's outcome
            rec["drop_reason"] = f"undiagnosed ({type(exc).__name__}: {exc})"
    rec["time_s"] = time.perf_counter() - t0
    return rec


def gripper_counts(recs) -> dict:
    """Outcome -> number of K-finger cases, plus ``held``, ``dropped``, ``invalid`` (the geometric check,
    :func:`simgrip.validity_shapes.gripper_violations`) and ``invalid_returned_as_valid`` (must be 0) among the
    settled, and
    ``dropped_by`` / ``unsettled_by``: ``drop_reason`` -> number."""
    counts = {k: 0 for k in ("settled", "rejected", "unsettled", "failed")}
    for c in recs:
        counts[c["outcome"]] += 1
    counts["total"] = len(recs)
    counts["held"] = sum(1 for c in recs if c["outcome"] == "settled" and c["held"])
    counts["dropped"] = sum(1 for c in recs if c["outcome"] == "settled" and not c["held"])
    counts["invalid"] = sum(1 for c in recs if c["outcome"] == "settled" and c.get("invalid_kinds"))
    counts["invalid_returned_as_valid"] = sum(1 for c in recs if c["outcome"] == "settled" and c.get("invalid_kinds")
                                              and c.get("valid", True))
    for name, sel in (("dropped_by", lambda c: c["outcome"] == "settled" and not c["held"]),
                      ("unsettled_by", lambda c: c["outcome"] == "unsettled")):
        by: dict = {}
        for c in recs:
            if sel(c):
                why = c.get("drop_reason") or "undiagnosed"
                by[why] = by.get(why, 0) + 1
        counts[name] = by
    return counts


def default_gripper_cases(cases: int) -> int:
    """K-finger cases in a stress run of ``cases`` planar cases: one per 50, at least 1, at most 8."""
    return min(8, max(1, int(cases) // 50))
