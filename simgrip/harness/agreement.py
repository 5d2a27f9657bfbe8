"""Do the static settle and the dynamic settle agree on hold/drop?  Checked over a stress run's cases.

For each case of a ``stress.json`` (:mod:`simgrip.harness.stress`) with a
workpiece, the scene is built again and settled twice, ``settle(scene)``
(Newton) and ``settle(scene, method="dynamics")``, and the two answers on
hold/drop compared.  Where they disagree, the case's *friction margin* says
whether the disagreement matters: ``1 - mu_req / mu_s`` of the state that
holds (``mu_req`` the largest ``required_mu_contact`` over its contacts, the
ratio MuJoCo's friction cone uses), so a held state 1 % inside the cone has a
margin of 0.01.  A disagreement within :data:`MARGIN` of the cone is the
friction threshold, where the two contact models (simgrip's sticking
constraint, MuJoCo's soft cone that creeps) may differ; one above it is a
disagreement of the methods.

Run: ``python -m simgrip.harness.agreement STRESS_JSON [--jobs J] [--out FILE]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor

__all__ = ["MARGIN", "agreement_case", "method_agreement"]

#: Disagreements of the methods closer than this to the friction cone (relative) are the threshold.
MARGIN = 0.02


def agreement_case(case: dict) -> dict:
    """Settle one stress case with both methods; ``{"id", "grip", "newton", "dynamics", "margin", ...}``.

    ``newton``/``dynamics`` are ``"held"``, ``"dropped"`` or ``"unsettled: <message>"``.
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
    for method in ("newton", "dynamics"):
        t0 = time.perf_counter()
        try:
            st = settle(build_scene(case["grip"], params, prof, case["n"]), method=method)
            out[method] = "held" if st.held else "dropped"
            if st.held and st.contacts:
                req = max(c.required_mu_contact if math.isfinite(c.required_mu_contact) else c.required_mu
                          for c in st.contacts)
                margins[method] = 1.0 - req / params.mu_s
        except (SettleError, ValueError) as exc:
            out[method] = f"unsettled: {exc}"
        times[method] = time.perf_counter() - t0
    rec.update(newton=out["newton"], dynamics=out["dynamics"], time_newton_s=times["newton"],
               time_dynamics_s=times["dynamics"], margin_newton=margins.get("newton"),
               margin_dynamics=margins.get("dynamics"))
    held = [m for m in ("newton", "dynamics") if out[m] == "held"]
    rec["agree"] = out["newton"] == out["dynamics"]
    rec["margin"] = margins.get(held[0]) if len(held) == 1 else None
    return rec


def method_agreement(cases, *, jobs: int = 1) -> dict:
    """:func:`agreement_case` over the settled stress cases with a workpiece; counts and the disagreements.

    ``disagree_above_margin`` lists the disagreements whose held state is more
    than :data:`MARGIN` inside the friction cone (or whose margin is unknown);
    ``disagree_above_margin_unflagged`` those whose Newton state carries no
    invalid-state flag of the stress run (a self-intersecting rod, one turned
    beyond a full turn, the wrong grip's shape: states where the two methods
    may reach different branches).
    """
    todo = [c for c in cases if c.get("outcome") == "settled" and c["grip"] != "free"]
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as ex:
            recs = list(ex.map(agreement_case, todo, chunksize=4))
    else:
        recs = [agreement_case(c) for c in todo]
    dis = [r for r in recs if not r["agree"]]
    big = [r for r in dis if r["margin"] is None or abs(r["margin"]) > MARGIN]
    uns = [r for r in recs if r["newton"].startswith("unsettled") or r["dynamics"].startswith("unsettled")]
    return {"cases": len(recs), "agree": len(recs) - len(dis), "disagree": len(dis),
            "disagree_above_margin": big, "disagree_within_margin": [r for r in dis if r not in big],
            "disagree_above_margin_unflagged": [r for r in big if not r["flags"]],
            "unsettled": uns, "slowest_dynamics_s": max((r["time_dynamics_s"] for r in recs), default=0.0),
            "slowest_newton_s": max((r["time_newton_s"] for r in recs), default=0.0), "records": recs}


def main(argv=None) -> int:  # pragma: no cover - manual run
    import json

    from simgrip.io import write_json

    ap = argparse.ArgumentParser(prog="python -m simgrip.harness.agreement")
    ap.add_argument("stress_json")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    cases = json.loads(open(a.stress_json).read())["cases"]
    res = method_agreement(cases, jobs=a.jobs)
    if a.out:
        write_json(a.out, res)
    summary = {k: v for k, v in res.items() if k != "records"}
    for key in ("disagree_above_margin", "disagree_within_margin", "disagree_above_margin_unflagged", "unsettled"):
        summary[key] = [{k: r[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "newton", "dynamics",
                                            "margin", "flags")} for r in res[key]]
    print(json.dumps(summary, indent=1, default=str))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
