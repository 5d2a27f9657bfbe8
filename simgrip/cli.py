"""The ``simgrip`` command line: a thin layer over the library.

Every command works in the paper's dimensionless units (lengths over the finger
length, forces on the rod over ``rho g l``, z up, the finger's base at the
origin).

What every command does with its input and with an interrupt:

* bad input prints one line naming the parameter (or option) and exits with
  status 2, before any work: output paths (``--out``, ``--png``, ``--gif``) are
  checked first, then the values; numeric options take negative values as
  values (``--kappa -1e6``, ``--kappa -inf`` reach validation);
* a solver that cannot converge says so and exits with status 1;
* Ctrl-C (SIGINT) or SIGTERM prints ``simgrip <command>: interrupted`` and
  exits with status 130, without a traceback; the parallel runner has stopped
  its workers by then, and results, written whole or not at all
  (:func:`simgrip.io.atomic_write`), leave no partial file behind;
* a closed standard output (``simgrip compare ... | head -1``) ends quietly.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import signal
import sys
import threading
from pathlib import Path

from simgrip.params import (
    ALPHA_MAX,
    D_MAX,
    D_MIN,
    KAPPA_LIMIT,
    M_MAX,
    MAX_LINKS,
    MU_MAX,
    DimensionlessParams,
    check_grip,
)
from simgrip.command_parser import EXIT_USAGE, CommandParser
from simgrip.profiles import Concentrated, Uniform

__all__ = ["main", "build_parser"]

EXIT_FAILED = 1
EXIT_INTERRUPTED = 130  # 128 + SIGINT, what shells report for a Ctrl-C
#: Most nodes of solve's discrete stability check: its error falls as 1/K^2, ~1e-8 relative here, in about 2 s.
MAX_K = 16384
#: simulate/compare print progress lines on stderr (model build, settle) for a model whose compile takes
#: seconds: MuJoCo's compile solves the mass matrix once per body, work ~ fingers * links^3, about 3 s for
#: one finger of SLOW_LINKS links (the threshold: fingers * links^3 > SLOW_LINKS^3).
SLOW_LINKS = 512
from simgrip.cli_outputs import OUTPUT_OPTIONS, RENDER_DEFAULTS, check_outputs as _check_outputs  # noqa: F401
from simgrip.cli_outputs import clean_after_interrupt as _clean_after_interrupt, render_outputs as _render_outputs
from simgrip.cli_outputs import drop_empty as _drop_empty


def _add_state_options(p: argparse.ArgumentParser, grips=("free", "I", "II", "III")) -> None:
    p.add_argument("grip", help=f"one of {', '.join(grips)}")
    g = p.add_argument_group("rod, workpiece and curvature (dimensionless)")
    g.add_argument("--kappa", type=float, default=None, help=f"uniform intrinsic curvature kappa_bar = l*kappa0, |kappa| <= {KAPPA_LIMIT:g} (required for --profile uniform)")
    g.add_argument("--D", type=float, default=1.0, help=f"bending stiffness EI/(rho g l^3), {D_MIN:g}..{D_MAX:g} [default 1]")
    g.add_argument("--M", type=float, default=5.0, help=f"workpiece mass per finger m/(rho l), 0..{M_MAX:g} [default 5]")
    g.add_argument("--b", type=float, default=0.6, help="workpiece width b/l, 0 < b < 2 [default 0.6]")
    g.add_argument("--mu", type=float, default=1.0, help=f"static friction coefficient mu_s, 0..{MU_MAX:g} [default 1]")
    g.add_argument("--gamma", type=float, default=0.8, help="Grip III contact arc length gamma/l, 0 < gamma < 1 [default 0.8]")
    g.add_argument("--profile", default="uniform", help="curvature profile: uniform or concentrated (eq. 34)")
    g.add_argument("--kappa-max", type=float, default=None, help=f"peak |kappa_bar| of the concentrated profile, 0..{KAPPA_LIMIT:g} [default 6]")
    g.add_argument("--alpha", type=float, default=None, help=f"concentration exponent of eq. (34), 0..{ALPHA_MAX:g} [default 2]")
    g.add_argument("--sign", type=int, default=None, help="sign p of eq. (34): -1 curls down, +1 up [default: +1 for Grip II, else -1]")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``simgrip`` command."""
    parser = CommandParser(prog="simgrip", description="Soft-finger grips: elastica reference, MuJoCo simulation, figures and benchmarks.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=CommandParser)

    p = sub.add_parser("solve", help="solve the elastica boundary-value problem of one grip")
    _add_state_options(p)
    p.add_argument("--K", type=int, default=128, help=f"nodes of the discrete stability check, 2..{MAX_K} [default 128]")
    p.add_argument("--contact", default="point",
                   help="point (the paper's BVP, default) or full: every contact unilateral (free, I, II): the "
                   "contact set found by the constrained chain, then the free-boundary BVP (tip + box corner) or "
                   "the chain itself where no smooth BVP applies")

    for name, text in (
        ("simulate", "settle the MuJoCo finger (symmetric reduction) and print its state"),
        ("compare", "simulation, elastica reference and their difference side by side"),
    ):
        p = sub.add_parser(name, help=text)
        _add_state_options(p)
        p.add_argument("--links", type=int, default=32, help=f"links per finger, 2..{MAX_LINKS} [default 32]")
        p.add_argument(
            "--method", default=None,
            help="settle method: newton (static solve, residual 1e-10) or dynamics "
            "(over-damped MuJoCo dynamics with MuJoCo's own friction) [default: newton, and where it fails the "
            "dynamics, with a warning; an explicit --method newton does not fall back]; with --fingers: "
            "auto (the symmetry skip where the scene is exactly symmetric, else dynamics), symmetric or "
            "dynamics [default auto]",
        )
        p.add_argument("--contact", default=None,
                       help="where sticking friction acts: point (the finger's centreline, the paper's point "
                       "contact; default for newton) or surface (MuJoCo's contact point on the tip sphere, whose "
                       "radius adds a couple; the reference then carries it; the only choice for dynamics); "
                       "full: every link and the tip may touch the workpiece (a real box below the palm) and "
                       "the finger itself, settled by the over-damped dynamics (free, I, II); "
                       "with --fingers: the symmetry skip's (point by default; surface for box and cylinder)")
        p.add_argument("--target-error", type=float, default=None,
                       help="settle to this error (tip over l, forces relative) by Richardson extrapolation over "
                       "resolutions it chooses (free, I, II; --links is then ignored)")
        p.add_argument("--box-depth", type=float, default=None, metavar="D",
                       help="with --contact full, Grips I/II: grasp the box with the tip D (over l, in (0, 1]) below "
                       "its top edge (II: above its bottom edge); the box then hangs on the tip's friction, as in "
                       "the free-boundary reference (simgrip solve GRIP --contact full, depth 0.4) [default: the "
                       "box stays 0.15 l below the palm]")
        p.add_argument("--extra-friction", default=None, choices=("on", "off"),
                       help="with --contact full: friction on the contacts other than the tip's (off: frictionless, "
                       "the theory's determinate problem; on: every contact, statically indeterminate) "
                       "[default: off with --box-depth, else on]")
        if name in ("simulate", "compare"):  # compare: symmetric scenes only (simgrip.gripper.compare)
            p.add_argument("--fingers", type=int, default=None,
                           help="K >= 2 fingers around the palm axis holding a workpiece free in 3-D (Grips I, II: "
                           "the symmetry skip where exactly symmetric, else dynamics, see --method; III: a box with "
                           "K = 4, each finger carrying its face's bottom edge, settled as the planar cradle); "
                           "--json gains 'fingers', one record per finger, and 'method', which settle ran")
            p.add_argument("--workpiece", default=None,
                           help="with --fingers: box (K = 2 or 4), cylinder or sphere (diameter b) [default cylinder]")
            p.add_argument("--offset", type=float, nargs=2, default=None, metavar=("DX", "DY"),
                           help="with --fingers: the workpiece's centre off the palm axis over l (box, cylinder; "
                           "the palm axis inside its footprint) [default 0 0]")
            p.add_argument("--workpiece-yaw", type=float, default=None, metavar="DEG",
                           help="with --fingers: the workpiece turned about its vertical axis, degrees [default 0]")
            p.add_argument("--kappa-per-finger", type=float, nargs="+", default=None, metavar="K",
                           help="with --fingers: one uniform curvature per finger (K values; replaces --kappa)")
            p.add_argument("--contact-angle", type=float, default=None, metavar="DEG",
                           help="with --workpiece sphere: elevation of the contact normal at the start, degrees in "
                           "(-90, 90) (0: the equator) [default 0]; the JSON's angles are in radians")

    p = sub.add_parser("modes", help="natural frequencies and mode shapes of the settled finger beside the rod's")
    _add_state_options(p)
    p.add_argument("--links", type=int, default=32, help=f"links per finger, 2..{MAX_LINKS} [default 32]")
    p.add_argument("--count", type=int, default=3,
                   help="lowest modes to compute, 1..the degrees of freedom (links, or links - 1 with the "
                   "workpiece held) [default 3]")
    p.add_argument("--method", default=None, help="settle method: newton or dynamics [default newton]")
    p.add_argument("--contact", default=None, help="where the settle's sticking friction acts: point or surface "
                   "[default point]; the modes always stick the centreline point")
    p.add_argument("--fingers", type=int, default=None,
                   help="K >= 2 fingers around the palm axis holding a workpiece free in 3-D (Grips I, II): the "
                   "gripper's modes, its symmetric modes and the rod's beside them")
    p.add_argument("--workpiece", default=None, help="with --fingers: box (K = 2 or 4), cylinder or sphere "
                   "[default cylinder]")

    p = sub.add_parser("bench", help="run time against error, naive vs settle vs minimiser vs BVP, what skipping buys")
    from simgrip.harness import bench as _bench  # light: matplotlib/mujoco are imported inside its functions

    _bench.add_arguments(p)

    p = sub.add_parser("stress", help="randomised and grid numerical stress test of settle()")
    from simgrip.harness import stress as _stress

    _stress.add_arguments(p)

    p = sub.add_parser("sweep", help="design map: settled simulation beside the elastica BVP over a grid (Dask)")
    from simgrip.sweep import run as _sweep  # light: Dask, MuJoCo and matplotlib are imported when it runs

    _sweep.add_arguments(p)

    p = sub.add_parser("render", help="PNG of a settled grip and GIF of a scripted pick (pick environment)",
                       description="Writes only the files asked for: --png alone writes only the PNG, --gif alone "
                       "only the GIF; with neither, both, as grip.png and pick.gif in the current folder. Each "
                       "must be a new or regular file (a symbolic link is followed, the link kept); a folder, "
                       "FIFO, device or socket, or one file for both, is refused before any rendering (exit 2).")
    p.add_argument("--grip", default="I", help="I (pinch) or III (cradle) [default I]")
    p.add_argument("--seed", type=int, default=0, help="episode seed [default 0]")
    p.add_argument("--png", default=None, help="write the PNG of the settled grip here "
                   "[default: grip.png, only when --gif is not given either]")
    p.add_argument("--gif", default=None, help="write the GIF of the scripted pick here "
                   "[default: pick.gif, only when --png is not given either]")

    p = sub.add_parser("figures", help="write the paper's figures (Figs. 6-16) as PNG files")
    from simgrip import figures as _figures  # light: matplotlib/mujoco are imported inside its functions

    _figures.add_arguments(p)
    return parser


def _params(args) -> DimensionlessParams:
    return DimensionlessParams(D=args.D, M=args.M, b=args.b, mu_s=args.mu, gamma=args.gamma)


def _profile(args, grip: str):
    """The curvature profile of ``--profile`` and its options; ValueError naming an option the profile does not
    read (an audit found ``--kappa`` ignored by the concentrated profile, ``--sign`` by the uniform one)."""
    kind = str(args.profile).strip().lower()
    if kind == "uniform":
        if args.kappa is None:
            raise ValueError("kappa is required for the uniform profile (--kappa K)")
        given = [o for o, v in (("--kappa-max", args.kappa_max), ("--alpha", args.alpha), ("--sign", args.sign))
                 if v is not None]
        if given:
            raise ValueError(f"{given[0]}: only with --profile concentrated (the uniform profile has --kappa alone)")
        return Uniform(args.kappa)
    if kind == "concentrated":
        if args.kappa is not None:
            raise ValueError("kappa: the concentrated profile takes --kappa-max, --alpha and --sign, not --kappa")
        sign = args.sign if args.sign is not None else (1 if grip == "II" else -1)
        if sign not in (-1, 1):
            raise ValueError(f"sign (p of eq. 34) must be -1 or +1, got {sign!r}")
        return Concentrated(kappa_max=6.0 if args.kappa_max is None else args.kappa_max,
                            alpha=2.0 if args.alpha is None else args.alpha, p=sign)
    raise ValueError(f"profile must be 'uniform' or 'concentrated', got {args.profile!r}")


def _links(value) -> int:
    """``--links`` as an int in ``[2, MAX_LINKS]`` (:func:`simgrip.params.check_link_count`)."""
    from simgrip.chain import check_link_count

    return check_link_count(value)


def _progress(args, links: int):
    """Progress lines on stderr (:class:`simgrip.progress.StderrProgress`) for a model whose build and settle
    take seconds (see :data:`SLOW_LINKS`), else None (silent)."""
    from simgrip.progress import StderrProgress

    fingers = getattr(args, "fingers", None) or 1
    return StderrProgress(f"simgrip {args.command}") if fingers * links ** 3 > SLOW_LINKS ** 3 else None


def _seed(value) -> int:
    """A seed: a non-negative integer (NumPy's and Gymnasium's generators refuse negative ones)."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"seed must be a non-negative integer, got {value!r}")
    return value


def _cmd_solve(args) -> dict:
    from simgrip.report import solve_record


    grip = check_grip(args.grip)
    if args.contact == "full":
        from simgrip.reference.full_contact import full_contact_record

        return full_contact_record(grip, _params(args), _profile(args, grip))
    if args.contact != "point":
        raise ValueError(f"contact must be point or full for solve, got {args.contact!r}")
    if args.K > MAX_K:
        raise ValueError(f"K must be at most {MAX_K}, got {args.K!r} (the stability check's error is ~1e-8 there)")
    return solve_record(grip, _params(args), _profile(args, grip), K=args.K)


def _cmd_simulate(args) -> dict:
    from simgrip.compare import settled_record, simulate


    grip = check_grip(args.grip)
    params, links = _params(args), _links(args.links)
    gripper = _gripper_arguments(args, grip)
    if gripper is not None:
        from simgrip.gripper import gripper_record, simulate_gripper

        profile = gripper.pop("profile")
        state = simulate_gripper(grip, params, profile, links, progress=_progress(args, links), **gripper)
        return gripper_record(state, params, profile)
    profile = _profile(args, grip)
    return settled_record(simulate(grip, params, profile, links, method=args.method,
                                   target_error=args.target_error, contact=args.contact,
                                   progress=_progress(args, links), **_grasp_options(args, grip)),
                          params, profile)


def _grasp_options(args, grip: str) -> dict:
    """``--box-depth`` and ``--extra-friction`` as ``box_depth``/``extra_friction`` keywords of the full-contact
    scene (none given: {}); ValueError naming the option."""
    depth, extra = getattr(args, "box_depth", None), getattr(args, "extra_friction", None)
    if depth is None and extra is None:
        return {}
    if args.contact != "full":
        raise ValueError(f"{'--box-depth' if depth is not None else '--extra-friction'}: needs --contact full")
    from simgrip.sim.full_contact import check_grasp

    try:
        depth, extra = check_grasp(grip, "full", depth, None if extra is None else extra == "on")
    except ValueError as exc:
        raise ValueError(f"--{str(exc).replace('_', '-', 1)}") from None
    return {"box_depth": depth, "extra_friction": extra}


def _gripper_arguments(args, grip: str) -> dict | None:
    """The K-finger options of simulate/compare checked, as keywords of ``simulate_gripper`` (with ``profile``);
    None when none is given (the planar finger)."""
    per_finger = args.kappa_per_finger is not None
    if (args.fingers is not None or args.workpiece is not None or args.contact_angle is not None or per_finger
            or args.offset is not None or args.workpiece_yaw is not None):
        from simgrip.gripper.scene import uniform_profiles

        from simgrip.gripper.symmetry import GRIPPER_METHODS

        profile = None if per_finger else _profile(args, grip)

        if args.method is not None and args.method not in GRIPPER_METHODS:
            raise ValueError(f"method: a K-finger gripper (--fingers) settles by {' or '.join(GRIPPER_METHODS)} "
                             f"(no newton: that is the planar finger's), got {args.method!r}")
        if args.target_error is not None:
            raise ValueError("method: --target-error extrapolates the planar finger's settle; a K-finger gripper "
                             "(--fingers) has none")
        if args.fingers is None:
            raise ValueError("fingers: --workpiece, --contact-angle, --offset, --workpiece-yaw and --kappa-per-finger "
                             "need --fingers K")
        for option in ("box_depth", "extra_friction"):  # (the planar finger's full-contact scene's; an audit found
            if getattr(args, option, None) is not None:  # them ignored with --fingers)
                raise ValueError(f"--{option.replace('_', '-')}: the planar finger's --contact full only, not with "
                                 f"--fingers")
        if per_finger:
            if args.kappa is not None:
                raise ValueError("kappa_per_finger: give --kappa-per-finger or --kappa, not both")
            profile = list(uniform_profiles(args.kappa_per_finger, args.fingers))
        yaw_deg = 0.0 if args.workpiece_yaw is None else args.workpiece_yaw
        if not math.isfinite(yaw_deg):
            raise ValueError(f"workpiece_yaw must be finite (degrees), got {yaw_deg!r}")
        beta_deg = 0.0 if args.contact_angle is None else args.contact_angle
        if not (math.isfinite(beta_deg) and abs(beta_deg) < 90.0):
            raise ValueError(f"contact_angle must lie in (-90, 90) degrees, got {beta_deg!r}")
        return dict(profile=profile, fingers=args.fingers, workpiece=args.workpiece or "cylinder",
                    contact_angle=math.radians(beta_deg),
                    offset=args.offset if args.offset is not None else (0.0, 0.0),
                    workpiece_yaw=math.radians(yaw_deg), method=args.method or "auto", contact=args.contact)
    return None


def _cmd_modes(args):
    from simgrip.modes import modes
    from simgrip.modes.report import format_modes

    grip = check_grip(args.grip)
    params, links = _params(args), _links(args.links)
    profile = _profile(args, grip)
    dofs = links - (0 if grip == "free" else 1)
    if isinstance(args.count, bool) or args.count < 1 or args.count > dofs:
        raise ValueError(f"count must be a positive integer at most {dofs} (the degrees of freedom of {links} "
                         f"links{'' if grip == 'free' else ' holding the workpiece'}), got {args.count!r}")
    if args.fingers is not None or args.workpiece is not None:
        from simgrip.modes.gripper import gripper_modes
        from simgrip.modes.report import format_gripper_modes

        if args.fingers is None:
            raise ValueError("fingers: --workpiece needs --fingers K")
        rec = gripper_modes(grip, params, profile, links, fingers=args.fingers, workpiece=args.workpiece or "cylinder",
                            count=args.count, method=args.method, contact=args.contact, progress=_progress(args, links))
        return json.dumps(rec, allow_nan=False) if args.json else format_gripper_modes(rec)
    result = modes(grip, params, profile, links, count=args.count, method=args.method, contact=args.contact,
                   progress=_progress(args, links))
    return json.dumps(result.record(), allow_nan=False) if args.json else format_modes(result)


def _cmd_compare(args) -> str:
    from simgrip.compare import compare
    from simgrip.io import to_jsonable
    from simgrip.report import format_comparison

    grip = check_grip(args.grip)
    params, links = _params(args), _links(args.links)
    gripper = _gripper_arguments(args, grip)
    if gripper is not None:
        from simgrip.gripper.compare import compare_gripper

        result = compare_gripper(grip, params, gripper.pop("profile"), links, progress=_progress(args, links),
                                 **gripper)
    else:
        result = compare(grip, params, _profile(args, grip), links, method=args.method,
                         target_error=args.target_error, contact=args.contact, progress=_progress(args, links),
                         **_grasp_options(args, grip))
    if args.json:
        return json.dumps(to_jsonable(result), allow_nan=False)
    if gripper is None:  # the centreline and the contact list are --json's
        return format_comparison({**result, "simulation": {k: v for k, v in result["simulation"].items()
                                                           if k not in ("nodes", "contacts")}})
    sim = {k: v for k, v in result["simulation"].items() if k != "fingers"}  # one line per finger below instead
    lines = [f"finger {f['finger']}: N {f['normal_force']:.5g}"
             + ("" if f["relative_difference"] is None else f" ({100 * f['relative_difference']:+.2g} % of the BVP's)")
             for f in result["fingers"]]
    return format_comparison({**result, "simulation": sim}) + "\n" + "\n".join(lines)


def _cmd_render(args):
    from simgrip.envs.rendering import render_grip_png, render_pick_gif
    from simgrip.sim.gl import choose_backend

    choose_backend()  # headless: EGL, then OSMesa (RenderingUnavailable, exit 1, says what it tried)

    seed = _seed(args.seed)
    outputs = _render_outputs(args)  # only what was asked for (both defaults when nothing was)
    if "--png" in outputs:
        render_grip_png(outputs["--png"], grip=args.grip, seed=seed)
    if "--gif" in outputs:
        render_pick_gif(outputs["--gif"], grip=args.grip, seed=seed)
    return [str(path) for path in outputs.values()]


def _cmd_bench(args) -> dict:
    from simgrip.harness.bench import cli_bench

    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {args.jobs!r}")
    if args.jobs is not None:  # at most 2 per core and what memory holds (a note), refused above MAX_JOBS
        from simgrip.sweep.budget import MAX_JOBS, cap_jobs

        args.jobs, why = cap_jobs(args.jobs, MAX_JOBS)
        if why:
            print(f"simgrip bench: {why}", file=sys.stderr, flush=True)
    return cli_bench(args)


def _cmd_stress(args) -> dict:
    from simgrip.harness.stress import cli_stress

    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {args.jobs!r}")
    if args.cases < 1:
        raise ValueError(f"cases must be a positive integer, got {args.cases!r}")
    _seed(args.seed)
    return cli_stress(args)


def _cmd_sweep(args):
    from simgrip.sweep.run import cli_sweep

    return cli_sweep(args)


def _cmd_figures(args):
    from simgrip.figures import cli_figures

    return [str(path) for path in cli_figures(args)]


def _print(result, as_json: bool) -> None:
    """Print what a command returned: a record (table or JSON), a text, or lines (e.g. files written)."""
    from simgrip.io import to_jsonable
    from simgrip.report import format_table

    if result is None:
        return
    if isinstance(result, str):
        print(result)
    elif isinstance(result, (list, tuple)):
        for line in result:
            print(line)
    elif as_json or any(isinstance(v, (dict, list)) and k != "params" for k, v in result.items()
                        if k not in ("tip", "contact", "warnings", "nodes", "contacts")):
        print(json.dumps(to_jsonable(result), allow_nan=False, indent=None if as_json else 2))
    else:
        from simgrip.contact_report import brief_record
        print(format_table(brief_record(result)))


COMMANDS = {
    "solve": _cmd_solve,
    "simulate": _cmd_simulate,
    "compare": _cmd_compare,
    "modes": _cmd_modes,
    "figures": _cmd_figures,
    "render": _cmd_render,
    "bench": _cmd_bench,
    "stress": _cmd_stress,
    "sweep": _cmd_sweep,
}


#: Commands that do not import MuJoCo up front: render chooses its GL backend first (named error).  (solve imports it
#: too: its validity check builds the simulation's solids, :func:`simgrip.report.reference_validity`.)
_NO_MUJOCO_IMPORT = ("render",)


def _signals_as_interrupt(on_stuck=None):
    """Within the block, SIGINT and SIGTERM raise ``KeyboardInterrupt`` (main thread only), and with
    ``on_stuck`` a watchdog ends a run whose main thread is inside a long C call: see
    :func:`simgrip.interrupt.signals_as_interrupt`."""
    from simgrip.interrupt import signals_as_interrupt

    return signals_as_interrupt(on_stuck)


def _command_name(argv: list[str]) -> str:
    return next((a for a in argv if a in COMMANDS), "")


def _quiet_stdout() -> None:
    """Point stdout at /dev/null after a broken pipe, so that the interpreter's final flush stays quiet."""
    import os

    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _say_interrupted(prefix: str, detail: str = "") -> None:
    """The one line of an interrupted run on stderr (off a progress bar's line on a terminal); ``detail``, what
    the command adds (a ``KeyboardInterrupt``'s message: sweep's saved points), after a semicolon."""
    with contextlib.suppress(OSError, ValueError):
        start = "\n" if sys.stderr.isatty() else ""
        sys.stderr.write(f"{start}{prefix}: interrupted{'; ' + detail if detail else ''}\n")
        sys.stderr.flush()


def main(argv=None) -> int:
    """Entry point of the ``simgrip`` command; returns the exit status.

    0: done; 1: a solver or the cluster failed (named); 2: bad input (named);
    130: interrupted (Ctrl-C or SIGTERM), within 2 s of the signal even when
    the main thread is inside one long C call (MuJoCo's compile of a large
    model): a watchdog (:mod:`simgrip.interrupt`) then cleans up, prints the
    same one line, stops the run's worker processes and ends the process.
    """
    import os

    import simgrip.io  # noqa: F401  (now: the watchdog's clean-up must not wait on an import of the main thread)
    from simgrip.interrupt import Finish, kill_descendants

    argv = list(sys.argv[1:] if argv is None else argv)
    command = _command_name(argv)
    prefix = f"simgrip {command}" if command else "simgrip"
    outputs: dict[str, list[Path]] = {"folders": [], "created": []}  # read by the watchdog's clean-up too
    finish = Finish()

    def on_stuck(signum: int) -> None:  # watchdog thread: the main thread is inside a long C call
        if not finish.claim():
            return
        with contextlib.suppress(Exception):
            _clean_after_interrupt(outputs["folders"], outputs["created"])
        _say_interrupted(prefix)
        with contextlib.suppress(Exception):
            kill_descendants()
        os._exit(EXIT_INTERRUPTED)

    with _signals_as_interrupt(on_stuck) as received:
        try:
            try:
                parser = build_parser()
                args = parser.parse_args(argv)
            except SystemExit as exc:  # --help, or argparse's own message (exit 2)
                return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else EXIT_USAGE)
            try:
                outputs["folders"] = _check_outputs(args)
                outputs["created"] = [f for f in outputs["folders"] if not f.exists()]
                if args.command not in _NO_MUJOCO_IMPORT:
                    from simgrip.sim.gl import import_mujoco

                    # a broken MUJOCO_GL must not stop work that does not render; warnings not into ./MUJOCO_LOG.TXT
                    mujoco = import_mujoco()
                    from simgrip.sim.checks import stderr_printer

                    mujoco.set_mju_user_warning(stderr_printer(prefix))
                result = COMMANDS[args.command](args)
            except BrokenPipeError:  # a command that prints as it goes (sweep's paths), piped into head: not ours
                _quiet_stdout()
                return 0
            except ValueError as exc:
                if received.signum is not None:
                    raise  # what an interrupt became on its way up: the handler below
                _drop_empty(outputs["created"])
                print(f"{prefix}: error: {exc}", file=sys.stderr)
                return EXIT_USAGE
            except RuntimeError as exc:  # ElasticaError, DiscreteError, SettleError, RunnerError: named, never silent
                if received.signum is not None:
                    raise
                _drop_empty(outputs["created"])
                print(f"{prefix}: failed: {type(exc).__name__}: {exc}", file=sys.stderr)
                return EXIT_FAILED
            try:
                _print(result, getattr(args, "json", False))
                sys.stdout.flush()
            except BrokenPipeError:  # e.g. piped into head: not an error of ours
                _quiet_stdout()
            return 0
        except BaseException as exc:
            # a signal seen, whatever it became on its way up (an import cut short raises ImportError): interrupted
            if not isinstance(exc, KeyboardInterrupt) and (received.signum is None or isinstance(exc, SystemExit)):
                raise
            if not finish.claim():  # the watchdog is cleaning up and ends the process
                threading.Event().wait()
            # a second Ctrl-C or SIGTERM must not cut the clean-up short
            previous = {sig: signal.signal(sig, signal.SIG_IGN) for sig in (signal.SIGINT, signal.SIGTERM)}
            try:
                _clean_after_interrupt(outputs["folders"], outputs["created"])
                _say_interrupted(prefix, str(exc) if isinstance(exc, KeyboardInterrupt) else "")
            finally:
                for sig, handler in previous.items():
                    signal.signal(sig, handler)
            return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
