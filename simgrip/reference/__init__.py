"""The continuous and discrete references simgrip's simulations are checked against (no MuJoCo here).

One import for users: ``from simgrip.reference import solve, solve_chain, max_load, ...``.

========================  ================================================================
module                    holds
========================  ================================================================
``bvp``                   the elastica ODE systems and boundary conditions (free rod, Grips I-III)
``continuation``          warm starts, natural continuation and cold starts of ``solve_bvp``
``elastica``              :func:`solve`, :func:`sweep`, :class:`ElasticaSolution`
``inclined``              a tip on a sphere off its equator (:func:`solve_inclined`)
``capacity``              feasibility margin, least friction coefficient, largest load
``minimiser``             the discrete energy both schemes share and its constrained Newton
``nodal``                 the paper's nodal scheme (:func:`solve_discrete`)
``hinge_chain``           the hinge chain's settled state (:func:`solve_chain`), Grip III start shape
``stability``             projected-Hessian eigenvalue (normalisation), banded algebra
``arguments``             checks of the entry points' arguments
========================  ================================================================
"""

import importlib as _importlib

# Each name is imported from its module on first use (PEP 562), not with the package: a settle needs the
# hinge chain alone, and the eager imports (the BVP, capacity, nodal and inclined modules with SciPy's
# optimize, interpolate and special) cost ~0.25 s of CPU in every process that settles (issue 19: a
# 300-point sweep at 32 links settles in ~1 s).  ``from simgrip.reference import X`` works as before.
_LAZY = {
    "LoadCapacity": "capacity", "largest_load": "capacity", "least_mu": "capacity", "margin": "capacity",
    "margin_terms": "capacity", "max_load": "capacity", "track_largest_load": "capacity",
    "FINE_POINTS": "elastica", "ElasticaError": "elastica", "ElasticaSolution": "elastica",
    "kappa_sweep": "elastica", "solve": "elastica", "sweep": "elastica",
    "InclinedContact": "inclined", "solve_inclined": "inclined",
    "ChainEquilibrium": "hinge_chain", "chain_energy": "hinge_chain", "cradle_start_angles": "hinge_chain",
    "solve_chain": "hinge_chain",
    "GRADIENT_TOL": "minimiser", "DiscreteError": "minimiser", "EnergyTerms": "minimiser",
    "DiscreteSolution": "nodal", "discrete_energy": "nodal", "discrete_from_continuous": "nodal",
    "solve_discrete": "nodal", "stability_eigenvalue": "nodal",
    "min_eigenvalue": "stability",
}


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        try:  # a submodule not imported yet (``reference.bvp`` after ``import simgrip.reference``)
            return _importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "ChainEquilibrium",
    "DiscreteError",
    "DiscreteSolution",
    "ElasticaError",
    "ElasticaSolution",
    "EnergyTerms",
    "FINE_POINTS",
    "GRADIENT_TOL",
    "InclinedContact",
    "LoadCapacity",
    "chain_energy",
    "cradle_start_angles",
    "discrete_energy",
    "discrete_from_continuous",
    "kappa_sweep",
    "largest_load",
    "least_mu",
    "margin",
    "margin_terms",
    "max_load",
    "min_eigenvalue",
    "solve",
    "solve_chain",
    "solve_discrete",
    "solve_inclined",
    "stability_eigenvalue",
    "sweep",
    "track_largest_load",
]
