"""simgrip: fast, theory-checked simulation of soft pneumatic robot fingers.

Data flows one way: parameters and curvature profile -> scene (MjSpec) ->
settle -> settled state -> comparison with the elastica reference.
"""

import sys as _sys


def _quiet_interrupt_while_the_command_starts() -> None:
    """In the ``simgrip`` command only (its console script is the main program): a Ctrl-C while the command's
    modules are still importing (NumPy, Gymnasium: ~0.2-0.5 s, before :func:`simgrip.cli.main` takes the signals
    over) prints ``simgrip: interrupted`` and exits with status 130, as later, instead of an import traceback.
    Nothing has started then (no worker, no output).  A program that merely imports simgrip is left alone."""
    import os
    import signal

    main = _sys.modules.get("__main__")
    script = getattr(main, "__file__", None) or ""
    if getattr(main, "__name__", None) != "__main__" or getattr(main, "__spec__", None) is not None \
            or not _sys.argv or not script:  # (a worker spawned by the command runs it as __mp_main__: not ours)
        return
    if os.path.basename(script) not in ("simgrip", "simgrip-script.py", "simgrip.exe") or os.path.abspath(
            script) != os.path.abspath(_sys.argv[0]):
        return
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:  # someone else's handler: theirs
        return

    def interrupted(signum, frame):
        try:
            _sys.stderr.write("simgrip: interrupted\n")
            _sys.stderr.flush()
        finally:
            os._exit(130)  # 128 + SIGINT, as simgrip.cli.EXIT_INTERRUPTED

    signal.signal(signal.SIGINT, interrupted)


_quiet_interrupt_while_the_command_starts()

import importlib.util as _ilu  # noqa: E402 - after the interrupt handler above, the first thing the command does
from pathlib import Path as _Path  # noqa: E402


def _map_source_checkout() -> None:
    """Make ``simgrip.models`` / ``simgrip.envs`` importable from a source checkout.

    pyproject's ``package-dir`` maps the top-level ``models/`` and ``envs/``
    folders to these subpackages in an installed copy.  When this file is
    imported straight from a checkout (e.g. ``python -m simgrip.cli`` in the
    repository root, where the folder shadows an installed copy), map them the
    same way; an installed copy already has them and is left alone.
    """
    here = _Path(__file__).resolve().parent
    root = here.parent
    if not (root / "pyproject.toml").is_file():
        return
    for name in ("models", "envs"):
        full = f"{__name__}.{name}"
        init = root / name / "__init__.py"
        if full in _sys.modules or (here / name).exists() or not init.is_file():
            continue
        if _ilu.find_spec(full) is not None:  # an editable install's finder maps it already
            continue
        spec = _ilu.spec_from_file_location(full, init, submodule_search_locations=[str(root / name)])
        module = _ilu.module_from_spec(spec)
        _sys.modules[full] = module
        spec.loader.exec_module(module)
        globals()[name] = module


_map_source_checkout()

from simgrip.params import GRIPS, STANDARD, DimensionlessParams, PhysicalParams, check_grip
from simgrip.profiles import Concentrated, CurvatureProfile, Uniform, UserProfile, as_profile

__version__ = "0.1.0"

__all__ = [
    "GRIPS",
    "STANDARD",
    "DimensionlessParams",
    "PhysicalParams",
    "check_grip",
    "Concentrated",
    "CurvatureProfile",
    "Uniform",
    "UserProfile",
    "as_profile",
]



def __getattr__(name: str):
    """``from simgrip import elastica``: the BVP module; ``discrete``: the whole reference package
    (``solve_discrete``, ``solve_chain``, ...); ``modes``: natural frequencies (:mod:`simgrip.modes`, callable
    as ``simgrip.modes(...)``); all imported lazily (SciPy, MuJoCo)."""
    import importlib

    if name == "elastica":
        return importlib.import_module("simgrip.reference.elastica")
    if name == "discrete":
        return importlib.import_module("simgrip.reference")
    if name == "modes":  # the package, callable: simgrip.modes(grip, params, profile, links, ...)
        return importlib.import_module("simgrip.modes")
    raise AttributeError(f"module 'simgrip' has no attribute {name!r}")


import simgrip.envs  # noqa: E402,F401  registers simgrip/Pick-v1 and simgrip/PickCradle-v1 (lazy entry points)
