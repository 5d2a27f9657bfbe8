"""The settled chain's natural frequencies (simgrip.modes) against rod theory, at the derived order.

Error model.  The chain is a second-order discretisation of the rod's energy (springs, gravity,
simgrip.chain) and of its kinetic energy (rigid links = the piecewise-linear interpolant of the nodes), so
mode k's frequency error is C_k (beta_k ds)^2 + O(ds^4), and the observed order is 2 + O((beta_k ds)^2).
On top of that the capsule's rotary inertia rho r_link^2/4 (r_link = 2e-3 l by default), which does not
vanish with ds, lowers omega_k by ~(beta_k r_link)^2 / 8 <= 3e-5 for the first three modes: negligible at
the issue's 0.5 % / 1 %, but visible at n = 128 (1e-4 errors), so the order is measured on scenes with
r_link = 1e-5 (a 4e-10 shift).  Tolerances: the issue's 0.5 % (Euler-Bernoulli) and 1 % (the rod) at
n = 64; observed least-squares order over n = 16..128 within 2 +- 0.1 (the next term's share
(beta_3 ds)^2 / 12 ~ 2 % at n = 16); MAC >= 1 - 1e-4: the shapes' relative error eps is O(ds^2) like the
frequencies' (<= 1e-2 at n = 64), and 1 - MAC = O(eps^2).
"""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import simgrip
from simgrip import DimensionlessParams, STANDARD, Uniform
from simgrip.cli import main
from simgrip.modes import chain_modes, eigen, linearise, modes, reference_modes
from simgrip.settle import settle
from simgrip.sim.scene import build_scene

LINKS = (16, 32, 64, 128)
EB = np.array([brentq(lambda x: 1 + math.cos(x) * math.cosh(x), a, b, xtol=1e-14) for a, b in
               [(1, 2.5), (4, 5.5), (7, 8.5)]]) ** 2
CASES = {  # name: grip, params, kappa
    "euler-bernoulli": ("free", DimensionlessParams(D=1e4), 0.0),
    "curled-free": ("free", DimensionlessParams(D=1.0), -3.0),
    "grip-I": ("I", STANDARD, -6.0),
}


def reference(name):
    grip, params, kappa = CASES[name]
    if name == "euler-bernoulli":
        return EB * math.sqrt(params.D)  # omega sqrt(l/g) = (beta l)^2 sqrt(D)
    return reference_modes(grip, params, Uniform(kappa), 3).omega


@pytest.fixture(scope="module")
def errors():
    """Relative frequency errors of the first three modes at each n (r_link = 1e-5, see the module docstring)."""
    out = {}
    for name, (grip, params, kappa) in CASES.items():
        ref = reference(name)
        rows = []
        for n in LINKS:
            scene = build_scene(grip, params, Uniform(kappa), n, r_link=1e-5)
            w = chain_modes(scene, settle(scene), 3)[1]
            rows.append(np.sqrt(w) / ref - 1.0)
        out[name] = np.array(rows)
    return out


@pytest.mark.parametrize("name", list(CASES))
def test_second_order_in_ds(errors, name):
    e = np.abs(errors[name])
    for k in range(3):
        p = -np.polyfit(np.log(LINKS), np.log(e[:, k]), 1)[0]
        assert abs(p - 2.0) < 0.1, (name, k, p, e[:, k])


@pytest.mark.parametrize("name, tol", [("euler-bernoulli", 5e-3), ("curled-free", 1e-2), ("grip-I", 1e-2)])
def test_at_64_links_with_the_default_scene(name, tol):
    grip, params, kappa = CASES[name]
    r = modes(grip, params, Uniform(kappa), 64, count=3, reference=name != "euler-bernoulli")
    ref = reference(name) if name == "euler-bernoulli" else r.reference_frequencies
    assert np.all(np.abs(r.frequencies / ref - 1.0) < tol), (r.frequencies, ref)
    if r.mac is not None:
        assert np.all(r.mac >= 1.0 - 1e-4), r.mac
        assert r.reference_error < 1e-6
    assert r.settled["misfit"] < 1e-8 and r.settled["asymmetry"] < 1e-8


def test_held_workpiece_is_a_constraint():
    """Grip I: the tip sticks to the workpiece, which slides vertically: n + 1 dofs, 2 constraints, and the
    multipliers are the settled contact force (N1, -M)."""
    scene = build_scene("I", STANDARD, Uniform(-6.0), 16)
    state = settle(scene)
    lin, w, v, shapes, _ = chain_modes(scene, state, 15)
    assert lin.dofs == 15 and lin.jacobian.shape == (2, 17)
    assert np.allclose(lin.multipliers, [state.N1, -STANDARD.M], rtol=1e-6)
    assert np.max(np.abs(lin.jacobian @ v)) < 1e-10  # the modes keep the tip on the workpiece
    assert np.all(w > 0) and shapes.shape == (15, 1, 17, 2)


def test_eigen_and_linearise_refuse_bad_input():
    scene = build_scene("free", DimensionlessParams(D=1.0), Uniform(-1.0), 8)
    lin = linearise(scene)
    with pytest.raises(ValueError, match="count"):
        eigen(lin.M, lin.K, count=9)
    with pytest.raises(ValueError, match="square"):
        eigen(lin.M[:3], lin.K)
    with pytest.raises(ValueError, match="step"):
        linearise(scene, step=0.0)
    with pytest.raises(ValueError, match="count"):
        modes("free", DimensionlessParams(D=1.0), Uniform(-1.0), 8, count=9)


def test_callable_package_and_cli(capsys):
    r = simgrip.modes("free", DimensionlessParams(D=1.0), Uniform(-3.0), 16, count=2, reference=False)
    assert r.frequencies.shape == (2,) and r.reference_frequencies is None
    assert main(["modes", "free", "--kappa", "-3", "--links", "16", "--count", "2", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["count"] == 2 and len(rec["reference_frequencies"]) == 2
    assert max(abs(x) for x in rec["relative_difference"]) < 0.02  # C_k (1/16)^2 with C_2 ~ 2.5
    for bad, option in ((["--count", "0"], "count"), (["--count", "17"], "count"), (["--links", "1"], "links")):
        assert main(["modes", "free", "--kappa", "-3", "--links", "16", *bad]) == 2
        assert option in capsys.readouterr().err
    assert main(["modes", "I", "--kappa", "-6", "--links", "8", "--count", "3"]) == 0
    assert "MAC" in capsys.readouterr().out


def test_grip_iii_against_the_rod_at_its_own_gamma():
    """Grip III: the corner sticks to the rod's point at the simulation's gamma (reference at that gamma and
    X(gamma), as simgrip.compare).  The contact falls inside a link, so the chain's error is first order like
    the statics' (docs/validation.md: the BVP within 0.05/n): asserted 1 % at n = 64 (the issue's bound) and
    a first-order envelope 0.5/n at n = 32 (measured 0.1/n)."""
    for n, tol in ((32, 0.5 / 32), (64, 1e-2)):
        r = modes("III", STANDARD, Uniform(-4.0), n)
        assert np.all(np.abs(r.relative_difference) < tol), (n, r.relative_difference)
        assert np.all(r.mac >= 1.0 - 1e-3), r.mac  # 1 - MAC = O(eps^2), eps <= 0.03 at n = 32


def test_k_finger_gripper_contains_the_symmetric_reduction(capsys):
    """K = 3 fingers around a centred cylinder: the symmetric subspace is invariant, and on it the gripper is
    the planar symmetric reduction (the same chain, the workpiece's mass shared by K): the same frequencies to
    the linearisations' errors (finite differences ~1e-10, the settles' residual ~1e-9), and they are modes of
    the whole gripper too.  The sway modes come below them."""
    from simgrip.modes.gripper import gripper_modes

    rec = gripper_modes("I", STANDARD, Uniform(-6.0), 16, fingers=3, workpiece="cylinder", count=4)
    planar = modes("I", STANDARD, Uniform(-6.0), 16, count=3, reference=False).frequencies
    assert np.allclose(rec["symmetric_frequencies"][:3], planar, rtol=1e-7, atol=0)
    full = np.array(rec["frequencies"])
    assert np.min(np.abs(full - planar[0])) < 1e-7 * planar[0] and full[0] < planar[0]
    assert main(["modes", "I", "--kappa", "-6", "--links", "16", "--fingers", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["fingers"] == 3
    assert main(["modes", "I", "--kappa", "-6", "--links", "16", "--workpiece", "box"]) == 2
    assert "fingers" in capsys.readouterr().err


def test_physical_units_give_the_same_dimensionless_frequencies():
    """PhysicalParams() is the standard case in SI (D = EI/(rho g l^3) = 1, M = 5, b = 0.6): omega sqrt(l/g)
    must not depend on the units (the settles' residual, ~1e-9, bounds the difference)."""
    from simgrip import PhysicalParams

    a = modes("I", PhysicalParams(), Uniform(-6.0), 16, count=3)
    b = modes("I", STANDARD, Uniform(-6.0), 16, count=3)
    assert np.allclose(a.frequencies, b.frequencies, rtol=1e-8, atol=0)
    assert np.allclose(a.reference_frequencies, b.reference_frequencies, rtol=1e-8, atol=0)


@pytest.mark.parametrize("contact", ["full", "bogus"])
def test_modes_refuse_a_contact_mode_they_do_not_linearise(contact):
    from simgrip.modes import modes as modes_of

    with pytest.raises(ValueError, match="contact must be 'point' or 'surface'"):
        modes_of("I", STANDARD, -6.0, 8, contact=contact)


def test_modes_tell_their_phases():
    """``modes`` and ``gripper_modes`` take ``progress`` as ``simulate`` does (the CLI prints a long job's
    phases; an audit found ``modes --links 1000 --fingers K`` silent for minutes)."""
    import contextlib

    from simgrip.modes import modes
    from simgrip.modes.gripper import gripper_modes
    from simgrip.params import DimensionlessParams
    from simgrip.profiles import Uniform

    told = []

    def progress(what):
        told.append(what)
        return contextlib.nullcontext()

    modes("I", DimensionlessParams(), Uniform(-5.5), 8, count=1, reference=False, progress=progress)
    gripper_modes("I", DimensionlessParams(), Uniform(-5.5), 8, fingers=3, count=1, reference=False,
                  progress=progress)
    assert told == ["building the model (8 links per finger)", "settling",
                    "building the model (3 fingers x 8 links)", "settling"]
