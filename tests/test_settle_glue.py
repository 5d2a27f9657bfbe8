"""Issue 19: the settle's shortcuts around numpy's wrappers give numpy's own answers, bit for bit.

* :func:`simgrip.settle.banded.lstsq_vector` is ``np.linalg.lstsq(A, b, rcond)[0]`` (the same gufunc), including
  rank-deficient and wide systems, and raises ``lstsq``'s ``LinAlgError`` on non-finite input;
* the reductions the hot loops call (``_MAX``, ``_ALL``, ``_ANY``) answer as ``ndarray.max``, ``.all`` and ``.any``,
  NaN and signed zeros included;
* :meth:`ChainModel.to_q`'s one-finger path (suffix sums along one axis) is the two-axis form's, bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle.banded import _ALL, _ANY, _MAX, lstsq_vector
from simgrip.settle.chain_model import ChainModel


def test_lstsq_vector_is_numpys_lstsq_bit_for_bit():
    rng = np.random.default_rng(19)
    for k in range(400):
        m, n = int(rng.integers(1, 40)), int(rng.integers(1, 6))
        A = rng.normal(size=(m, n)) * 10.0 ** rng.integers(-6, 6)
        if k % 4 == 0 and n > 1:
            A[:, -1] = 2.0 * A[:, 0]  # rank deficient
        b = rng.normal(size=m)
        for rcond in (1e-12, 1e-14):
            want = np.linalg.lstsq(A, b, rcond=rcond)[0]
            got = lstsq_vector(A, b, rcond)
            assert got.shape == want.shape and got.tobytes() == want.tobytes()


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_lstsq_vector_raises_as_lstsq_on_non_finite_input(bad):
    A = np.ones((4, 2))
    A[1, 1] = bad
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.lstsq(A, np.ones(4), rcond=1e-12)
    with pytest.raises(np.linalg.LinAlgError):
        lstsq_vector(A, np.ones(4), 1e-12)


def test_reductions_answer_as_the_array_methods():
    cases = [np.array([1.0, -2.0, 3.0]), np.array([0.0, -0.0]), np.array([np.nan, 1.0]), np.array([1.0, np.nan]),
             np.array([-0.0]), np.array([1e-300, 0.0]), np.array([np.inf, -np.inf])]
    for x in cases:
        assert np.array_equal(_MAX(x), x.max(), equal_nan=True)
        assert np.signbit(_MAX(x)) == np.signbit(x.max())
        assert bool(_ALL(x)) == bool(x.all()) and bool(_ANY(x)) == bool(x.any())
    assert bool(_ALL(np.zeros(0))) and not bool(_ANY(np.zeros(0)))
    two = np.array([[1.0, np.inf], [0.5, 2.0]])
    assert bool(_ALL(np.isfinite(two), axis=None)) == bool(np.isfinite(two).all())


@pytest.mark.parametrize("n", [2, 7, 32])
def test_to_q_one_finger_path_is_the_two_axis_form(n):
    cm = ChainModel(build_scene("I", STANDARD, Uniform(-6.0), n))
    rng = np.random.default_rng(n)
    F = rng.normal(size=n) * 10.0 ** rng.integers(-8, 8, size=n)
    want = F.reshape(1, n)[:, ::-1].cumsum(axis=1)[:, ::-1].reshape(-1)
    assert cm.to_q(F).tobytes() == want.tobytes()
