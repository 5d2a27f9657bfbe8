"""Fixtures shared by several test modules."""

import pytest

from simgrip import STANDARD, Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from settle_cases import KAPPA


@pytest.fixture(scope="session")
def surface_states():
    """Grips I-III at n = 16, 32 settled with the friction at MuJoCo's contact point (``contact="surface"``: the
    tip couple); computed once for the settle and dynamics tests."""
    out = {}
    for grip in ("I", "II", "III"):
        for n in (16, 32):
            out[grip, n] = settle(build_scene(grip, STANDARD, Uniform(KAPPA[grip]), n), contact="surface")
    return out
