"""simgrip: fast, theory-checked simulation of soft pneumatic robot fingers.

Data flows one way: parameters and curvature profile -> scene (MjSpec) ->
settle -> settled state -> comparison with the elastica reference.
"""

from simgrip.params import GRIPS, STANDARD, DimensionlessParams, PhysicalParams, check_grip
from simgrip.profiles import Concentrated, CurvatureProfile, Uniform, UserProfile, as_profile

__version__ = "0.1.0"

__all__ = [
    "GRIPS",
    "STANDARD",
    "DimensionlessParams",
    "PhysicalParams",
    "check_grip",
    "Concentrated",
    "CurvatureProfile",
    "Uniform",
    "UserProfile",
    "as_profile",
]

import simgrip.envs  # noqa: E402,F401  registers simgrip/Pick-v0 and simgrip/PickCradle-v0 (lazy entry points)
