"""Gymnasium environments over simgrip's scene builder (shipped as ``simgrip.envs``)."""
