"""The bench's ratios at matched error and its Markdown tables (``summary.md``, ``skips.md``).

Ratios are ``time of settle / time of the other method`` (``< 1``: settle is
faster).  Settle, naive and minimiser at the same ``n`` converge to the same
chain state, so their ratio is taken at equal ``n``; for the BVP, against the
cheapest tolerance whose error is at most the settle's error at that ``n``.
Where the naive run's time is only a lower bound (an extrapolation too far to
trust, or no decay at all, see :mod:`simgrip.harness.methods`), the ratio is
an upper bound and reads ``< x``; where the naive run has no static state to
reach, ``0``.  Infinite times print as words ("never"), not ``inf``.
:func:`checks_md` and :func:`write_record` serve the bench's other records
(settle targets, K-finger settles): their checks table, and the record
written as JSON and Markdown.
"""

from __future__ import annotations

import math
import os

from simgrip.harness.bench_envs import envs_md

__all__ = ["ratios", "summary_md", "skips_md", "fmt", "checks_md", "ratio_lines", "write_record"]

GRIP_ORDER = ("free", "I", "II", "III")


def fmt(v, spec=".3g", inf="never"):
    """A table cell: ``–`` for missing, yes/no, ``inf`` as the word ``inf`` says (default "never")."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isnan(v):
            return "–"
        if math.isinf(v):
            return inf
        return format(v, spec)
    return str(v)


def _bvp_match(curve, target):
    """The cheapest BVP row with an error at most ``target`` (else the most accurate one)."""
    match = next((b for b in curve if b["tip_err"] <= target), None) if target is not None else None
    if match is None and curve:
        match = min(curve, key=lambda b: b["tip_err"])
    return match


def ratios(rows) -> list[dict]:
    """Per grip and ``n``: settle / naive, settle / minimiser, settle / BVP (and the same for the dynamics)."""
    by = {}
    for r in rows:
        by.setdefault((r["grip"], r["n"], r["method"]), []).append(r)
    out = []
    for (grip, n, method), rs in sorted(by.items(), key=lambda kv: (GRIP_ORDER.index(kv[0][0]), kv[0][1])):
        if method != "settle" or n == 0 or not rs[0].get("time_s"):
            continue
        s = rs[0]
        rec = {"grip": grip, "n": n, "settle_s": s["time_s"], "settle_tip_err": s.get("tip_err")}
        nv = by.get((grip, n, "naive"), [{}])[0]
        naive_s = nv.get("time_min_s") if nv.get("lower_bound") else nv.get("time_s")
        if naive_s and nv.get("settle_same_start_s"):
            rec.update(settle_over_naive=nv["settle_same_start_s"] / naive_s, naive_s=naive_s,
                       naive_extrapolated=bool(nv.get("extrapolated")), naive_lower_bound=bool(nv.get("lower_bound")),
                       settle_same_start_s=nv["settle_same_start_s"])
        mn = by.get((grip, n, "minimiser"), [{}])[0]
        if mn.get("time_s"):
            rec["settle_over_minimiser"] = s["time_s"] / mn["time_s"]
        curve = sorted((b for b in by.get((grip, 0, "bvp"), []) if b.get("tip_err") is not None),
                       key=lambda b: b["time_s"])
        match = _bvp_match(curve, s.get("tip_err"))
        if match is not None:
            rec["settle_over_bvp"] = s["time_s"] / match["time_s"]
            rec["bvp_tol_matched"] = match["tol"]
        dy = by.get((grip, n, "settle_dynamics"), [{}])[0]
        if dy.get("time_s"):
            rec["dynamics_s"] = dy["time_s"]
            rec["dynamics_tip_err"] = dy.get("tip_err")
            if mn.get("time_s"):
                rec["dynamics_over_minimiser"] = dy["time_s"] / mn["time_s"]
            dmatch = _bvp_match(curve, dy.get("tip_err") or 0.0)
            if dmatch is not None:
                rec["dynamics_over_bvp"] = dy["time_s"] / dmatch["time_s"]
            if naive_s:
                rec["dynamics_over_naive"] = dy["time_s"] / naive_s
        out.append(rec)
    return out


def _over_naive(r, key) -> str:
    """A ratio over the naive time: ``0`` when it has no static state, ``< x`` when its time is a lower bound."""
    if r.get("naive_s") is not None and math.isinf(r["naive_s"]):
        return "0 (naive: no static state)"
    v = fmt(r.get(key))
    if r.get("naive_lower_bound"):
        return f"< {v} (naive: not reached)"
    if r.get("naive_extrapolated"):
        return f"{v} (naive extrap.)"
    return v


def skips_md(skips) -> str:
    """The skipping table (Markdown)."""
    lines = [
        "| skip | case | n | with (s) | without (s) | speedup | answer change: tip | force | without means |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for s in skips:
        if s.get("error"):
            lines.append(f"| {s['skip']} | – | {s['n']} | – | – | – | – | – | failed: {s['error']} |")
            continue
        without, sp = fmt(s.get("time_without_s"), inf="never (no static state)"), s.get("speedup")
        speedup = fmt(sp, ".3g", "unbounded") + "×" if sp is not None else "–"
        if s.get("lower_bound"):
            without, speedup = f"> {without} (not reached)", f"> {speedup}"
        elif s.get("extrapolated"):
            without += " (extrap.)"
        lines.append(
            f"| {s['skip']} | {s.get('case', '')} | {s['n']} | {fmt(s.get('time_with_s'))} | {without} | {speedup} | "
            f"{fmt(s.get('answer_change_tip'), '.1e')} | {fmt(s.get('answer_change_force'), '.1e')} | {s.get('note', '')} |"
        )
    return "\n".join(lines) + "\n"


def _ratio_tables(res) -> list[str]:
    L = ["## Ratios at matched error (time of settle / time of the other method; < 1: settle is faster)", "",
         "| grip | n | settle (s) | tip error | settle / naive | settle / minimiser | settle / BVP (tol) |",
         "|---|---|---|---|---|---|---|"]
    for r in res.ratios:
        bv = fmt(r.get("settle_over_bvp"))
        if r.get("bvp_tol_matched") is not None:
            bv += f" ({r['bvp_tol_matched']:.0e})"
        L.append(f"| {r['grip']} | {r['n']} | {fmt(r['settle_s'])} | {fmt(r.get('settle_tip_err'), '.2e')} | "
                 f"{_over_naive(r, 'settle_over_naive')} | {fmt(r.get('settle_over_minimiser'))} | {bv} |")
    L += ["", "## settle(method=\"dynamics\"): over-damped MuJoCo dynamics with MuJoCo's own friction", "",
          "| grip | n | dynamics (s) | tip error | dynamics / naive | dynamics / minimiser | dynamics / BVP |",
          "|---|---|---|---|---|---|---|"]
    for r in res.ratios:
        if r.get("dynamics_s") is None:
            continue
        L.append(f"| {r['grip']} | {r['n']} | {fmt(r['dynamics_s'])} | {fmt(r.get('dynamics_tip_err'), '.2e')} | "
                 f"{_over_naive(r, 'dynamics_over_naive')} | {fmt(r.get('dynamics_over_minimiser'))} | "
                 f"{fmt(r.get('dynamics_over_bvp'))} |")
    return L


def _rows_table(res) -> list[str]:
    L = ["## Errors and times", "", "| grip | n | method | time (s) | steps | tip error | force error | note |",
         "|---|---|---|---|---|---|---|---|"]
    for r in res.rows:
        t = fmt(r.get("time_s"), inf="never (no static state)")
        if r.get("lower_bound"):
            t = f"> {fmt(r.get('time_min_s'))}"
        method = f"{r['method']} tol {r['tol']:.0e}" if not r["n"] and r.get("tol") else r["method"]
        if r.get("target_error") is not None:
            method = f"{r['method']} {r['target_error']:.0e} ({r.get('links', '?')} links)"
        L.append(f"| {r['grip']} | {r['n'] or '–'} | {method} | {t} | {fmt(r.get('steps'))} | "
                 f"{fmt(r.get('tip_err'), '.2e')} | {fmt(r.get('force_err'), '.2e')} | {r.get('note') or ''} |")
    return L


def _sweep_text(s) -> list[str]:
    if not s:
        return []
    if "error" in s:
        return ["", f"## Fig. 7 sweep: failed ({s['error']})"]
    return ["", f"## Fig. 7 sweep (Grip I, {len(s['kappas'])} curvatures, n = {s['n']})", "",
            f"simulation with warm starts {s['time_warm_s']:.3g} s, cold {s['time_cold_s']:.3g} s, "
            f"BVP sweep {s['time_bvp_s']:.3g} s; held where the BVP is feasible: "
            f"{sum(s['held'])}/{len(s['held'])} held, {sum(s['held_bvp_feasible'])} feasible; "
            f"max |N_sim − N_BVP| over held points {fmt(s['max_dN_sim_vs_bvp'], '.2e')} (BVP without the contact "
            f"couple; discretisation error at this n), max |N_sim − N_chain| {fmt(s.get('max_dN_sim_vs_chain'), '.2e')}."]


def summary_md(res, load_avg) -> str:
    """``summary.md``: ratios, every row, the sweep, the env throughput and the skipping table."""
    where = f"jobs = {res.jobs}" if res.jobs is not None else "on an existing Dask cluster"
    L = [f"# simgrip bench{' (quick)' if res.quick else ''}", "",
         f"{where}, {os.cpu_count()} cores, load average {load_avg}, {res.elapsed_s:.0f} s in all. "
         "Timings are medians; errors are against the converged BVP (tol 1e-10) of the same state.", ""]
    L += _ratio_tables(res)
    L += [""] + _rows_table(res)
    L += _sweep_text(res.sweep)
    L += envs_md(res.env)
    L += ["", "## What skipping buys", "", skips_md(res.skips)]
    jobs = f" --jobs {res.jobs}" if res.jobs is not None else " --scheduler ADDRESS"
    L += ["Reproduce: `simgrip bench" + (" --quick" if res.quick else "") + f"{jobs}` "
          "(or `python -c \"from simgrip.harness.bench import run_bench; run_bench('bench_out')\"`).", ""]
    return "\n".join(L)


def ratio_lines(rows: list[dict]) -> list[str]:
    """Markdown bullet lines of bench rows: ``- <case>: key value; ...`` (floats to 3 significant digits)."""
    def val(v) -> str:
        return f"{v:.3g}" if isinstance(v, float) else str(v)

    return ["- " + r["case"] + ": " + "; ".join(f"{k} {val(v)}" for k, v in r.items() if k != "case") for r in rows]


def checks_md(checks: dict) -> list[str]:
    """Markdown lines of a ``{check: met}`` table (a blank line first; met reads yes or NO)."""
    return ["", "| check | met |", "|---|---|"] + [f"| {k} | {'yes' if v else 'NO'} |" for k, v in checks.items()]


def write_record(out_dir, name: str, rec: dict, markdown: str) -> None:
    """Write ``rec`` as ``<name>.json`` and ``markdown`` as ``<name>.md`` into ``out_dir``, each whole or not at
    all (:func:`simgrip.io.write_json`, :func:`simgrip.io.atomic_write`)."""
    from pathlib import Path

    from simgrip.io import atomic_write, write_json

    out = Path(out_dir)
    write_json(out / f"{name}.json", rec)
    with atomic_write(out / f"{name}.md") as fh:
        fh.write(markdown)
