"""Results files, written whole or not at all, and never over anything but a regular file.

Every file simgrip writes (JSON, CSV, PNG, GIF) goes through :func:`atomic_write`:
the content is written to a temporary file in the destination folder and moved
into place with :func:`os.replace`, so an interrupted run never leaves a
half-written result behind.

The output-path policy (one for every command, the examples and the library):

* **Only regular files are replaced.**  An existing target that is a folder, a
  FIFO (named pipe), a character or block device (``/dev/null``) or a socket is
  refused with :class:`OutputPathError` (a ``ValueError``) naming the option or
  parameter: a rename over it would destroy it (as root, ``render --png
  /dev/null`` used to replace the machine's ``/dev/null`` with a PNG).
  :func:`atomic_write` checks when it opens *and again right before*
  :func:`os.replace`, so a target that became a FIFO or a device meanwhile is
  not replaced either (what is left is the instant between that ``lstat`` and
  the rename, which no portable call closes).
* **A symbolic link is followed, never replaced**: the result is written over
  the regular file the link points to (through any chain of links), and the link
  stays.  A link to something that is not a regular file is refused as above; a
  link that points nowhere (dangling) or into a loop is refused, since following
  it would create a file at a place the user may not expect.
* **Two outputs of one command may not be one file** (:func:`check_distinct_outputs`):
  ``render --png P --gif P``, also as ``./P`` and ``P``, a link to ``P`` or a
  hard link, is refused instead of the second write silently replacing the first.
* **Checked before any work**: commands check their destinations first with
  :func:`check_output_dir` (a folder, e.g. ``--out``), :func:`check_output_file`
  (a file, e.g. ``--png``) and :func:`check_output_files_in` (the files a
  command will write into its ``--out`` folder, where their names are known up
  front), so a bad path costs nothing instead of a traceback after minutes of
  computing.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
import tempfile
from pathlib import Path
from typing import Iterable, Iterator, Mapping

import numpy as np

__all__ = [
    "OutputPathError",
    "atomic_write",
    "check_distinct_outputs",
    "check_output_dir",
    "check_output_file",
    "check_output_files_in",
    "remove_partial_files",
    "resolve_output_file",
    "to_jsonable",
    "write_json",
]


#: Name prefix of :func:`atomic_write`'s temporary files (what :func:`remove_partial_files` looks for).
TEMP_PREFIX = ".simgrip-partial."


class OutputPathError(ValueError):
    """An output path simgrip refuses to write (not a regular file, a clash, not writable); names the option."""


def _kind(mode: int) -> str:
    """What a non-regular file is, in words (for the messages)."""
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _empty(path) -> bool:
    return path is None or str(path).strip() == ""


def resolve_output_file(path: str | os.PathLike, option: str = "path") -> Path:
    """The file that writing ``path`` would replace, after the policy's checks (see the module docstring).

    Returns ``path`` itself when it does not exist or is a regular file, and
    the regular file a symbolic link at ``path`` points to (all links followed).
    Raises :class:`OutputPathError` naming ``option`` when ``path`` is empty, is
    (or links to) anything but a regular file, is a dangling or looping link, or
    lies below a file.  Nothing is created or written.
    """
    if _empty(path):
        raise OutputPathError(f"{option} must name a file, got {path!r}")
    target = Path(path)
    try:
        st = os.lstat(target)
    except FileNotFoundError:
        return target
    except NotADirectoryError:
        raise OutputPathError(f"{option}: {str(target)!r} lies below something that is not a folder") from None
    except OSError as exc:
        raise OutputPathError(f"{option}: cannot use {str(target)!r} ({exc.strerror or exc})") from None
    if stat.S_ISLNK(st.st_mode):
        try:
            real = Path(os.path.realpath(target, strict=True))
            st = os.lstat(real)
        except OSError:  # ENOENT: dangling; ELOOP: a loop
            raise OutputPathError(f"{option}: {str(target)!r} is a symbolic link to a missing file (or a loop); "
                                  f"refusing to follow it") from None
        if not stat.S_ISREG(st.st_mode):
            raise OutputPathError(f"{option}: {str(target)!r} links to {str(real)!r}, which is {_kind(st.st_mode)}, "
                                  f"not a regular file; refusing to replace it")
        return real
    if not stat.S_ISREG(st.st_mode):
        raise OutputPathError(f"{option}: {str(target)!r} is {_kind(st.st_mode)}, not a regular file; "
                              f"refusing to replace it")
    return target


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "w", *, option: str = "path") -> Iterator:
    """Open a temporary file next to ``path``; on success move it over ``path``, on error delete it.

    ``mode`` is ``"w"`` (text) or ``"wb"`` (binary).  Parent folders are created.
    The output-path policy of this module applies: ``path`` must be missing or a
    regular file, or a symbolic link to one (then the file it points to is
    replaced and the link kept); it is checked before the temporary file is made
    and again right before :func:`os.replace`.  Anything else raises
    :class:`OutputPathError` naming ``option`` and leaves both the target and
    the folder as they were.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    target = resolve_output_file(path, option)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as exc:
        raise OutputPathError(f"{option}: cannot write {str(path)!r} ({exc.strerror or exc})") from None
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; results are ordinary files
        again = resolve_output_file(path, option)  # a FIFO, device or new link put there meanwhile is refused
        if again != target:
            raise OutputPathError(f"{option}: {str(path)!r} now points to {str(again)!r}, not {str(target)!r} as when "
                                  f"the write began; refusing to replace it")
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
    :class:`OutputPathError` (a ``ValueError``) naming ``option`` (the
    command-line option or parameter that gave the path) when ``path`` is empty,
    exists but is not a folder (a file, FIFO, device, socket, or a link to one),
    sits below a file, or cannot be written.  A link to a folder is a folder
    (files are written into it; the link stays).  Returns ``path`` as a ``Path``.
    """
    if _empty(path):
        raise OutputPathError(f"{option} must name a folder, got {path!r}")
    target = Path(path)
    try:
        st = os.stat(target)  # follows links: a link to a folder is a folder
    except OSError:
        st = None
    if st is not None and not stat.S_ISDIR(st.st_mode):
        what = "an existing file" if stat.S_ISREG(st.st_mode) else _kind(st.st_mode)
        raise OutputPathError(f"{option}: {str(target)!r} is {what}, not a folder")
    probe_dir = target
    try:
        if create:
            target.mkdir(parents=True, exist_ok=True)
        else:
            probe_dir = target.absolute()
            while not os.path.lexists(probe_dir):
                probe_dir = probe_dir.parent
            if not probe_dir.is_dir():
                raise NotADirectoryError(20, f"{str(probe_dir)!r} is not a folder")
        with tempfile.TemporaryFile(prefix=".simgrip-probe.", dir=probe_dir):
            pass
    except OSError as exc:
        raise OutputPathError(f"{option}: cannot write results to {str(target)!r} ({exc.strerror or exc})") from None
    return target


def check_output_file(path: str | os.PathLike, option: str, *, create: bool = True) -> Path:
    """Check that the file ``path`` can be written under the output-path policy, before any work is done.

    ``path`` itself goes through :func:`resolve_output_file` (missing, a regular
    file, or a link to one), its folder through :func:`check_output_dir`
    (created unless ``create=False``).  Raises :class:`OutputPathError` (a
    ``ValueError``) naming ``option`` otherwise.  Returns ``path`` as a ``Path``.
    """
    if _empty(path):
        raise OutputPathError(f"{option} must name a file, got {path!r}")
    real = resolve_output_file(path, option)
    check_output_dir(real.parent, option, create=create)
    return Path(path)


def check_output_files_in(folder: str | os.PathLike, names: Iterable[str], option: str = "--out") -> list[Path]:
    """Check the files a command will write into ``folder`` (an ``--out``), before any work is done.

    Each ``folder / name`` must be missing, a regular file or a link to one
    (:func:`resolve_output_file`); e.g. a folder where ``sweep.csv`` goes is
    refused now, not after every point was computed.  Raises
    :class:`OutputPathError` naming ``option`` and the file.  Returns the paths.
    The folder itself is :func:`check_output_dir`'s.
    """
    paths = [Path(folder) / name for name in names]
    for p in paths:
        resolve_output_file(p, option)
    return paths


def _identity(path: str | os.PathLike):
    """What makes two paths one file: the inode of an existing file, else the resolved absolute path."""
    try:
        st = os.stat(path)  # follows links
        return ("inode", st.st_dev, st.st_ino)
    except OSError:
        return ("path", os.path.normcase(os.path.realpath(path)))


def check_distinct_outputs(outputs: Mapping[str, str | os.PathLike]) -> None:
    """Refuse two outputs of one command at one file: ``outputs`` maps each option to its path.

    Paths are compared as files: ``P``, ``./P``, an absolute spelling, a
    symbolic or hard link to ``P`` are all ``P``.  Raises
    :class:`OutputPathError` naming both options.
    """
    seen: dict = {}
    for option, path in outputs.items():
        key = _identity(path)
        if key in seen:
            first, first_path = seen[key]
            raise OutputPathError(f"{option}: {str(path)!r} is the same file as {first} {str(first_path)!r}; "
                                  f"give each output its own path")
        seen[key] = (option, path)


def remove_partial_files(folder: str | os.PathLike, recursive: bool = True) -> list[Path]:
    """Delete the temporary files :func:`atomic_write` left in ``folder`` (returns them).

    A writer removes its own temporary file on any exception, but a worker
    process killed outright (``SIGKILL`` after an interrupt) cannot; the command
    line calls this on the output folders after an interrupt.  Only regular
    files whose names start with :data:`TEMP_PREFIX` and end in ``.tmp`` are
    touched.
    """
    root = Path(folder)
    if not root.is_dir():
        return []
    pattern = f"{TEMP_PREFIX}*.tmp"
    found = root.rglob(pattern) if recursive else root.glob(pattern)
    removed = []
    for path in found:
        with contextlib.suppress(OSError):
            if stat.S_ISREG(os.lstat(path).st_mode):
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


def write_json(path: str | os.PathLike, data, indent: int = 2, *, option: str = "path") -> None:
    """Write ``data`` as JSON atomically (see :func:`atomic_write`; ``option`` names ``path`` in its errors)."""
    text = json.dumps(to_jsonable(data), indent=indent, allow_nan=False)
    with atomic_write(path, option=option) as fh:
        fh.write(text + "\n")
