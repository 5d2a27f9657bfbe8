"""Results files, written whole or not at all.

Every file simgrip writes (JSON, CSV, PNG, GIF) goes through :func:`atomic_write`:
the content is written to a temporary file in the destination folder and moved
into place with :func:`os.replace`, so an interrupted run never leaves a
half-written result behind.

Commands that write results check their destination *before* any work with
:func:`check_output_dir` (a folder, e.g. ``--out``) or :func:`check_output_file`
(a file, e.g. ``--png``): a path that is an existing file, cannot be created or
is not writable raises ``ValueError`` naming the option, so a bad path costs
nothing instead of a traceback after minutes of computing.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Iterator

import numpy as np

__all__ = ["atomic_write", "check_output_dir", "check_output_file", "remove_partial_files", "write_json", "to_jsonable"]


#: Name prefix of :func:`atomic_write`'s temporary files (what :func:`remove_partial_files` looks for).
TEMP_PREFIX = ".simgrip-partial."


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "w") -> Iterator:
    """Open a temporary file next to ``path``; on success move it over ``path``, on error delete it.

    ``mode`` is ``"w"`` (text) or ``"wb"`` (binary).  Parent folders are created.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; results are ordinary files
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def check_output_dir(path: str | os.PathLike, option: str = "--out", *, create: bool = True) -> Path:
    """Make sure ``path`` is a folder results can be written to, before any work is done.

    Creates the folder (and its parents) when missing and writes and deletes a
    probe file in it (which also catches read-only file systems, and works for
    root, unlike :func:`os.access`).  With ``create=False`` nothing is created:
    the probe goes into the nearest existing parent (the command line checks
    every output this way before it validates anything else).  Raises
    ``ValueError`` naming ``option`` (the command-line option or parameter that
    gave the path) when ``path`` is empty, an existing file, sits below a file,
    or cannot be written.  Returns ``path`` as a ``Path``.
    """
    if path is None or str(path).strip() == "":
        raise ValueError(f"{option} must name a folder, got {path!r}")
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise ValueError(f"{option}: {str(target)!r} is an existing file, not a folder")
    probe_dir = target
    try:
        if create:
            target.mkdir(parents=True, exist_ok=True)
        else:
            probe_dir = target.absolute()
            while not probe_dir.exists():
                probe_dir = probe_dir.parent
            if not probe_dir.is_dir():
                raise NotADirectoryError(20, f"{str(probe_dir)!r} is a file")
        with tempfile.TemporaryFile(prefix=".simgrip-probe.", dir=probe_dir):
            pass
    except OSError as exc:
        raise ValueError(f"{option}: cannot write results to {str(target)!r} ({exc.strerror or exc})") from None
    return target


def check_output_file(path: str | os.PathLike, option: str, *, create: bool = True) -> Path:
    """Check that the file ``path`` can be written, before any work is done.

    Its folder is checked (and created) by :func:`check_output_dir`.  Raises
    ``ValueError`` naming ``option`` when ``path`` is empty, an existing folder,
    or its folder cannot be written.  Returns ``path`` as a ``Path``.
    """
    if path is None or str(path).strip() == "":
        raise ValueError(f"{option} must name a file, got {path!r}")
    target = Path(path)
    if target.is_dir():
        raise ValueError(f"{option}: {str(target)!r} is an existing folder, not a file")
    check_output_dir(target.parent, option, create=create)
    return target


def remove_partial_files(folder: str | os.PathLike, recursive: bool = True) -> list[Path]:
    """Delete the temporary files :func:`atomic_write` left in ``folder`` (returns them).

    A writer removes its own temporary file on any exception, but a worker
    process killed outright (``SIGKILL`` after an interrupt) cannot; the command
    line calls this on the output folders after an interrupt.  Only names
    starting with :data:`TEMP_PREFIX` and ending in ``.tmp`` are touched.
    """
    root = Path(folder)
    if not root.is_dir():
        return []
    pattern = f"{TEMP_PREFIX}*.tmp"
    found = root.rglob(pattern) if recursive else root.glob(pattern)
    removed = []
    for path in found:
        with contextlib.suppress(OSError):
            if path.is_file():
                path.unlink()
                removed.append(path)
    return removed


def to_jsonable(obj):
    """Convert NumPy scalars/arrays (recursively) to plain Python; non-finite floats become ``None``."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


def write_json(path: str | os.PathLike, data, indent: int = 2) -> None:
    """Write ``data`` as JSON atomically (see :func:`atomic_write`)."""
    text = json.dumps(to_jsonable(data), indent=indent, allow_nan=False)
    with atomic_write(path) as fh:
        fh.write(text + "\n")
