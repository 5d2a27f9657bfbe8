"""Design sweeps (``simgrip sweep``): the settled simulation beside the elastica BVP over a grid of designs.

``grid`` holds the six axes and their validation, ``point`` settles and solves
one design, ``store`` writes the CSV table and the resumable partial results,
``map`` draws ``map.png``, ``profile`` measures points per second, and
``sweep`` runs it all on the parallel runner (:func:`run_sweep`).
"""

from simgrip.sweep.run import SweepResult, run_sweep

__all__ = ["SweepResult", "run_sweep"]
