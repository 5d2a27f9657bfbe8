"""The bench's measuring helpers (simgrip.harness.timing): interleaved CPU times, a settle repeatable from
its start, errors against a reference."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.harness.timing import fastest_cpu_times, settle_from_start


def test_fastest_cpu_times_runs_the_functions_in_turn_and_keeps_each_ones_fastest():
    calls = []
    fns = {"a": lambda: calls.append("a"), "b": lambda: calls.append("b")}
    t = fastest_cpu_times(fns, 3)
    assert calls == ["a", "b"] * 3  # interleaved, run by run
    assert set(t) == {"a", "b"} and all(v >= 0.0 for v in t.values())
    calls.clear()
    fastest_cpu_times(fns, 0)  # at least once
    assert calls == ["a", "b"]


@pytest.mark.parametrize("grip, kappa", [("I", -6.0), ("free", -3.0)])
def test_settle_from_start_settles_from_the_same_start_every_call(grip, kappa, monkeypatch):
    import simgrip.settle

    seen = []

    def moving_settle(scene, **kw):  # records the start it is given, then moves the scene as a settle may
        seen.append((scene.data.qpos.copy(), scene.model.body_pos.copy(), kw))
        scene.data.qpos[:] += 0.1
        scene.model.body_pos[:] += 0.01
        return len(seen)

    monkeypatch.setattr(simgrip.settle, "settle", moving_settle)
    run = settle_from_start(grip, kappa, 8, method="dynamics")
    assert (run(), run()) == (1, 2)
    (q1, b1, kw1), (q2, b2, kw2) = seen
    np.testing.assert_array_equal(q1, q2)
    np.testing.assert_array_equal(b1, b2)
    assert kw1 == kw2 == {"method": "dynamics"}


def test_settle_from_start_is_the_settle_of_the_standard_case():
    from simgrip import STANDARD, Uniform
    from simgrip.scenes import build_scene
    from simgrip.settle import settle

    st = settle_from_start("I", -6.0, 8)()
    ref = settle(build_scene("I", STANDARD, Uniform(-6.0), 8))
    np.testing.assert_array_equal(st.qpos, ref.qpos)
