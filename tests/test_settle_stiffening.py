"""``Newton.stiffening`` (the largest contact-stiffness factor, which caps the settle's contact floor) stays the
largest of ``kc_factor`` through any sequence of :meth:`~simgrip.settle.newton.Newton.stiffen` and
:meth:`~simgrip.settle.newton.Newton.restore_contact` calls: :meth:`stiffen` recomputes it only when it changed
a factor (issue 19), so a call that changes nothing must find it already right.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.chain_newton import ChainNewton
from simgrip.settle.newton import PEN_STIFFEN


def _force(run, depth: float) -> np.ndarray:
    """The normal force [N] that presses pair 0 ``depth`` times :data:`PEN_STIFFEN` deep at its current ``K_c``."""
    return np.array([depth * PEN_STIFFEN * run.scene.length * float(run.kc[0])])


def test_stiffening_follows_every_raise_fall_and_restore():
    run = ChainNewton(build_scene("I", STANDARD, Uniform(-6.0), 16))
    run.normal_active = [0]
    assert run.stiffening == 1.0 == float(np.max(run.kc_factor))
    seen, levels = [], []
    # (depth over the allowed, grow_only): a raise, nothing, a further raise, a fall refused while growing only,
    # the fall, nothing
    for depth, grow_only in ((50.0, True), (0.5, True), (500.0, False), (1e-3, True), (1e-3, False), (0.5, False)):
        snap = run.contact_snapshot()
        changed = run.stiffen(_force(run, depth), grow_only=grow_only)
        seen.append(changed)
        levels.append(run.stiffening)
        assert run.stiffening == float(np.max(run.kc_factor))
        if changed:  # put back, then apply again: restore_contact sets it, a repeat of the same call keeps it
            run.restore_contact(snap)
            assert run.stiffening == float(np.max(run.kc_factor))
            assert run.stiffen(_force(run, depth), grow_only=grow_only)
            assert run.stiffening == float(np.max(run.kc_factor))
    assert seen == [True, False, True, False, True, False]  # (each kind of call was exercised)
    assert levels[0] > 1.0 and levels[2] > levels[0] and levels[4] < levels[2]  # (raised, raised, fell)


@pytest.mark.parametrize("D", [1e2, 1e4])
def test_stiff_grip_settle_reports_the_largest_factor(D, monkeypatch):
    """A stiff finger's settle stiffens its contact (``D = 1e2``: 10, ``1e4``: 1000); at the end of the settle the
    solve's ``stiffening`` is the largest factor it left."""
    runs = []
    init = ChainNewton.__init__

    def spy(self, scene):
        init(self, scene)
        runs.append(self)

    monkeypatch.setattr(ChainNewton, "__init__", spy)
    st = settle(build_scene("I", STANDARD.replace(D=D), Uniform(-6.0), 16))
    run = runs[-1]
    assert st.held and run.stiffening > 1.0
    assert run.stiffening == float(np.max(run.kc_factor))
