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

__all__ = ["atomic_write", "check_output_dir", "write_json", "to_jsonable"]


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "w") -> Iterator:
    """Open a temporary file next to ``path``; on success move it over ``path``, on error delete it.

    ``mode`` is ``"w"`` (text) or ``"wb"`` (binary).  Parent folders are created.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
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


def check_output_dir(path: str | os.PathLike, option: str = "--out") -> Path:
    """Check, before any work, that result files can be written in the folder ``path``.

    Returns ``path`` as a :class:`~pathlib.Path`; nothing is created (the writers
    create missing folders).  Raises ``ValueError`` naming ``option`` when
    ``path`` is empty, is an existing file, has a file among its parents, or when
    its nearest existing folder is not writable (tested by really creating and
    deleting a file there, which also catches read-only file systems and root).
    """
    if path is None or str(path).strip() == "":
        raise ValueError(f"{option} must name a folder, got {path!r}")
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{option} {str(folder)!r} is an existing file, not a folder")
    existing = folder.absolute()
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise ValueError(f"{option} {str(folder)!r} cannot be created: {str(existing)!r} is a file")
    try:
        fd, probe = tempfile.mkstemp(prefix=".simgrip-write-check.", dir=existing)
    except OSError as exc:
        raise ValueError(f"{option} {str(folder)!r} is not writable ({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(probe)
    return folder


def check_output_file(path: str | os.PathLike, option: str) -> Path:
    """Check that the file ``path`` can be written (its folder is created if needed).

    Raises ``ValueError`` naming ``option`` when ``path`` is empty, is an existing
    folder, or its folder cannot be created or written (see :func:`check_output_dir`).
    """
    if path is None or str(path).strip() == "":
        raise ValueError(f"{option} must name a file, got {path!r}")
    target = Path(path)
    if target.is_dir():
        raise ValueError(f"{option} {str(target)!r} is an existing folder, not a file")
    check_output_dir(target.parent, option)
    return target
