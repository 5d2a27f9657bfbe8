"""The Python API's inputs, tried as a hostile user would (issue 18's audit of every surface; the brief's
"robust": a clear error naming the parameter, before any work, from the library as from the CLI).

Each case is one that misbehaved: a physical parameter set that ``simulate`` takes and ``compare`` crashed on
after the settle (AttributeError); more links than the documented maximum, which only the CLI refused.
"""

from __future__ import annotations

import pytest

from simgrip import DimensionlessParams, PhysicalParams, Uniform


def test_compare_takes_physical_params_as_simulate_does():
    """``compare("I", PhysicalParams(), ...)`` settled, then raised AttributeError 'no attribute D'; now it
    reports the groups the physical parameters have, the same numbers as given the groups."""
    from simgrip.compare import compare

    phys = PhysicalParams()
    a, b = (compare("I", p, Uniform(-5.5), 8) for p in (phys, phys.dimensionless()))
    assert a["simulation"]["normal_force"] == b["simulation"]["normal_force"]
    assert a["reference"]["normal_force"] == b["reference"]["normal_force"]
    with pytest.raises(ValueError, match="^params must be DimensionlessParams or PhysicalParams, got dict"):
        compare("I", {"D": 1.0}, -5.5, 8)


def test_compare_gripper_and_the_records_take_physical_params():
    from simgrip.gripper import compare_gripper, gripper_record, simulate_gripper
    from simgrip.settled import settled_record, simulate

    phys = PhysicalParams()
    kw = dict(fingers=3, workpiece="cylinder")
    a = compare_gripper("I", phys, Uniform(-5.5), 8, **kw)
    b = compare_gripper("I", phys.dimensionless(), Uniform(-5.5), 8, **kw)
    assert a["simulation"]["normal_force"] == b["simulation"]["normal_force"]
    state = simulate_gripper("I", phys, Uniform(-5.5), 8, **kw)
    assert gripper_record(state, phys) == gripper_record(state, phys.dimensionless())
    planar = simulate("I", phys, Uniform(-5.5), 8)
    ra, rb = settled_record(planar, phys), settled_record(planar, phys.dimensionless())
    ra.pop("wall_time_s"), rb.pop("wall_time_s")
    assert ra == rb


def test_the_api_bounds_the_links_as_the_cli_does():
    """``simulate(..., links=1001)`` ran (4.9 s) and ``modes`` too (21 s), while the docs and every command's
    ``--links`` stop at MAX_LINKS = 1000; MuJoCo's own limit (1023) was all the API checked."""
    import simgrip
    from simgrip.compare import simulate
    from simgrip.gripper import simulate_gripper
    from simgrip.params import MAX_LINKS

    p = DimensionlessParams()
    for call in (lambda: simulate("I", p, -5.5, MAX_LINKS + 1),
                 lambda: simgrip.modes("free", p, -5.5, MAX_LINKS + 1, count=1),
                 lambda: simulate_gripper("I", p, -5.5, MAX_LINKS + 1, fingers=3, workpiece="cylinder")):
        with pytest.raises(ValueError, match=f"^links must be at most {MAX_LINKS}"):
            call()


@pytest.mark.parametrize("gravity", [0.5, float("nan"), "False", 1, None])
def test_the_bvps_gravity_is_a_switch_not_a_truthy_value(gravity):
    """``solve(..., gravity=0.5)`` solved with full gravity (the value was read as True), while ``solve_chain``
    takes a factor: a half-weight rod silently got the whole weight.  The BVP's switch now takes a bool only."""
    import simgrip.reference as R

    with pytest.raises(ValueError, match="^gravity must be True or False"):
        R.solve("I", DimensionlessParams(), Uniform(-5.5), gravity=gravity)
    assert R.solve("I", DimensionlessParams(), Uniform(-5.5), gravity=False).success


@pytest.mark.parametrize("make, name", [
    (lambda: DimensionlessParams(D="1"), "D"), (lambda: DimensionlessParams(M=False), "M"),
    (lambda: DimensionlessParams(b=True), "b"), (lambda: PhysicalParams(m=True), "m"),
    (lambda: Uniform(True), "kappa"), (lambda: Uniform("-5"), "kappa"), (lambda: Uniform(-5).scaled("2"), "factor"),
])
def test_a_string_or_a_bool_is_not_a_number(make, name):
    """``D="1"`` was 1.0, ``b=True`` 1.0, ``Uniform("-5")`` -5: converted where docs/limits.md says they are
    refused (a NumPy number is still one)."""
    import numpy as np

    with pytest.raises(ValueError, match=f"^{name} must be a real number"):
        make()
    assert DimensionlessParams(D=np.float64(2.0)).D == 2.0 and Uniform(np.float32(-5.0)).kappa == -5.0


def test_a_user_profiles_arithmetic_failure_is_named():
    """``UserProfile(lambda s: 1 / 0)`` raised ZeroDivisionError: the profile's ValueError now, as its other
    failures."""
    from simgrip import UserProfile

    with pytest.raises(ValueError, match="failed on an array of s_bar: division by zero"):
        UserProfile(lambda s: 1 / 0)


def test_an_unconverged_state_asked_for_says_so():
    """``allow_unconverged=True`` returned the state with ``converged`` False and no warning: a 1-iteration
    Newton read as a drop (held False), a 3-step dynamics as held and feasible.  Each now carries the warning."""
    from simgrip.compare import simulate

    for kw in ({"max_steps": 1}, {"max_steps": 3, "method": "dynamics"}):
        s = simulate("I", DimensionlessParams(), Uniform(-5.5), 12, allow_unconverged=True, **kw)
        assert not s.converged
        assert any(w.startswith("not converged: ") and "allow_unconverged" in w for w in s.warnings), s.warnings
    assert simulate("I", DimensionlessParams(), Uniform(-5.5), 12).warnings == []


def test_progress_and_the_largest_loads_bound_are_checked_by_name():
    """``simulate(..., progress=1)`` raised TypeError "'int' object is not callable" inside the build;
    ``largest_load(..., M_max=1e5)`` searched loads beyond the model's range of M (1e4)."""
    from simgrip.compare import simulate
    from simgrip.params import M_MAX
    from simgrip.reference.capacity import largest_load

    with pytest.raises(ValueError, match="^progress must be None or a callable"):
        simulate("I", DimensionlessParams(), -5.5, 8, progress=1)
    with pytest.raises(ValueError, match=f"^M_max must be at most {M_MAX:g}"):
        largest_load("I", DimensionlessParams(), Uniform(-5.5), M_max=10 * M_MAX)


@pytest.mark.parametrize("call, name", [
    (lambda s: s("I", DimensionlessParams(), -5.5, 8, allow_unconverged="no"), "allow_unconverged"),
    (lambda s: s("I", DimensionlessParams(), -5.5, 8, close="no"), "close"),
])
def test_a_switch_takes_true_or_false_not_a_truthy_word(call, name):
    """``allow_unconverged="no"`` allowed an unconverged state ("no" is truthy), ``close="no"`` closed the fingers;
    ``modes(reference="no")`` solved the reference and ``build_scene(free_workpiece="no")`` built a free box."""
    import simgrip
    from simgrip.compare import simulate
    from simgrip.sim.scene import build_scene

    with pytest.raises(ValueError, match=f"^{name} must be True or False"):
        call(simulate)
    with pytest.raises(ValueError, match="^reference must be True or False"):
        simgrip.modes("I", DimensionlessParams(), -5.5, 8, reference="no")
    with pytest.raises(ValueError, match="^free_workpiece must be True or False"):
        build_scene("I", DimensionlessParams(), -5.5, 8, free_workpiece="no")


def test_a_gripper_offset_of_words_or_bools_is_refused():
    """``offset=("0.01", "0")`` was read as (0.01, 0) by NumPy's conversion; the other gripper numbers refused
    words already (workpiece_yaw, contact_angle)."""
    import numpy as np

    from simgrip.gripper.placement import check_offset

    for bad in (("0.01", "0"), (True, 0.0), "12"):
        with pytest.raises(ValueError, match="^offset must be two real numbers"):
            check_offset(bad)
    assert check_offset(np.array([0.01, 0.0])).tolist() == [0.01, 0.0]


def test_the_reference_helpers_name_a_wrong_argument():
    """``margin(None)`` raised AttributeError, ``min_eigenvalue`` of a (3, 2) matrix a broadcasting error."""
    import numpy as np

    import simgrip.reference as R

    with pytest.raises(ValueError, match="^sol must be an ElasticaSolution"):
        R.margin(None)
    with pytest.raises(ValueError, match="^hessian must be a finite square matrix"):
        R.min_eigenvalue(np.ones((3, 2)))
    with pytest.raises(ValueError, match=r"^constraint_gradient must have shape \(3,\)"):
        R.min_eigenvalue(np.eye(3), np.ones(2))
    assert R.min_eigenvalue(np.diag([3.0, 1.0, 2.0])) == 1.0
