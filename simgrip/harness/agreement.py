"""Do the static settle and the dynamic settle agree on hold/drop?  Checked over a stress run's cases.

For each case of a ``stress.json`` (:mod:`simgrip.harness.stress`) with a
workpiece, the scene is built again and settled by the static solve and by
the dynamics, and the two answers on hold/drop compared.  Like is compared with
like: the dynamics is MuJoCo's own contact, whose friction acts at the geoms'
surface, so the static settle it is compared with is
``settle(scene, contact="surface")``; the default point-contact settle (the
paper's problem) is settled too and reported beside it.  The two contact
problems differ by the couple ``C`` of the contact force about the centreline
(finite contact radius): a couple turns the rod's end by about ``C / D``
(:func:`couple_rotation`), which is small for a stiff finger and of order one for
a soft one, so there the point and surface problems may genuinely hold and
drop differently (``contact_model_differs``, listed with that rotation).

Where the methods disagree, the case's *friction margin* says whether the
disagreement matters: ``1 - mu_req / mu_s`` of the state that holds (``mu_req``
the largest ``required_mu_contact`` over its contacts, the ratio MuJoCo's
friction cone uses), so a held state 1 % inside the cone has a margin of 0.01.
A disagreement within :data:`MARGIN` of the cone is the friction threshold,
where the two contact models (simgrip's sticking constraint, MuJoCo's soft cone
that creeps) may differ; one above it is a disagreement of the methods.

Run: ``python -m simgrip.harness.agreement STRESS_JSON [--jobs J] [--out FILE]``.
"""

from __future__ import annotations

import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor

from simgrip.command_parser import CommandParser
from simgrip.gripper.state import FRICTION_MARGIN

__all__ = ["MARGIN", "agreement_case", "couple_rotation", "method_agreement"]

#: Disagreements of the methods closer than this to the friction cone (relative) are the threshold (the K-finger
#: states warn there: :data:`simgrip.gripper.state.FRICTION_MARGIN`, the same value).
MARGIN = FRICTION_MARGIN


def couple_rotation(state, D: float) -> float:
    """``max |C| / D`` over a settled state's contacts: the turn [rad] the contact couple ``C`` (over
    ``rho g l^2``) gives a rod of bending stiffness ``D`` (over ``rho g l^3``) over its length."""
    return max((abs(c.moment) for c in state.contacts), default=0.0) / D


def _verdict(st, mu_s):
    """``("held" | "dropped", margin or None)`` of a settled state."""
    if not st.held:
        return "dropped", None
    if not st.contacts:
        return "held", None
    req = max(c.required_mu_contact if math.isfinite(c.required_mu_contact) else c.required_mu
              for c in st.contacts)
    return "held", 1.0 - req / mu_s


def agreement_case(case: dict) -> dict:
    """Settle one stress case three ways; ``{"id", "grip", "newton", "dynamics", "margin", ...}``.

    ``newton`` is the static settle with MuJoCo's surface contact (the dynamics' own contact
    problem), ``newton_point`` the default point-contact settle; each is ``"held"``, ``"dropped"``
    or ``"unsettled: <message>"``.  ``agree`` compares ``newton`` and ``dynamics``;
    ``contact_model_differs`` says whether ``newton_point`` and ``newton`` disagree, with
    ``couple_rotation`` (:func:`couple_rotation` of the surface state).
    """
    from simgrip.harness.stress_cases import stress_profile
    from simgrip.params import DimensionlessParams
    from simgrip.scenes import build_scene
    from simgrip.settle import SettleError, settle

    params = DimensionlessParams(D=case["D"], M=case["M"], b=case["b"], mu_s=case["mu_s"])
    prof = stress_profile(case["profile"], case["kappa"], case.get("alpha", 0.0))
    rec = {k: case[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "profile", "alpha")}
    # the stress run's invalid-state flags of the Newton state (self-intersection, beyond a full turn, ...)
    rec["flags"] = sorted(k for k, v in (case.get("flags") or {}).items() if v)
    out, margins, times = {}, {}, {}
    rec["couple_rotation"] = None
    runs = {"newton": dict(contact="surface"), "newton_point": dict(), "dynamics": dict(method="dynamics")}
    for name, kw in runs.items():
        t0 = time.perf_counter()
        try:
            st = settle(build_scene(case["grip"], params, prof, case["n"]), **kw)
            out[name], margins[name] = _verdict(st, params.mu_s)
            if name == "newton":
                rec["couple_rotation"] = couple_rotation(st, params.D)
        except (SettleError, ValueError) as exc:
            out[name], margins[name] = f"unsettled: {exc}", None
        times[name] = time.perf_counter() - t0
    for name in runs:
        rec[name] = out[name]
        rec[f"time_{name}_s"] = times[name]
        rec[f"margin_{name}"] = margins[name]
    rec["agree"] = out["newton"] == out["dynamics"]
    rec["margin"] = _held_margin(out, margins, "newton", "dynamics")
    rec["contact_model_differs"] = out["newton"] != out["newton_point"]
    rec["margin_point_vs_surface"] = _held_margin(out, margins, "newton", "newton_point")
    return rec


def _held_margin(out, margins, a, b):
    """The margin of the one of ``a``, ``b`` that holds (None when both or neither hold)."""
    held = [m for m in (a, b) if out[m] == "held"]
    return margins.get(held[0]) if len(held) == 1 else None


def method_agreement(cases, *, jobs: int = 1) -> dict:
    """:func:`agreement_case` over the settled stress cases with a workpiece; counts and the disagreements.

    ``disagree_above_margin`` lists the disagreements whose held state is more
    than :data:`MARGIN` inside the friction cone (or whose margin is unknown);
    ``disagree_above_margin_unflagged`` those whose Newton state carries no
    invalid-state flag of the stress run (a self-intersecting rod, one turned
    beyond a full turn, the wrong grip's shape: states where the two methods
    may reach different branches).  ``contact_model_differs`` lists the cases
    whose point-contact and surface-contact static settles disagree above
    :data:`MARGIN` (two contact problems, not two methods), with their
    ``couple_rotation``.
    """
    todo = [c for c in cases if c.get("outcome") == "settled" and c["grip"] != "free"]
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as ex:
            recs = list(ex.map(agreement_case, todo, chunksize=4))
    else:
        recs = [agreement_case(c) for c in todo]
    dis = [r for r in recs if not r["agree"]]
    big = [r for r in dis if r["margin"] is None or abs(r["margin"]) > MARGIN]
    uns = [r for r in recs if any(r[m].startswith("unsettled") for m in ("newton", "newton_point", "dynamics"))]
    model = [r for r in recs if r["contact_model_differs"] and (
        r["margin_point_vs_surface"] is None or abs(r["margin_point_vs_surface"]) > MARGIN)]
    return {"cases": len(recs), "agree": len(recs) - len(dis), "disagree": len(dis),
            "disagree_above_margin": big, "disagree_within_margin": [r for r in dis if r not in big],
            "disagree_above_margin_unflagged": [r for r in big if not r["flags"]],
            "contact_model_differs": model, "unsettled": uns,
            "slowest_dynamics_s": max((r["time_dynamics_s"] for r in recs), default=0.0),
            "slowest_newton_s": max((r["time_newton_s"] for r in recs), default=0.0), "records": recs}


def main(argv=None) -> int:  # pragma: no cover - manual run
    import json

    from simgrip.io import write_json

    ap = CommandParser(prog="python -m simgrip.harness.agreement")
    ap.add_argument("stress_json")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    cases = json.loads(open(a.stress_json).read())["cases"]
    res = method_agreement(cases, jobs=a.jobs)
    if a.out:
        write_json(a.out, res)
    summary = {k: v for k, v in res.items() if k != "records"}
    for key in ("disagree_above_margin", "disagree_within_margin", "disagree_above_margin_unflagged",
                "contact_model_differs", "unsettled"):
        summary[key] = [{k: r[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "newton", "newton_point",
                                            "dynamics", "margin", "margin_point_vs_surface", "couple_rotation",
                                            "flags")} for r in res[key]]
    print(json.dumps(summary, indent=1, default=str))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
