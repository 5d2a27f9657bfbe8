"""Every key a pick environment's ``step`` puts in ``info`` is named in its class docstring (issue 18)."""

import pytest

import simgrip  # noqa: F401  registers the environments
from env_checks import make

# the retired fragile ids (v0, v1, v4, v5, ...; built through retired_spec) keep their documented keys too
IDS = ["simgrip/Pick-v1", "simgrip/PickMulti-v0", "simgrip/PickFragile-v0", "simgrip/PickMultiFragile-v0",
       "simgrip/PlaceFragile-v0", "simgrip/PickFragile-v1", "simgrip/PickMultiFragile-v1", "simgrip/PlaceFragile-v1",
       "simgrip/PickFragile-v4", "simgrip/PickMultiFragile-v4", "simgrip/PickFragile-v5",
       "simgrip/PickMultiFragile-v5", "simgrip/PickFragile-v6", "simgrip/PickMultiFragile-v6", "simgrip/PlaceFragile-v3", "simgrip/PlaceFragile-v4", "simgrip/PlaceFragile-v5", "simgrip/PlaceFragile-v6", "simgrip/PlaceFragile-v7",
       "simgrip/PickCradleFragile-v4", "simgrip/PickSphereFragile-v4", "simgrip/PickCradleFragile-v5",
       "simgrip/PickSphereFragile-v5", "simgrip/PickFragile-v7", "simgrip/PickMultiFragile-v7",
       "simgrip/PlaceFragile-v8", "simgrip/PickCradleFragile-v6", "simgrip/PickSphereFragile-v6"]


@pytest.mark.parametrize("env_id", IDS)
def test_every_info_key_is_documented(env_id):
    env = make(env_id)
    try:
        env.reset(seed=0)
        _, _, _, _, info = env.step(env.action_space.sample())
        doc = type(env.unwrapped).__doc__ or ""
        module_doc = __import__(type(env.unwrapped).__module__, fromlist=["_"]).__doc__ or ""
        missing = [k for k in info if f"``{k}``" not in doc + module_doc]
        assert "is_success" in info
        assert not missing, f"{env_id}: info keys not in the docstring: {missing}"
    finally:
        env.close()
