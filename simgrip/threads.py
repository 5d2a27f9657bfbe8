"""Run numpy's and scipy's OpenBLAS with a given number of threads (a context manager).

The settle's Newton steps solve small dense systems (``n + a few`` unknowns);
multithreaded OpenBLAS on a busy machine makes them up to 30x slower at
``n >= 128`` (its threads spin waiting for a core), so :func:`simgrip.settle.settle`,
the bench and the stress run compute single-threaded.
"""

from __future__ import annotations

import functools
import os

__all__ = ["blas_threads"]


@functools.lru_cache(maxsize=1)
def _openblas_libs_cached() -> tuple:
    import ctypes
    import glob
    import importlib.util

    out = []
    for pkg in ("numpy", "scipy"):
        spec = importlib.util.find_spec(pkg)
        if spec is None or not spec.submodule_search_locations:
            continue
        root = os.path.dirname(list(spec.submodule_search_locations)[0])
        for path in glob.glob(os.path.join(root, f"{pkg}.libs", "*openblas*.so*")):
            try:
                lib = ctypes.CDLL(path)
            except OSError:  # pragma: no cover
                continue
            for prefix in ("scipy_openblas", "openblas"):
                for suffix in ("64_", ""):
                    get = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                    put = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                    if get is not None and put is not None:
                        out.append((get, put))
                        break
                else:
                    continue
                break
    return tuple(out)


def _openblas_libs():
    """ctypes handles ``(get, set)`` of the OpenBLAS copies numpy and scipy ship (``[]`` when none is found)."""
    return list(_openblas_libs_cached())


class blas_threads:
    """Context manager: run with ``k`` BLAS threads in numpy's and scipy's OpenBLAS.

    The previous thread counts are restored on exit (nesting is fine).  A
    no-op where OpenBLAS is not found.
    """

    def __init__(self, k: int = 1):
        self.k = int(k)
        self.saved = []

    def __enter__(self):
        for get, put in _openblas_libs():
            self.saved.append((put, get()))
            put(self.k)
        return self

    def __exit__(self, *exc):
        for put, old in reversed(self.saved):
            put(old)
        self.saved = []
        return False
