"""A settled hinge chain's shape as a warm start of the elastica BVP (:func:`chain_guess`).

The simulation's settled finger is the ``n``-link discretisation of one
elastica equilibrium: its shape lies on that equilibrium's branch, within the
chain's ``O(1/n^2)`` discretisation error.  Starting ``solve_bvp`` from it
lands on the same branch, where a cold start (continuation from the straight
rod) may land on another one (issue 16: Grip I at ``kappa = -6, D = 1e4, b =
0.02``, the settle holds with the tip at ``Y = -0.0002``, the cold BVP found
``Y = +0.85`` with a negative normal force).

The guess interpolates the chain: ``theta`` linearly through the link angles at
the link midpoints (and ``theta(0) = 0``, the clamp), the bending moment
``m = D (theta' - kappa0)`` from the joint angles at the interior nodes
(extrapolated to the clamp, the contact moment at the tip), ``X, Y`` through the
nodes, and the contact force ``N1`` on the rod as the BVP's unknown.  All
dimensionless (``l = 1``, forces over ``rho g l``).
"""

from __future__ import annotations

import numpy as np

from simgrip.reference.bvp import BvpProblem, BvpSolution

__all__ = ["ChainGuess", "chain_guess"]


class ChainGuess(BvpSolution):
    """A :class:`BvpSolution`-shaped warm start read from a hinge chain (see the module docstring).

    Only what a warm start reads is defined: ``prob``, ``x`` (the mesh), ``N1``
    and :meth:`states`; it is never a solution itself.
    """

    def __init__(self, prob: BvpProblem, s_theta, theta, s_m, m, s_xy, xy, N1: float):
        mesh = np.unique(np.concatenate((np.asarray(s_theta, float), np.asarray(s_xy, float))))
        super().__init__(prob=prob, x=mesh, y=np.zeros((4, mesh.size)), p=np.array([float(N1)]), sol=None,
                         rms=np.inf, message="hinge-chain guess")
        self._curves = ((np.asarray(s_theta, float), np.asarray(theta, float)),
                        (np.asarray(s_m, float), np.asarray(m, float)),
                        (np.asarray(s_xy, float), np.asarray(xy, float)[:, 0]),
                        (np.asarray(s_xy, float), np.asarray(xy, float)[:, 1]))
        self._N1 = float(N1)

    @property
    def N1(self) -> float:
        return self._N1

    def states(self, s) -> np.ndarray:
        """``(theta, m, X, Y)`` of the chain at arc lengths ``s`` (linear interpolation, shape ``(4,) + s.shape``)."""
        s = np.asarray(s, dtype=float)
        flat = np.clip(s.ravel(), 0.0, 1.0)
        out = np.array([np.interp(flat, xs, ys) for xs, ys in self._curves])
        return out.reshape((4,) + s.shape)

    def contact_state(self) -> np.ndarray:
        return self.states(np.array([self.prob.gamma]))[:, 0]


def chain_guess(prob: BvpProblem, link_angles, nodes=None, N1: float = 0.0, contact_moment: float = 0.0) -> ChainGuess:
    """The warm start of ``prob`` from a settled chain of ``n`` links.

    ``link_angles``: the ``n`` link angles [rad] from ``E1``, counter-clockwise;
    ``nodes``: the ``n + 1`` joint and tip positions ``(X, Y)`` over ``l``, the
    first at the clamp (None: the chain's own, the links of length ``1/n`` laid
    end to end from the clamp at the origin); ``N1``: the horizontal contact force on the rod (over
    ``rho g l``; the BVP's unknown); ``contact_moment``: the workpiece's couple on
    the rod (the tip's moment for Grips I/II).  ``ValueError`` if the arrays do
    not describe one chain.
    """
    th = np.asarray(link_angles, dtype=float).ravel()
    n = th.size
    if nodes is None:
        steps = np.stack((np.cos(th), np.sin(th)), axis=1) / max(n, 1)
        nodes = np.vstack((np.zeros((1, 2)), np.cumsum(steps, axis=0)))
    xy = np.asarray(nodes, dtype=float)
    if n < 2 or xy.shape != (n + 1, 2) or not (np.all(np.isfinite(th)) and np.all(np.isfinite(xy))):
        raise ValueError(f"chain_guess: need n >= 2 finite link angles and n + 1 finite nodes (X, Y), got "
                         f"{th.shape} and {xy.shape}")
    ds = 1.0 / n
    s_nodes = np.arange(n + 1) * ds
    s_mid = (np.arange(n) + 0.5) * ds
    s_theta = np.concatenate(([0.0], s_mid, [1.0]))
    theta = np.concatenate(([0.0], th, [th[-1]]))
    inner = s_nodes[1:-1]
    curvature = np.diff(th) / ds  # theta' at the interior joints
    kappa0 = np.asarray(prob.profile(inner), dtype=float) if callable(prob.profile) else np.zeros_like(inner)
    m_inner = prob.D * (curvature - kappa0)
    m0 = 2.0 * m_inner[0] - m_inner[1] if m_inner.size > 1 else m_inner[0]
    tip_m = float(contact_moment) if not prob.two_seg else 0.0
    s_m = np.concatenate(([0.0], inner, [1.0]))
    m = np.concatenate(([m0], m_inner, [tip_m]))
    return ChainGuess(prob, s_theta, theta, s_m, m, s_nodes, xy, float(N1))
