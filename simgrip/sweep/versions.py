"""The versions a sweep records beside its numbers (``simgrip sweep``'s JSON and its ``--throughput`` profile).

Both :mod:`simgrip.sweep.run` and :mod:`simgrip.sweep.profile` write them, so
they sit here, below both.
"""

from __future__ import annotations

import platform

__all__ = ["versions"]


def versions() -> dict:
    """Versions of Python and of the packages that decide a sweep's numbers and how it ran."""
    from importlib import metadata

    out = {"python": platform.python_version()}
    for pkg in ("simgrip", "mujoco", "numpy", "scipy", "dask", "distributed"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out
