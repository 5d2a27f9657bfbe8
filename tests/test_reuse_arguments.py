"""The scene cache binds a builder's arguments by hand (simgrip.sim.reuse._arguments): the same dict, in the same
order, as inspect's bind + apply_defaults, and the same TypeError, for every builder the cache serves."""

import inspect

import numpy as np
import pytest

from simgrip.gripper.scene import build_gripper
from simgrip.sim import reuse
from simgrip.sim.scene import build_scene

BUILDERS = [build_scene, build_gripper]


def _inspect(fn, args, kw):
    b = inspect.signature(fn).bind(*args, **kw)
    b.apply_defaults()
    return list(b.arguments.items())


@pytest.mark.parametrize("fn", BUILDERS)
def test_arguments_are_inspects(fn):
    sig = inspect.signature(fn)
    npos = sum(p.kind is p.POSITIONAL_OR_KEYWORD for p in sig.parameters.values())
    args = tuple(f"a{i}" for i in range(npos))
    keywords = [p.name for p in sig.parameters.values() if p.kind is p.KEYWORD_ONLY]
    assert reuse._plain_layout(fn) is not None  # the fast path is the one taken for every builder
    rng = np.random.default_rng(19)
    cases = [{}] + [{k: object() for k in rng.choice(keywords, size=int(rng.integers(1, len(keywords) + 1)),
                                                     replace=False)} for _ in range(6)]
    for kw in cases:
        assert list(reuse._arguments(fn, args, kw).items()) == _inspect(fn, args, kw)
    # positional given by keyword, or too few: inspect decides (and raises alike)
    assert list(reuse._arguments(fn, args[:-1], {sig_name(sig, npos - 1): 1}).items()) == \
        _inspect(fn, args[:-1], {sig_name(sig, npos - 1): 1})
    for bad_args, bad_kw in ((args, {"no_such_keyword": 1}), (args[:-1], {}), (args + ("extra",), {})):
        with pytest.raises(TypeError) as ours:
            reuse._arguments(fn, bad_args, bad_kw)
        with pytest.raises(TypeError) as theirs:
            _inspect(fn, bad_args, bad_kw)
        assert str(ours.value) == str(theirs.value)


def sig_name(sig, i):
    return list(sig.parameters)[i]
