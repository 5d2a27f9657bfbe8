"""The paper's figures 6-9 and 11-16, recomputed from the elastica reference.

Computing, simulating and drawing are separate modules:

* :mod:`~simgrip.figures.data` -- :func:`figure_data`, the numbers a figure
  shows (a ``dict`` of NumPy arrays and floats; no matplotlib), so tests and
  other tools check them without rendering;
* :mod:`~simgrip.figures.overlay` -- :func:`simulation_overlay`, the settled
  MuJoCo hinge chain at a few ``kappa_bar0`` of figures 6-9 (the ``overlay``
  format is documented there);
* :mod:`~simgrip.figures.plot` -- :func:`plot_figure` and :func:`save_figure`
  (matplotlib's object-oriented API, no pyplot state);
* :mod:`~simgrip.figures.make` -- :func:`make_figures`, the files, one task of
  the parallel runner per figure;
* :mod:`~simgrip.figures.gripper` -- K-finger grippers: :func:`render_gripper`
  (a settled grasp drawn offscreen) and the normal force per finger on the BVP.

``import simgrip.figures`` does not import matplotlib: :func:`plot_figure` and
:func:`save_figure` load :mod:`~simgrip.figures.plot` on first use.

Conventions: dimensionless units (lengths over ``l``, forces on the rod over
``rho g l``), the finger's base at the origin, ``x`` horizontal along ``E1``,
``z`` vertically **up** (heights ``h`` are positive up, unlike the paper's
Fig. 9, which measures them downwards).

=====  ===================================================================
name   content
=====  ===================================================================
fig06  free clamped rod, uniform ``kappa_bar0``: (a) no gravity, (b) gravity; D = 1
fig07  Grip I, ``kappa_bar0`` in [0, -6]: shapes (feasible marked ``f``),
       required friction ``M`` vs available ``mu_s N``, tip height ``h``;
       feasible region shaded
fig08  Grip II, ``kappa_bar0`` in [0, 6]: the same three panels
fig09  Grip III, ``kappa_bar0`` in [0, -10], ``gamma = 0.8``: shapes, friction
       ``|f|`` needed vs ``mu_s n`` available, heights ``h`` (tip) and
       ``h_gamma`` (contact); feasible region shaded
fig11  smallest eigenvalue of ``E^T L E`` along the sweeps of Figs. 7-9
fig12  concentrated profile (34), ``kappa_max = 6``, ``p = -1``, alpha in [1, 3]:
       the profile and the free heavy rod's shape
fig13  Grip I with profile (34), alpha in [1, 3]: shapes, load capacity
       ``mu_s N``, smallest eigenvalue
fig14  Grip II with profile (34) (``p = +1``): the same three panels
fig15  Grip III with profile (34): shapes, load capacity (largest ``|N2| = M``
       held, see the caption of the paper's Fig. 15), smallest eigenvalue
fig16  (a) least ``mu_s = |f|/n`` to hold ``M = 5`` (gaps: no normal force, or
       Grip III's tip above the contact), (b) largest ``M`` held at
       ``mu_s = 1`` (hollow markers: limited by the fold where the finger
       snaps through); the three grips vs ``|kappa_bar0|``
=====  ===================================================================

K-finger grippers (:mod:`~simgrip.figures.gripper`; Grip I, standard case):
``grasp3`` and ``grasp4`` (three fingers around a cylinder, four around a box,
rendered), ``grip_forces`` (``N`` per finger vs ``kappa_bar0``, cylinder with
3 and 4 fingers, on the BVP curve).
"""

from __future__ import annotations

from simgrip.figures.catalog import FIGURES, figure_key
from simgrip.figures.data import figure_data
from simgrip.figures.gripper import render_gripper
from simgrip.figures.make import add_arguments, cli_figures, make_figures
from simgrip.figures.overlay import simulation_overlay

__all__ = ["FIGURES", "figure_data", "plot_figure", "make_figures", "save_figure", "simulation_overlay",
           "figure_key", "add_arguments", "cli_figures", "render_gripper"]


def __getattr__(name: str):
    """``plot_figure`` and ``save_figure``: :mod:`simgrip.figures.plot`, imported (with matplotlib) on first use."""
    if name in ("plot_figure", "save_figure"):
        from simgrip.figures import plot

        return getattr(plot, name)
    raise AttributeError(f"module 'simgrip.figures' has no attribute {name!r}")
