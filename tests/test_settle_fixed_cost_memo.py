"""The settle's per-settle set-up read once per set of values, and a start at rest judged once (issue 19).

:class:`~simgrip.settle.chain_model.ChainModel` reads its parameters through a one-entry memo on the scene
(keyed on the model fields they come from) and a contact-free start already in equilibrium is judged by
MuJoCo's balance alone (:meth:`~simgrip.settle.chain_newton.ChainNewton.solve`).  Each must give exactly
what the computation it replaces gives: parameters edited in place are seen at once, and settled states
are bit for bit those of the full inner Newton solve.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.chain_model import ChainModel
from simgrip.settle.chain_newton import ChainNewton

_PARAMS = ("k", "ds", "c", "_k_next", "_k_diag", "weight", "wscale", "radius", "L", "W")


def _fresh(scene) -> ChainModel:
    scene.__dict__.pop("_chain_parameters", None)
    return ChainModel(scene)


def _same(a, b) -> bool:
    return np.array_equal(np.asarray(a), np.asarray(b)) and np.asarray(a).dtype == np.asarray(b).dtype


@pytest.mark.parametrize("grip,kappa,fingers", [("free", -3.0, 1), ("I", -6.0, 1), ("III", -4.0, 2)])
def test_chain_parameters_follow_in_place_edits(grip, kappa, fingers):
    """Stiffness, masses, gravity, geom sizes and positions edited in place: the next model reads the new
    values, equal bit for bit to a computation without the memo; unchanged values are not read again."""
    sc = build_scene(grip, STANDARD, Uniform(kappa), 10, fingers=fingers)
    first = ChainModel(sc)
    assert ChainModel(sc).k is first.k  # nothing changed: the memo's arrays
    m = sc.model
    # (edit, the parameter it must move): stiffness, masses, centres of mass, gravity, and the contact geoms
    edits = [(lambda: m.jnt_stiffness.__imul__(1.5), "k"), (lambda: m.body_mass.__imul__(1.25), "c"),
             (lambda: m.body_ipos.__imul__(1.1), "c"), (lambda: setattr(m.opt, "gravity", [0.0, 0.0, -4.0]), "c")]
    if m.npair:
        edits += [(lambda: m.geom_size.__imul__(1.01), "_rad"), (lambda: m.geom_pos.__iadd__(1e-3), "_gl")]
    for edit, moved in edits:
        before = ChainModel(sc)
        edit()
        got = ChainModel(sc)
        want = _fresh(sc)
        for name in _PARAMS + (("_gl", "_hx", "_rad", "_pf", "_pl", "_sph") if m.npair else ()):
            assert _same(getattr(got, name), getattr(want, name)), name
        assert not _same(getattr(before, moved), getattr(got, moved)), f"an edit of {moved} went unseen"
    with pytest.raises(ValueError):  # shared between settles: read only
        ChainModel(sc).k[0] = 0.0


def _fields(st, skip=("wall_time_s",)):
    out = {}
    for f in dataclasses.fields(st):
        if f.name in skip:
            continue
        v = getattr(st, f.name)
        out[f.name] = v.tobytes() if isinstance(v, np.ndarray) else repr(v)
    return out


def _settle_both(make, monkeypatch, **kw):
    """A settle as it runs, and the same settle with the at-rest judgement off (the inner Newton always)."""
    sc = make()
    fast = settle(sc, **kw)
    data_fast = (sc.data.qpos.tobytes(), sc.data.xpos.tobytes(), sc.data.qfrc_passive.tobytes())
    with monkeypatch.context() as mp:
        mp.setattr(ChainNewton, "_at_rest", lambda self, tol, frozen: False)
        sc2 = make()
        slow = settle(sc2, **kw)
        data_slow = (sc2.data.qpos.tobytes(), sc2.data.xpos.tobytes(), sc2.data.qfrc_passive.tobytes())
    return fast, slow, data_fast, data_slow


@pytest.mark.parametrize("kappa,n,D", [(-3.0, 16, 1.0), (-8.0, 33, 1.0), (2.0, 64, 1.0), (-3.0, 24, 0.05),
                                       (-5.0, 12, 200.0)])
def test_free_rod_at_rest_is_the_newton_state_bit_for_bit(kappa, n, D, monkeypatch):
    """The free rod from the chain's equilibrium: the state judged at rest is the inner Newton's, every
    field (the MuJoCo evaluations counted included) and the scene's data after.  A stiff rod (``D = 200``)
    whose start is not within the tolerance takes its Newton step as before: the same state, the judgement
    one more MuJoCo evaluation."""
    p = STANDARD.replace(D=D)
    fast, slow, df, ds = _settle_both(lambda: build_scene("free", p, Uniform(kappa), n), monkeypatch)
    assert fast.converged and fast.newton_iterations == slow.newton_iterations
    if D <= 1.0:  # the standard stiffness and softer: the start is at rest
        assert fast.newton_iterations == 0
    if fast.newton_iterations == 0:
        assert _fields(fast) == _fields(slow)
    else:
        skip = ("wall_time_s", "forward_calls")
        assert _fields(fast, skip) == _fields(slow, skip)
        assert fast.forward_calls == slow.forward_calls + 1
    assert df == ds


def test_dropped_workpiece_finger_alone_is_unchanged(monkeypatch):
    """A Grip I workpiece too heavy for its friction drops; the finger alone (contacts off, workpiece parked and
    frozen) settles from the chain's free state: the same state either way."""
    p = STANDARD.replace(M=40.0, mu_s=0.1)
    fast, slow, df, ds = _settle_both(lambda: build_scene("I", p, Uniform(-6.0), 16), monkeypatch)
    assert not fast.held
    assert _fields(fast) == _fields(slow)
    assert df == ds


def test_a_warm_start_is_not_judged_first(monkeypatch):
    """A warm start from another curvature is not put at the chain's equilibrium: the inner Newton takes its
    steps as always, with no extra MuJoCo evaluation (every field the same, the count included)."""
    prev = settle(build_scene("free", STANDARD, Uniform(-2.0), 20))
    sc = build_scene("free", STANDARD, Uniform(-3.0), 20)
    warm = settle(sc, warm_start=prev)
    with monkeypatch.context() as mp:
        mp.setattr(ChainNewton, "_at_rest", lambda self, tol, frozen: False)
        sc2 = build_scene("free", STANDARD, Uniform(-3.0), 20)
        warm2 = settle(sc2, warm_start=prev)
    assert warm.newton_iterations > 0
    assert _fields(warm) == _fields(warm2)
    assert sc.data.qpos.tobytes() == sc2.data.qpos.tobytes()


def test_a_judgement_is_not_reused_once_the_balance_changed():
    """The judge reuses the at-rest judgement only at the same positions with the same rest angles, stiffness,
    gravity and applied forces: after a change it evaluates MuJoCo again (and finds the new imbalance)."""
    from simgrip.settle.closing import start_free
    from simgrip.settle.statics import configure_statics

    sc = build_scene("free", STANDARD, Uniform(-3.0), 16)
    run = ChainNewton(sc)
    configure_statics(sc)
    assert start_free(sc)
    assert run.solve(1e-10, 50, at_rest=True) == (True, "ok")
    assert run._judged is not None
    sc.model.qpos_spring[sc.joint_qpos[0]] += 0.01  # (the rest angles edited in place, the positions unchanged)
    r = run.full_residual(sc.data.qpos)
    assert run._judged is None
    assert float(np.abs(r).max()) > 1e-4  # the new imbalance, not the judged one (~1e-12)
