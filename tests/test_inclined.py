"""simgrip.reference.inclined: the elastica of a tip on a sphere off its equator."""

from __future__ import annotations

import math

import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import elastica
from simgrip.reference.inclined import solve_inclined


def test_equator_is_the_vertical_face():
    for grip, kappa in (("I", -6.0), ("II", 5.0)):
        ref = elastica.solve(grip, STANDARD, Uniform(kappa), contact_moment=0.01)
        inc = solve_inclined(grip, STANDARD, Uniform(kappa), 0.0, contact_moment=0.01)
        assert inc.normal_force == ref.N1 and inc.friction_force == ref.N2 and inc.N2 == pytest.approx(-STANDARD.M)
        assert inc.required_mu == pytest.approx(ref.required_mu, rel=1e-12)
        assert inc.feasible == ref.feasible and inc.centre_height == ref.tip[1]


@pytest.mark.parametrize("beta", [-0.4, -0.1, 0.15])
def test_force_on_the_rod_rotated_into_the_contact_frame(beta):
    inc = solve_inclined("I", STANDARD, Uniform(-6.0), beta)
    # the rod's problem is Grip I at width b cos(beta): tip on the sphere, the friction carries M
    assert inc.tip[0] == pytest.approx(0.5 * STANDARD.b * math.cos(beta), abs=1e-9)
    assert inc.N2 == pytest.approx(-STANDARD.M, rel=1e-9)
    # (N, F_f) is (N1, N2) in the frame (n, t): same length, and back again
    assert math.hypot(inc.normal_force, inc.friction_force) == pytest.approx(math.hypot(inc.N1, inc.N2), rel=1e-14)
    c, s = math.cos(beta), math.sin(beta)
    assert inc.normal_force * c - inc.friction_force * s == pytest.approx(inc.N1, rel=1e-12)
    assert inc.normal_force * s + inc.friction_force * c == pytest.approx(inc.N2, rel=1e-12)
    # the tip is on the sphere: distance b/2 from the centre
    assert math.hypot(inc.tip[0], inc.tip[1] - inc.centre_height) == pytest.approx(0.5 * STANDARD.b, rel=1e-9)
    assert inc.feasible == (inc.normal_force > 0 and inc.required_mu <= STANDARD.mu_s)


def test_grip_i_holds_better_below_the_equator():
    # below the equator the normal force carries part of the weight: less friction needed
    mus = [solve_inclined("I", STANDARD, Uniform(-6.0), b).required_mu for b in (-0.3, -0.1, 0.0, 0.1, 0.3)]
    assert mus == sorted(mus)


def test_bad_input_is_named():
    for args, name in [(("III", STANDARD, -6.0, 0.1), "grip"), (("I", STANDARD, -6.0, math.pi / 2), "contact_angle"),
                       (("I", STANDARD, -6.0, "x"), "contact_angle"), (("I", {"b": 1}, -6.0, 0.1), "params")]:
        with pytest.raises(ValueError, match=name):
            solve_inclined(*args)
