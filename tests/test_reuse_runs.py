"""simgrip.sim.reuse: a cached model restored by runs of its buffer (``_copy_runs``) equals the per-array copy.

Every array :meth:`_Entry.restore` copies (``_array_fields``) is overwritten with random bytes, then restored
once by the runs and once array by array, on models of every planar grip and a K-finger gripper: every
array of the model (those restored and those left, the tree's sparse layout) must be the same bytes after
both, and equal to the template.  And the runs are what the layout promises: few, each array inside one,
no array that is not restored inside any.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.sim import reuse


def _arrays(m) -> dict:
    out = {}
    for k in reuse._MODEL_ARRAYS:
        a = getattr(m, k)
        out[k] = (a.dtype.str, a.shape, a.tobytes())
    return out


def _entry(grip, n, fingers):
    reuse.clear()
    reuse.build_scene(grip, STANDARD, Uniform(-4.0), n, fingers=fingers)
    sc = reuse.build_scene(grip, STANDARD, Uniform(-4.5), n, fingers=fingers)  # the second: set in place
    (entry,) = list(reuse._cache().values())
    assert entry.scene is sc
    return entry


def _scribble(entry, rng) -> None:
    for dst, _ in entry.fields:
        raw = dst.view(np.uint8).reshape(-1)
        raw[:] = rng.integers(0, 256, raw.size, dtype=np.uint8)


@pytest.mark.parametrize("grip,n,fingers", [("free", 256, 1), ("I", 32, 1), ("I", 16, 2), ("II", 32, 1),
                                            ("III", 16, 1), ("III", 64, 2)])
def test_runs_restore_the_same_bytes_as_the_per_array_copy(grip, n, fingers):
    rng = np.random.default_rng(5)
    entry = _entry(grip, n, fingers)
    assert entry.runs is not None and 1 <= len(entry.runs) <= 8
    m = entry.scene.model
    want = _arrays(entry.template)
    _scribble(entry, rng)
    entry.restore()  # by the runs
    by_runs = _arrays(m)
    runs, entry.runs = entry.runs, None
    _scribble(entry, rng)
    entry.restore()  # array by array
    by_fields = _arrays(m)
    entry.runs = runs
    assert by_runs == by_fields
    assert by_runs == want


def test_runs_cover_the_restored_arrays_and_nothing_else():
    entry = _entry("I", 32, 2)
    m = entry.scene.model
    restored = set(reuse._array_fields(m))
    for k in reuse._MODEL_ARRAYS:
        a = getattr(m, k)
        if not a.size:
            continue
        lo, hi = a.ctypes.data, a.ctypes.data + a.nbytes
        inside = [r for r in entry.runs if r[0] <= lo and hi <= r[0] + r[2]]
        touching = [r for r in entry.runs if lo < r[0] + r[2] and r[0] < hi]
        if k in restored:
            assert len(inside) == 1, k
        else:
            assert not touching, k  # the tree's layout (never written) is not copied


def test_a_model_replaced_on_the_scene_is_restored_array_by_array():
    """The runs hold addresses of the model the entry was taken from: another model on the scene is not touched
    through them (the per-array copy, whose arrays belong to the snapshot's model, runs instead)."""
    import copy

    entry = _entry("I", 16, 1)
    sc = entry.scene
    original = sc.model
    sc.model = copy.copy(original)
    before = _arrays(sc.model)
    entry.restore()
    assert _arrays(sc.model) == before
    sc.model = original
