"""The command line's output paths: which files each command writes, checked before any work, and the
clean-up after an interrupt (the policy itself is :mod:`simgrip.io`'s)."""

from __future__ import annotations

import contextlib
from pathlib import Path

__all__ = ["OUTPUT_OPTIONS", "RENDER_DEFAULTS", "check_outputs", "clean_after_interrupt", "drop_empty", "render_outputs"]

#: Output options and whether each names a folder (True) or a file (False), checked before any work.
OUTPUT_OPTIONS = {"out": ("--out", True), "png": ("--png", False), "gif": ("--gif", False)}
#: render's files when neither --png nor --gif is given (with either, only the ones given are written).
RENDER_DEFAULTS = {"--png": "grip.png", "--gif": "pick.gif"}


def render_outputs(args) -> dict[str, str]:
    """render's files as ``{option: path}``: those given, or :data:`RENDER_DEFAULTS` when neither is."""
    given = {option: getattr(args, option[2:]) for option in RENDER_DEFAULTS}
    given = {option: path for option, path in given.items() if path is not None}
    return given or dict(RENDER_DEFAULTS)


def check_outputs(args) -> list[Path]:
    """Check every output path of the command before any work (nothing is created); returns the folders.

    The one check of ``--out`` (bench, stress, figures, sweep, ...) and of
    render's ``--png``/``--gif`` (the files it will write, defaults included),
    under :mod:`simgrip.io`'s output-path policy: ``ValueError`` naming the
    option when a path is of the wrong kind (a file where a folder belongs; a
    folder, FIFO, device or socket where a file belongs), cannot be written, or
    when two outputs are one file.
    """
    from simgrip.io import check_distinct_outputs, check_output_dir, check_output_file, check_output_files_in

    folders = []
    files = render_outputs(args) if args.command == "render" else {}
    for attr, (option, is_dir) in OUTPUT_OPTIONS.items():
        value = getattr(args, attr, None)
        if value is None or option in files:
            continue
        if is_dir:
            folders.append(check_output_dir(value, option, create=False))
            check_output_files_in(value, _files_in_out(args), option)  # e.g. a folder or FIFO at OUT/bench.csv
        else:
            files[option] = value
    for option, value in files.items():
        folders.append(check_output_file(value, option, create=False).parent)
    check_distinct_outputs(files)
    return folders


def _files_in_out(args) -> list[str]:
    """The files bench, stress and figures will write into ``--out``, as far as known before any work.

    (The sweep checks its own, naming ``--out``; the libraries check theirs too, naming ``out_dir``.)
    """
    if args.command == "bench":
        from simgrip.harness.bench import OUTPUT_FILES

        return list(OUTPUT_FILES)
    if args.command == "stress":
        from simgrip.harness.stress import OUTPUT_FILES

        return list(OUTPUT_FILES)
    if args.command == "figures":
        from simgrip.figures.catalog import FIGURES, figure_key

        try:
            return [f"{figure_key(w)}.png" for w in args.which] if args.which else [f"{k}.png" for k in FIGURES]
        except ValueError:  # an unknown figure: the command names it
            return []
    return []


def clean_after_interrupt(folders: list[Path], created: list[Path]) -> None:
    """Remove partial files (of workers killed mid-write) and output folders this run created and left empty."""
    from simgrip.io import remove_partial_files

    for folder in folders:
        remove_partial_files(folder, recursive=folder not in (Path("."), Path.cwd()))
    for folder in created:
        with contextlib.suppress(OSError):
            folder.rmdir()  # only if empty


def drop_empty(created: list) -> None:
    """Remove the output folders this run created that are still empty (a run that failed leaves nothing behind:
    an audit found an empty ``--out`` after a scheduler that was not reached)."""
    for folder in created:
        with contextlib.suppress(OSError):  # (not empty, gone, or not ours to remove: left as it is)
            folder.rmdir()
