"""Parameters: validation (every bad value named) and the dimensionless round trip."""

import math

import pytest

from simgrip.params import STANDARD, DimensionlessParams, PhysicalParams, check_grip


def test_standard_case_is_the_papers():
    assert (STANDARD.D, STANDARD.M, STANDARD.b, STANDARD.mu_s, STANDARD.gamma) == (1.0, 5.0, 0.6, 1.0, 0.8)


def test_round_trip_physical_dimensionless():
    p = DimensionlessParams(D=2.5, M=3.0, b=0.4, mu_s=0.7, gamma=0.6)
    phys = p.to_physical(length=0.12, rho=0.08, g=9.81)
    back = phys.dimensionless()
    for name in ("D", "M", "b", "mu_s", "gamma"):
        assert math.isclose(getattr(back, name), getattr(p, name), rel_tol=1e-14)
    # D = EI/(rho g l^3) by hand
    assert math.isclose(phys.EI, 2.5 * 0.08 * 9.81 * 0.12**3, rel_tol=1e-14)
    assert math.isclose(phys.force_scale, 0.08 * 9.81 * 0.12, rel_tol=1e-14)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"EI": 0.0}, "EI"),
        ({"EI": -1.0}, "EI"),
        ({"length": -0.1}, "length"),
        ({"rho": 0.0}, "rho"),
        ({"g": float("nan")}, "g"),
        ({"m": -0.01}, "m"),
        ({"mu_s": -0.5}, "mu_s"),
        ({"b": 0.0}, "b"),
        ({"b": 0.2}, "b"),  # b/2 = length: out of reach
        ({"gamma": 0.0}, "gamma"),
        ({"gamma": 0.1}, "gamma"),
        ({"EI": float("inf")}, "EI"),
        ({"m": "heavy"}, "m"),
    ],
)
def test_physical_rejects_bad_values_by_name(kwargs, name):
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        PhysicalParams(**kwargs)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"D": 0.0}, "D"),
        ({"D": float("nan")}, "D"),
        ({"M": -1.0}, "M"),
        ({"b": 2.0}, "b"),
        ({"b": -0.1}, "b"),
        ({"mu_s": float("nan")}, "mu_s"),
        ({"gamma": 1.0}, "gamma"),
    ],
)
def test_dimensionless_rejects_bad_values_by_name(kwargs, name):
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        DimensionlessParams(**kwargs)


def test_replace_revalidates():
    with pytest.raises(ValueError, match="M"):
        STANDARD.replace(M=-2)
    assert STANDARD.replace(M=2).M == 2.0


@pytest.mark.parametrize("grip, norm", [("free", "free"), ("i", "I"), ("II", "II"), (" iii ", "III")])
def test_grip_names(grip, norm):
    assert check_grip(grip) == norm


@pytest.mark.parametrize("grip", ["IV", "", "pinch", None])
def test_unknown_grip_is_named(grip):
    with pytest.raises(ValueError, match="grip"):
        check_grip(grip)


@pytest.mark.parametrize(
    "field, value",
    [("D", 1e-3), ("D", 1e5), ("M", 1e300), ("M", 2e4), ("mu_s", 1e3)],
)
def test_the_parameter_space_ends_with_a_named_error(field, value):
    with pytest.raises(ValueError, match=rf"^{field} must lie in \["):
        DimensionlessParams(**{field: value})


def test_the_bounds_are_inclusive():
    from simgrip.params import D_MAX, D_MIN, M_MAX, MU_MAX

    for kw in (dict(D=D_MIN), dict(D=D_MAX), dict(M=M_MAX), dict(mu_s=MU_MAX), dict(M=0.0), dict(mu_s=0.0)):
        DimensionlessParams(**kw)


@pytest.mark.parametrize(
    "kw, name",
    [(dict(EI=1e300), "D"), (dict(m=1e300), "M"), (dict(length=1e200, b=1.0, gamma=1.0), "D"), (dict(EI=1e-12), "D")],
)
def test_physical_params_out_of_range_name_the_group_and_its_fields(kw, name):
    from simgrip.params import PhysicalParams

    with pytest.raises(ValueError, match=rf"{name} must .*EI/\(rho g length\^3\)"):
        PhysicalParams(**kw)


def test_to_physical_overflow_is_a_named_error():
    with pytest.raises(ValueError, match="EI"):
        DimensionlessParams(D=1e3).to_physical(length=1e300)
