"""Static MJCF parts that the scene builder composes (shipped as ``simgrip.models``)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["model_path", "available"]


def model_path(name: str) -> Path:
    """Absolute path of the MJCF part ``name`` (e.g. ``"defaults.xml"``) inside the installed package."""
    ref = resources.files(__name__).joinpath(name)
    if not ref.is_file():
        raise FileNotFoundError(f"no MJCF part {name!r} in simgrip.models (have: {available()})")
    return Path(str(ref))


def available() -> list[str]:
    """Names of the MJCF parts shipped with simgrip."""
    return sorted(p.name for p in resources.files(__name__).iterdir() if p.name.endswith(".xml"))
