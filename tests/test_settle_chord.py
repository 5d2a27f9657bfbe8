"""The chain Newton's chord step for MuJoCo's contact stiffness read back after a step (issue 19).

After a quadratic-phase Newton step, :meth:`~simgrip.settle.chain_newton.ChainNewton._chord` corrects the
contact rows for the ``K_c`` (and distance round-off) MuJoCo reports at the new state with the step's own
Jacobian, instead of a full Newton iteration.  The settled state must be the one the plain Newton reaches:
both satisfy the same equations to the settle's tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

import simgrip.settle.chain_newton as cn
from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.chain_model import ChainModel


def _counted(monkeypatch) -> list:
    """Count the chord steps taken (``_chord`` returning a step)."""
    taken = []
    chord = cn.ChainNewton._chord

    def spy(self, *a):
        out = chord(self, *a)
        taken.append(out is not None)
        return out

    monkeypatch.setattr(cn.ChainNewton, "_chord", spy)
    return taken


@pytest.mark.parametrize("grip,kappa,n,fingers", [("I", -6.0, 32, 1), ("II", 5.0, 32, 1), ("I", -6.0, 16, 2),
                                                  ("II", 5.0, 16, 2)])
def test_chord_state_is_the_plain_newton_state(grip, kappa, n, fingers, monkeypatch):
    """Point contact: the chord is taken and the state agrees with the plain Newton's (chord off) within what the
    tolerance allows: contact forces within the force tolerance, joint angles within it over the stiffest
    reading, ``tolerance / min k`` (a moment imbalance ``tol`` turns a hinge of stiffness ``k`` by ``tol / k``)."""
    sc = build_scene(grip, STANDARD, Uniform(kappa), n, fingers=fingers)
    q0 = sc.data.qpos.copy()
    taken = _counted(monkeypatch)
    fast = settle(sc)
    assert any(taken)
    monkeypatch.setattr(cn, "CHORD_GAIN", -1.0)  # never: the plain Newton
    sc.data.qpos[:] = q0
    slow = settle(sc)
    assert fast.converged and slow.converged and fast.held and slow.held
    assert fast.newton_iterations <= slow.newton_iterations
    tol = max(fast.tolerance, slow.tolerance)
    assert abs(fast.N1 - slow.N1) <= tol and abs(fast.N2 - slow.N2) <= tol
    k_min = float(np.min(ChainModel(sc).k))
    assert float(np.max(np.abs(fast.qpos - slow.qpos))) <= tol / k_min


def test_no_chord_with_friction_at_the_surface(monkeypatch):
    """Friction at the surface: re-anchoring moves the friction's arm, the next Newton step is needed anyway,
    so no chord is taken and the settle is the plain Newton's bit for bit."""
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    q0 = sc.data.qpos.copy()
    taken = _counted(monkeypatch)
    a = settle(sc, contact="surface")
    assert taken == []
    monkeypatch.setattr(cn, "CHORD_GAIN", -1.0)
    sc.data.qpos[:] = q0
    b = settle(sc, contact="surface")
    assert np.array_equal(a.qpos, b.qpos) and a.N1 == b.N1 and a.newton_iterations == b.newton_iterations


def test_chord_counts_against_the_budget(monkeypatch):
    """A chord step is an iteration: a budget one short of the settle's count is still spent."""
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16)
    q0 = sc.data.qpos.copy()
    taken = _counted(monkeypatch)
    st = settle(sc)
    assert any(taken)
    sc.data.qpos[:] = q0
    with pytest.raises(Exception, match="max_steps"):
        settle(sc, max_steps=st.newton_iterations - 1)
