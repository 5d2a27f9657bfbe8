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

from simgrip.reference.capacity import (
    LoadCapacity,
    largest_load,
    least_mu,
    margin,
    margin_terms,
    max_load,
    track_largest_load,
)
from simgrip.reference.elastica import FINE_POINTS, ElasticaError, ElasticaSolution, kappa_sweep, solve, sweep
from simgrip.reference.inclined import InclinedContact, solve_inclined
from simgrip.reference.hinge_chain import ChainEquilibrium, chain_energy, cradle_start_angles, solve_chain
from simgrip.reference.minimiser import GRADIENT_TOL, DiscreteError, EnergyTerms
from simgrip.reference.nodal import (
    DiscreteSolution,
    discrete_energy,
    discrete_from_continuous,
    solve_discrete,
    stability_eigenvalue,
)
from simgrip.reference.stability import min_eigenvalue

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
