"""Shared cases of the settle tests (scenes, the tip-couple chain, stress-run regressions)."""

from __future__ import annotations

from simgrip import Uniform
from simgrip.chain import ChainSprings, chain_springs
from simgrip.reference import solve_chain
from simgrip.scenes import build_scene

# Grip III at -5.5, not -6: at -6 the standard case violates condition (23) (the tip ends above the contact,
# the rod beyond it through the box's bottom), an impossible state reported not held since issue 17
KAPPA = {"I": -6.0, "II": 5.0, "III": -5.5}
PEN_LIMIT = 1e-4


def chain_with_tip_couple(grip, params, kappa, n, couple):
    """Hinge chain with a tip couple ``C`` (finite tip radius): rest angles shift by ``C / k_j``."""
    sp = chain_springs(Uniform(kappa), n)
    shifted = ChainSprings(n=n, ds=sp.ds, stiffness=sp.stiffness, rest=sp.rest + couple / (params.D * sp.stiffness),
                           nodes=sp.nodes)
    return solve_chain(grip, params, Uniform(kappa), n, springs=shifted)



def stress_scene(grip, D, kappa, M, mu_s, b, n, profile=None):
    from simgrip.params import DimensionlessParams

    params = DimensionlessParams(D=D, M=M, b=b, mu_s=mu_s)
    return build_scene(grip, params, profile if profile is not None else Uniform(kappa), n)


# Grip III cases whose corner slid off the stuck link: the sliding stick's pair left the
# contact set and the Newton residual crashed with "ValueError: <pair> is not in list"
# (stress ids 284, 458, 481).
GRIP_III_SLIDE_OFF = [
    dict(D=49.32953174607504, kappa=6.3606442227548925, M=19.385248039837457, mu_s=0.062374180278660284,
         b=0.6532110506998636, n=4),
    dict(D=14.40180791130886, kappa=-8.383539236514931, M=19.99879723747138, mu_s=0.3479490547863793,
         b=0.16583923089500135, n=21),
    dict(D=27.497204197282763, kappa=-9.076923278164506, M=20.245431709192307, mu_s=0.1409531991381925,
         b=0.35988568672429266, n=12),
]


# A heavy Grip II whose two-finger release stalled at the contact rows' round-off (1.5x the floor)
# because the line search measured them in length units (the force rows' round-off swamped them):
# the workpiece was reported dropped while the symmetric reduction holds it.
TWO_FINGER_HEAVY_II = dict(D=36.638914060188654, kappa=4.976523433174437, M=16.53275895587244,
                           mu_s=0.6904909409134506, b=0.39658623586100206, n=8)
