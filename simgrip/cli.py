"""The ``simgrip`` command line: a thin layer over the library.

Every command works in the paper's dimensionless units (lengths over the finger
length, forces on the rod over ``rho g l``, z up, the finger's base at the
origin).  Bad input prints one clear message naming the parameter and exits
with status 2.
"""

from __future__ import annotations

import argparse
import json
import sys

from simgrip.params import DimensionlessParams, check_grip
from simgrip.profiles import Concentrated, Uniform

__all__ = ["main", "build_parser"]

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """argparse with a consistent one-line error and exit code 2."""

    def error(self, message):  # pragma: no cover - exercised through main()
        self.print_usage(sys.stderr)
        self.exit(EXIT_USAGE, f"simgrip: error: {message}\n")


def _add_state_options(p: argparse.ArgumentParser, grips=("free", "I", "II", "III")) -> None:
    p.add_argument("grip", help=f"one of {', '.join(grips)}")
    g = p.add_argument_group("rod, workpiece and curvature (dimensionless)")
    g.add_argument("--kappa", type=float, default=None, help="uniform intrinsic curvature kappa_bar = l*kappa0 (required for --profile uniform)")
    g.add_argument("--D", type=float, default=1.0, help="bending stiffness EI/(rho g l^3) [default 1]")
    g.add_argument("--M", type=float, default=5.0, help="workpiece mass per finger m/(rho l) [default 5]")
    g.add_argument("--b", type=float, default=0.6, help="workpiece width b/l [default 0.6]")
    g.add_argument("--mu", type=float, default=1.0, help="static friction coefficient mu_s [default 1]")
    g.add_argument("--gamma", type=float, default=0.8, help="Grip III contact arc length gamma/l [default 0.8]")
    g.add_argument("--profile", default="uniform", help="curvature profile: uniform or concentrated (eq. 34)")
    g.add_argument("--kappa-max", type=float, default=6.0, help="peak |kappa_bar| of the concentrated profile [default 6]")
    g.add_argument("--alpha", type=float, default=2.0, help="concentration exponent of eq. (34) [default 2]")
    g.add_argument("--sign", type=int, default=None, help="sign p of eq. (34): -1 curls down, +1 up [default: +1 for Grip II, else -1]")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``simgrip`` command."""
    parser = _Parser(prog="simgrip", description="Soft-finger grips: elastica reference, MuJoCo simulation, figures and benchmarks.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("solve", help="solve the elastica boundary-value problem of one grip")
    _add_state_options(p)
    p.add_argument("--K", type=int, default=128, help="nodes of the discrete stability check [default 128]")

    for name, text in (
        ("simulate", "settle the MuJoCo finger (symmetric reduction) and print its state"),
        ("compare", "simulation, elastica reference and their difference side by side"),
    ):
        p = sub.add_parser(name, help=text)
        _add_state_options(p)
        p.add_argument("--links", type=int, default=32, help="links per finger [default 32]")
        p.add_argument(
            "--method", default="newton",
            help="settle method: newton (static solve, residual 1e-10) or dynamics "
            "(over-damped MuJoCo dynamics with MuJoCo's own friction) [default newton]",
        )

    p = sub.add_parser("bench", help="run time against error, naive vs settle vs minimiser vs BVP, what skipping buys")
    from simgrip.harness import bench as _bench  # light: matplotlib/mujoco are imported inside its functions

    _bench.add_arguments(p)

    p = sub.add_parser("stress", help="randomised and grid numerical stress test of settle()")
    from simgrip.harness import stress as _stress

    _stress.add_arguments(p)

    p = sub.add_parser("render", help="PNG of a settled grip and GIF of a scripted pick (pick environment)")
    p.add_argument("--grip", default="I", help="I (pinch) or III (cradle) [default I]")
    p.add_argument("--seed", type=int, default=0, help="episode seed [default 0]")
    p.add_argument("--png", default="grip.png", help="PNG of the settled grip [default grip.png]")
    p.add_argument("--gif", default="pick.gif", help="GIF of the scripted pick [default pick.gif]")

    p = sub.add_parser("figures", help="write the paper's figures (Figs. 6-16) as PNG files")
    from simgrip import figures as _figures  # light: matplotlib/mujoco are imported inside its functions

    _figures.add_arguments(p)
    return parser


def _params(args) -> DimensionlessParams:
    return DimensionlessParams(D=args.D, M=args.M, b=args.b, mu_s=args.mu, gamma=args.gamma)


def _profile(args, grip: str):
    kind = str(args.profile).strip().lower()
    if kind == "uniform":
        if args.kappa is None:
            raise ValueError("kappa is required for the uniform profile (--kappa K)")
        return Uniform(args.kappa)
    if kind == "concentrated":
        sign = args.sign if args.sign is not None else (1 if grip == "II" else -1)
        return Concentrated(kappa_max=args.kappa_max, alpha=args.alpha, p=sign)
    raise ValueError(f"profile must be 'uniform' or 'concentrated', got {args.profile!r}")


def _cmd_solve(args) -> dict:
    from simgrip.report import solve_record

    grip = check_grip(args.grip)
    return solve_record(grip, _params(args), _profile(args, grip), K=args.K)


def _cmd_simulate(args) -> dict:
    from simgrip.chain import check_links
    from simgrip.compare import settled_record, simulate

    grip = check_grip(args.grip)
    params, profile, links = _params(args), _profile(args, grip), check_links(args.links)
    return settled_record(simulate(grip, params, profile, links, method=args.method), params, profile)


def _cmd_compare(args):
    from simgrip.chain import check_links
    from simgrip.compare import compare
    from simgrip.io import to_jsonable
    from simgrip.report import format_comparison

    grip = check_grip(args.grip)
    result = compare(grip, _params(args), _profile(args, grip), check_links(args.links), method=args.method)
    print(json.dumps(to_jsonable(result), allow_nan=False) if args.json else format_comparison(result))
    return None


def _cmd_render(args):
    import os

    if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "osmesa"  # headless, CPU only
        os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
    from simgrip.envs.rendering import render_grip_png, render_pick_gif

    render_grip_png(args.png, grip=args.grip, seed=args.seed)
    render_pick_gif(args.gif, grip=args.grip, seed=args.seed)
    print(args.png)
    print(args.gif)
    return None


def _cmd_bench(args) -> dict:
    from simgrip.harness.bench import cli_bench

    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {args.jobs!r}")
    return cli_bench(args)


def _cmd_stress(args) -> dict:
    from simgrip.harness.stress import cli_stress

    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {args.jobs!r}")
    if args.cases < 1:
        raise ValueError(f"cases must be a positive integer, got {args.cases!r}")
    return cli_stress(args)


def _cmd_figures(args):
    from simgrip.figures import cli_figures

    for path in cli_figures(args):
        print(path)
    return None


def _print(record: dict, as_json: bool) -> None:
    from simgrip.io import to_jsonable
    from simgrip.report import format_table

    if as_json or any(isinstance(v, (dict, list)) and k != "params" for k, v in record.items() if k not in ("tip", "contact", "warnings")):
        print(json.dumps(to_jsonable(record), allow_nan=False, indent=None if as_json else 2))
    else:
        print(format_table(record))


COMMANDS = {
    "solve": _cmd_solve,
    "simulate": _cmd_simulate,
    "compare": _cmd_compare,
    "figures": _cmd_figures,
    "render": _cmd_render,
    "bench": _cmd_bench,
    "stress": _cmd_stress,
}


def main(argv=None) -> int:
    """Entry point of the ``simgrip`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        record = COMMANDS[args.command](args)
    except ValueError as exc:
        print(f"simgrip {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except RuntimeError as exc:  # ElasticaError, DiscreteError, SettleError: named, never silent
        print(f"simgrip {args.command}: failed: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    try:
        if record is not None:
            _print(record, getattr(args, "json", False))
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into head: not an error of ours
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
