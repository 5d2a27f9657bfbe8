"""The validity probe's coarse rows (``envs/pick_validity.py``, issue 18 item 5) change no verdict.

``FingerValidity._bound`` first tries rows over runs of links (:func:`simgrip.envs.pick_validity._coarse_spans`)
and answers valid when all of them clear, before the rows of single link pairs.  What makes that sound:

* the runs cover exactly the link pairs the pair rows compare, each once (a run pair only where all its link
  pairs are compared), for the two- and three-finger models and other link counts;
* a run pair's bound is at most each covered pair's (module docstring), so on random finger shapes (straight to
  beyond a full curl, per-hinge noise, some hinges past ``pi/2``: crossings, overlaps and fingers through each
  other all occur) a state the coarse rows clear has every pair row cleared too, and is valid by the unscreened
  :func:`simgrip.validity.chain_violations`; the probe's messages equal that reference on every state.  Both
  outcomes of the coarse rows occur (else the comparison proves nothing).
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

import mujoco
import numpy as np
import pytest

from simgrip.envs.pick import PickEnv
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.pick_validity import _coarse_spans

sys.path.insert(0, str(Path(__file__).parent))
from test_pick_validity import _reference  # noqa: E402  (chain_violations on every node, no screen)


def _compared(v) -> set:
    """The link pairs of the pair rows, ``((f, i), (g, j))``, from the probe's own mask (``_bind_bound``'s rule)."""
    K, n = v._bodies.shape
    out = set()
    for f in range(K):
        for g in range(f, K):
            for i, j in zip(*np.nonzero(v._mask[f, g])):
                if v._skip_one and f == g and j == i + 2:
                    continue  # proved apart by the link between them
                out.add(((f, int(i)), (g, int(j))))
    return out


def _keep(v) -> np.ndarray:
    K, n = v._bodies.shape
    keep = np.zeros((K * n, K * n), dtype=bool)
    for (f, i), (g, j) in _compared(v):
        keep[f * n + i, g * n + j] = True
    return keep


@pytest.mark.parametrize("make", [lambda: PickEnv(), lambda: PickMultiEnv(fingers=3), lambda: PickEnv(n_links=7),
                                  lambda: PickMultiEnv(fingers=4, n_links=16)], ids=["pick", "multi3", "pick7", "multi4"])
def test_runs_cover_the_compared_pairs_once(make):
    env = make()
    v = env._validity
    K, n = v._bodies.shape
    spans = _coarse_spans(_keep(v), K, n)
    covered = Counter()
    for (f, a, b), (g, c, e) in spans:
        assert 0 <= a < b <= n and 0 <= c < e <= n and f <= g
        for i in range(a, b):
            for j in range(c, e):
                covered[(f, i), (g, j)] += 1
    assert set(covered) == _compared(v) and set(covered.values()) == {1}
    assert v._QcT.shape[1] == len(spans) < v._QT.shape[1]  # fewer rows than pairs (else no point)
    env.close()


def _coarse_cleared(v, d) -> bool:
    """``_bound``'s coarse test on ``d``'s nodes (the same operations)."""
    (b0, b1), (t0, t1) = v._body_cols, v._tip_cols
    P = np.vstack([d.xpos[b0:b1], d.geom_xpos[t0:t1]])
    D = np.dot(P.T, v._QcT)
    return float(np.min(np.dot(v._ones, D * D))) >= 1.0


def _pair_rows_cleared(v, d) -> bool:
    (b0, b1), (t0, t1) = v._body_cols, v._tip_cols
    P = np.vstack([d.xpos[b0:b1], d.geom_xpos[t0:t1]])
    D = np.dot(P.T, v._QT)
    return float(np.min(np.dot(v._ones, D * D))) >= 1.0


@pytest.mark.parametrize("make", [lambda: PickEnv(), lambda: PickMultiEnv(fingers=3)], ids=["pick", "multi3"])
def test_coarse_rows_clear_only_valid_states(make):
    env = make()
    m, d = env.model, mujoco.MjData(env.model)
    v = env._validity
    joints = env.joint_qpos
    K, n = joints.shape
    rng = np.random.default_rng(118)
    counts = Counter()
    for trial in range(400):
        mujoco.mj_resetData(m, d)
        kappa = rng.uniform(-13.0, 2.0) + rng.normal(0.0, 0.5 if trial % 2 else 3.0, K)  # total turning [rad]
        q = kappa[:, None] / n + rng.normal(0.0, 0.12 if trial % 3 else 0.02, (K, n))
        q[rng.random((K, n)) < 0.02] += rng.choice((-1.0, 1.0)) * 1.7  # a few hinges past pi/2
        d.qpos[joints.ravel()] = q.ravel()
        d.qpos[env.palm_qpos] = rng.uniform(0.08, 0.2)
        mujoco.mj_kinematics(m, d)
        ql = d.qpos.tolist()
        reference = _reference(v, d)
        assert v._check(ql, d) == reference, trial
        hinges_ok = bool(np.all(np.abs(q) < 0.5 * np.pi))
        coarse = hinges_ok and _coarse_cleared(v, d)
        if coarse:
            assert _pair_rows_cleared(v, d), trial  # a run pair's bound is at most its link pairs'
            assert reference == [], trial
            assert v._bound(ql, d) == 1
        counts["coarse" if coarse else "not_coarse", "invalid" if reference else "valid"] += 1
    # the coarse rows cleared states, and left valid and invalid ones to the pair rows and the exact path
    for key in (("coarse", "valid"), ("not_coarse", "valid"), ("not_coarse", "invalid")):
        assert counts[key] > 20, dict(counts)
    env.close()
