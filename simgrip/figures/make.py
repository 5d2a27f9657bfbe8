"""Compute, draw and write the figures as PNG files (``simgrip figures``).

Each figure is one task of :func:`simgrip.parallel.runner.run_tasks` (the
slowest first); a figure's numbers do not depend on the others, so the files do
not depend on ``jobs``.  The output folder is checked before any work.
"""

from __future__ import annotations

import sys
from pathlib import Path

from simgrip.figures.catalog import (COST, FIGURES, FULL_CONTACT_FIGURES, GRIPPER_FIGURES, OVERLAY_FIGURES,
                                     RENDERED_FIGURES, figure_key)

__all__ = ["make_figures", "add_arguments", "cli_figures"]


def _render(task: tuple) -> str:
    """Compute, plot and write one figure: ``task = (name, out_dir, simulate, links)`` (runs in a worker); its
    path, or ``(path, note)`` where an overlay's settle failed (the note for stderr).

    With ``simulate``, figures 6-9 get :func:`simgrip.figures.simulation_overlay` (``links`` links).
    The K-finger figures are :func:`simgrip.figures.gripper.make_gripper_figure`'s.
    """
    name, out_dir, simulate, links = task
    if name in GRIPPER_FIGURES:
        from simgrip.figures.gripper import make_gripper_figure

        return str(make_gripper_figure(name, out_dir, simulate=simulate))
    if name == "wrap_grasp":  # its own links (32)
        from simgrip.figures.wrap_grasp import make_wrap_grasp_figure

        return str(make_wrap_grasp_figure(out_dir))
    if name in FULL_CONTACT_FIGURES:  # its own links (32): --links is Figs. 6-9's
        from simgrip.figures.full_contact import make_full_contact_figure

        return str(make_full_contact_figure(name, out_dir, simulate=simulate))
    from simgrip.figures.data import figure_data
    from simgrip.figures.overlay import simulation_overlay
    from simgrip.figures.plot import plot_figure, save_figure

    data = figure_data(name)
    overlay = simulation_overlay(name, links=links) if simulate and name in OVERLAY_FIGURES else None
    path = str(save_figure(plot_figure(name, data, overlay=overlay), Path(out_dir) / f"{name}.png"))
    failed = [] if overlay is None else [float(k) for k, f in zip(overlay["kappa"], overlay["failed"]) if f]
    if failed:  # said on stderr too (make_figures), not only in the figure's legend
        return path, f"{name}: the settle failed at kappa_bar = {', '.join(f'{k:g}' for k in failed)} " \
                     f"({links} links; drawn as red crosses)"
    return path


def make_figures(out_dir, *, which=None, jobs: int | None = None, progress: bool = True,
                 simulate: bool = True, links: int = 16, options=None) -> list[Path]:
    """Write the paper's figures as PNG files ``out_dir/figNN.png``.

    Parameters
    ----------
    out_dir : path
        Destination folder (created if missing; checked before any work).
    which : iterable of str or int, optional
        Figures to make (``"fig07"``, ``7``...); all of :data:`FIGURES` by default.
    jobs : int, optional
        Worker processes (default: all cores); ``1`` runs in this process.
    progress : bool
        Show a progress bar.
    simulate : bool
        Overlay the MuJoCo hinge chain's settled states on figures 6-9
        (:func:`simgrip.figures.simulation_overlay`, label ``"MuJoCo chain, n = <links>"``)
        and the settled K-finger gripper's forces on ``grip_forces``.
    links : int
        Links per finger of the simulated chain of figures 6-9 (default 16); the
        K-finger figures use :data:`simgrip.figures.gripper.LINKS` (32).
    options : simgrip.parallel.runner.RunnerOptions, optional
        How to run (e.g. on an existing Dask cluster); replaces ``jobs`` and ``progress``.

    Returns
    -------
    list of Path
        The files written, in the order of ``which``.
    """
    from simgrip.chain import check_link_count
    from simgrip.parallel.runner import RunnerOptions, run_tasks
    from simgrip.io import check_output_dir, check_output_files_in

    if which is None:
        names = list(FIGURES)
    else:
        try:
            names = [figure_key(w) for w in ([which] if isinstance(which, (str, int)) else which)]
        except TypeError:  # not iterable
            raise ValueError(f"which must be a figure name or number or a list of them, got {which!r}") from None
        except ValueError as exc:
            raise ValueError(f"which: {exc}") from None
    names = list(dict.fromkeys(names))
    options = RunnerOptions(jobs=jobs, progress=progress) if options is None else options
    links = check_link_count(links)  # [2, MAX_LINKS], as every command's --links
    out = check_output_dir(out_dir, option="out_dir")
    if any(k in RENDERED_FIGURES for k in names):
        from simgrip.sim.gl import RenderingUnavailable, choose_backend

        try:
            choose_backend()  # before any work; the workers inherit the choice
        except RenderingUnavailable as exc:
            if which is not None:  # renders asked for by name: say why they cannot be made
                raise
            names = [k for k in names if k not in RENDERED_FIGURES]  # "all" on a machine without OpenGL
            print(f"simgrip figures: skipping the renders {', '.join(RENDERED_FIGURES)} ({exc})", file=sys.stderr)
    check_output_files_in(out, [f"{k}.png" for k in names], "out_dir")  # a folder/FIFO at figNN.png: refused now
    order = sorted(names, key=lambda k: -COST.get(k, 1))
    if not options.remote:  # no more workers than figures, cores (2 each) or memory allow; refused above MAX_JOBS
        from dataclasses import replace

        from simgrip.sweep.budget import cap_jobs

        jobs, why = cap_jobs(options.jobs, len(order))
        if why:
            print(f"simgrip figures: {why}", file=sys.stderr, flush=True)
        options = options if jobs == options.jobs else replace(options, jobs=jobs)
    paths = run_tasks(_render, [(k, str(out), bool(simulate), links) for k in order],
                      options=options, desc="figures", batch_size=1)
    done = {}
    for k, got in zip(order, paths):  # a path, or (path, what failed in it)
        if isinstance(got, tuple):
            got, why = got
            print(f"simgrip figures: {why}", file=sys.stderr, flush=True)
        done[k] = got
    return [Path(done[k]) for k in names]


def add_arguments(p) -> None:
    """Add the options of ``simgrip figures`` to an argparse parser."""
    from simgrip.parallel.runner import add_runner_arguments

    p.add_argument("--out", default="figures", help="output folder [default ./figures]")
    p.add_argument("--which", nargs="+", default=None,
                   help="figures to make, e.g. 7 9 16 grasp3 grasp4 grip_forces fig07_full wrap_grasp [default: all]")
    p.add_argument("--links", type=int, default=16,
                   help="links per finger of the simulated chain overlaid on Figs. 6-9 [default 16; "
                        "the K-finger figures use 32]")
    p.add_argument("--no-simulate", action="store_true", help="reference curves only: no MuJoCo points on Figs. 6-9")
    add_runner_arguments(p)


def cli_figures(args) -> list[Path]:
    """Run ``simgrip figures`` from parsed arguments; returns the files (the CLI checked ``--out`` first)."""
    from simgrip.parallel.runner import runner_options

    return make_figures(args.out, which=args.which, simulate=not args.no_simulate, links=args.links,
                        options=runner_options(args))
