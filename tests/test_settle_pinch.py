"""Issue 19: :mod:`simgrip.settle.pinch`'s state functions are :class:`ChainModel`'s, bit for bit.

* at perturbed states of Grip I/II scenes (point and surface friction anchors, sticks of either tangent sign) the
  nodes, forces, the tip pair's term and the stick's term equal :class:`ChainModel`'s own (value, gradient,
  Hessian diagonal, no low-rank part);
* a tangent with an ``x`` part, a stick that turns with its link and a capsule pair (Grip III) are handed to
  :class:`ChainModel` itself;
* whole settles (Grips I-III, point and surface contact, warm sweeps) with the pinch functions and with
  :class:`ChainModel`'s give the same state, residual, forces and counts.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import chain_newton, settle, settle_sweep
from simgrip.settle.chain_model import ChainModel
from simgrip.settle.chain_newton import ChainNewton
from simgrip.settle.closing import start_on_chain, touch
from simgrip.settle.pinch import Pinch, evaluators
from simgrip.settle.statics import Stick


def _same_term(a, b):
    assert float(a.value).hex() == float(b.value).hex()
    for x, y in ((a.grad, b.grad), (a.diag, b.diag), (a.U, b.U), (a.S, b.S)):
        assert x.shape == y.shape and x.tobytes() == y.tobytes()


def _started(grip, kappa, n):
    """A scene at its chain start with the workpiece touching, and its Newton with the stick made."""
    sc = build_scene(grip, STANDARD, Uniform(kappa), n)
    run = ChainNewton(sc)
    assert start_on_chain(sc, run)
    touch(sc, run)
    assert run.stick_now() == 1
    return sc, run


@pytest.mark.parametrize("grip,kappa,n", [("I", -6.0, 32), ("I", -3.0, 8), ("II", 5.0, 16), ("I", -9.0, 64)])
def test_pinch_functions_are_the_chain_models(grip, kappa, n):
    sc, run = _started(grip, kappa, n)
    cm = run.model
    pinch = Pinch(cm)
    phi0, w0 = cm.split(sc.data.qpos)
    rng = np.random.default_rng(n)
    s0 = run.sticks[0]
    for k in range(20):
        phi = phi0 + (0.0 if k == 0 else 1e-3) * rng.normal(size=phi0.size)
        w = w0 + (0.0 if k == 0 else 1e-3) * rng.normal(size=w0.size)
        assert pinch.nodes(phi).tobytes() == cm.nodes(phi).tobytes()
        for a, b in zip(pinch.internal(phi), cm.internal(phi)):
            assert a.tobytes() == b.tobytes()
        nodes = cm.nodes(phi)
        _same_term(pinch.pair_term(0, phi, nodes, w), cm.pair_term(0, phi, nodes, w))
        # the stick as made, then with the tangent's sign flipped and with another anchor and offset
        for t_local, local_f, off in ((s0.t_local, s0.local_f, s0.offset), (-s0.t_local, s0.local_f, 0.0),
                                      (s0.t_local, s0.local_f + rng.normal(size=3) * 1e-3 * sc.length, 3e-7)):
            s = Stick(finger=0, body_f=s0.body_f, local_f=local_f, body_w=s0.body_w, local_w=s0.local_w,
                      t_body=s0.t_body, t_local=t_local, geoms=s0.geoms, offset=off)
            _same_term(pinch.stick_term(s, phi, nodes, w), cm.stick_term(s, phi, nodes, w))


def test_other_terms_are_the_chain_models_own(monkeypatch):
    sc, run = _started("I", -6.0, 16)
    cm = run.model
    pinch = Pinch(cm)
    phi, w = cm.split(sc.data.qpos)
    nodes = cm.nodes(phi)
    s0 = run.sticks[0]
    calls = []
    monkeypatch.setattr(ChainModel, "stick_term", lambda self, *a: calls.append(a) or "own")
    slanted = Stick(finger=0, body_f=s0.body_f, local_f=s0.local_f, body_w=s0.body_w, local_w=s0.local_w,
                    t_body=s0.t_body, t_local=np.array([0.6, 0.0, 0.8]), geoms=s0.geoms)
    link = Stick(finger=0, body_f=s0.body_f, local_f=s0.local_f, body_w=s0.body_w, local_w=s0.local_w,
                 t_body=s0.body_f, t_local=s0.t_local, geoms=s0.geoms)
    assert pinch.stick_term(slanted, phi, nodes, w) == "own"  # a tangent with an x part
    assert pinch.stick_term(link, phi, nodes, w) == "own"  # a tangent turning with the link
    assert len(calls) == 2
    three = ChainModel(build_scene("III", STANDARD, Uniform(-5.5), 16))
    phi3, w3 = three.split(three.scene.data.qpos)
    nodes3 = three.nodes(phi3)
    _same_term(evaluators(three)[2](0, phi3, nodes3, w3), three.pair_term(0, phi3, nodes3, w3))  # a capsule pair


def _record(st):
    return (st.qpos.tobytes(), st.tip.tobytes(), float(st.residual).hex(),
            [(float(c.N1).hex(), float(c.N2).hex()) for c in st.contacts], st.held, st.valid, st.converged,
            st.newton_iterations, st.forward_calls, list(st.warnings))


CASES = [("I", -6.0, 32, "point"), ("I", -6.0, 32, "surface"), ("I", -1.5, 8, "point"), ("I", -9.0, 64, "point"),
         ("II", 5.0, 16, "point"), ("II", 7.5, 32, "surface"), ("III", -5.5, 16, "point"), ("free", -3.0, 16, "point")]


@pytest.mark.parametrize("grip,kappa,n,contact", CASES)
def test_settles_with_and_without_the_pinch_functions_agree(monkeypatch, grip, kappa, n, contact):
    def run():
        return _record(settle(build_scene(grip, STANDARD, Uniform(kappa), n), contact=contact,
                              allow_unconverged=True))

    pinched = run()
    monkeypatch.setattr(chain_newton, "evaluators", lambda cm: (cm.nodes, cm.internal, cm.pair_term, cm.stick_term))
    assert run() == pinched


def test_warm_sweep_with_and_without_the_pinch_functions_agree(monkeypatch):
    def run():
        sc = build_scene("I", STANDARD, Uniform(-7.0), 16)
        return [_record(s) for s in settle_sweep(sc, [Uniform(k) for k in (-7.0, -6.5, -6.0, -5.0)])]

    pinched = run()
    monkeypatch.setattr(chain_newton, "evaluators", lambda cm: (cm.nodes, cm.internal, cm.pair_term, cm.stick_term))
    assert run() == pinched
