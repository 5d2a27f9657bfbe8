"""Hold/drop pinned to the discrete chain's own friction threshold, for every grip, method and the gripper.

The hold/drop verdict is the simulator's main output.  The other hold/drop tests compare it with the
BVP's required mu, from which the n = 16 chain differs by ~0.3 % (I) / 0.1 % (II) (second order in
``ds``), so they must test at +-1-2 % and miss a friction cone that is 1 % too generous (issue 22).
Here the reference is the hinge chain the MuJoCo finger *is* (:func:`simgrip.reference.solve_chain`),
solved at the settled state's own contact: its tip ``X`` (``b/2`` less the penetration), its tip
couple ``C`` and, for Grip III, its own ``gamma``; the chain's required mu is read in MuJoCo's contact
frame (Grips I/II: ``|N2| / N1``; Grip III: the carrying link's tangent and normal; a sphere: the
sphere's normal at the contact angle).  The only difference left is each method's own stopping error,
so the band around the threshold is derived from it:

* **Newton** (static settle, the K-finger symmetry skip): stops at a residual of ``tolerance``
  (1e-10 of ``rho g l``, raised by the round-off floor to at most 1e-6), which moves ``N1`` and the
  friction by at most that: ``|mu_settle / mu_chain - 1| <= tolerance (1 + mu) / N1 <= 3e-7``
  (measured 1e-13 to 1e-10; asserted below at 1e-6).  The cone test itself has a 1e-9 slack.
  Band :data:`NEWTON_BAND` = 1e-5, ten times the asserted agreement.
* **Dynamics** (MuJoCo's elliptic cone, impratio 1e4): sticking friction creeps and leaves up to the
  residual tolerance ``max(DYN_TOL, DYN_TOL_PER_WEIGHT M)`` (1e-5 at M = 5) of the weight unbalanced,
  so its threshold is the chain's to ``tol / M`` = 2e-6 (measured 2e-7 to 4e-6; asserted at 1e-5).
  Below the threshold the workpiece must also slide :data:`~simgrip.settle.dynamics.DYN_DROP_SLIP`
  within the step budget: the slide is driven by the excess ``eps M`` of the weight over the
  friction, so its time grows as ``eps^-1/2`` (measured 2,000-4,600 of the 20,000 steps at
  ``eps`` = 1e-3 and 3e-4; at 1e-5 it creeps without coming to rest).  Band :data:`DYN_BAND` = 1e-3:
  100 times the creep floor and a 5x margin in steps.
* **Grip III** (Newton): below the threshold the corner slides along its link and sticks again where
  the need meets ``mu_s``, ``d gamma ~ eps mu / |d mu / d gamma|`` (measured 7e-6 at ``eps`` = 1e-4,
  n = 16); above it the contact does not move (measured 0).  Band :data:`III_NEWTON_BAND` = 1e-4, so
  that the slide (:data:`SLID`) is 7x above the round-off of a stuck contact (:data:`STUCK`).

Each band is 10 to 1000 times tighter than a 1 % error in the friction cone, which therefore fails
these tests (mutations tried for issue 22: a ``1 + 1e-2`` slack in ``Newton.cone_violations``, MuJoCo's
pair friction x 1.01 in the planar and the K-finger dynamics, and in the sphere skip's cone).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import solve_chain
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.dynamics import DYN_TOL, DYN_TOL_PER_WEIGHT
from simgrip.gripper.settle import settle_gripper
from simgrip.gripper.scene import build_gripper

N = 16  # the resolution the other hold/drop tests use
KAPPA = {"I": -6.0, "II": 5.0, "III": -5.5}  # Grip III at -5.5: tip clear of the workpiece (condition (23))
#: Relative agreement of the Newton settle's required mu with the chain's (see the module docstring).
NEWTON_AGREE = 1e-6
NEWTON_BAND = 1e-5
#: The dynamics' creep floor relative to the weight, and its band.
DYN_AGREE = max(DYN_TOL / STANDARD.M, DYN_TOL_PER_WEIGHT)
DYN_BAND = 1e-3
III_NEWTON_BAND = 1e-4
#: A Grip III contact that has not slid moves by round-off (measured 0 for Newton, 2.5e-9 l for the dynamics'
#: creep); one that slid moved by >= 7e-6 (Newton, at the band) or dropped (the dynamics).
STUCK, SLID = 1e-8, 1e-6


def _need_i_ii(grip, tip_x, moment, n=N, kappa=None, beta=0.0):
    """The chain's required mu with its tip at ``X = tip_x`` and tip couple ``moment``, along a face whose
    normal is ``beta`` above horizontal (a sphere's contact angle; 0 for a vertical face)."""
    ch = solve_chain(grip, STANDARD.replace(b=2.0 * tip_x), Uniform(KAPPA[grip] if kappa is None else kappa), n,
                     contact_moment=moment)
    c, s = math.cos(beta), math.sin(beta)
    normal, friction = ch.N1 * c + ch.N2 * s, -ch.N1 * s + ch.N2 * c
    assert normal > 0
    return abs(friction) / normal


def _need_iii(st, n=N):
    """Grip III: the chain at the settled state's own ``gamma`` and ``X(gamma)``, read in the carrying link's
    frame (MuJoCo's contact frame, where the cone is tested)."""
    c = st.contact
    ch = solve_chain("III", STANDARD.replace(b=2.0 * c.point[0]), Uniform(KAPPA["III"]), n, gamma=c.gamma,
                     contact_moment=c.moment)
    phi = ch.link_angles[min(int(c.gamma * n), n - 1)]
    t = np.array([math.cos(phi), math.sin(phi)])
    F = np.array([ch.N1, ch.N2])
    normal = float(F @ np.array([-t[1], t[0]]))
    assert normal > 0
    return abs(float(F @ t)) / normal


def _planar(grip, mu_s, method, contact=None):
    kw = {} if contact is None else dict(contact=contact)
    return settle(build_scene(grip, STANDARD.replace(mu_s=mu_s), Uniform(KAPPA[grip]), N), method=method, **kw)


def _assert_dropped_to_the_free_chain(st, atol):
    free = solve_chain("free", STANDARD, Uniform(KAPPA[st.grip]), N)
    np.testing.assert_allclose(st.link_angles[0], free.link_angles, atol=atol)


# ---------------------------------------------------------------------------
# planar settle, Grips I and II


@pytest.mark.parametrize("contact", ["point", "surface"])
@pytest.mark.parametrize("grip", ["I", "II"])
def test_newton_holds_just_above_and_drops_just_below_the_chains_threshold(grip, contact):
    st = _planar(grip, STANDARD.mu_s, "newton", contact)
    assert st.held and st.converged and st.tolerance <= 1e-6
    need = _need_i_ii(grip, st.tip[0, 0], st.contact.moment)
    assert abs(st.contact.required_mu_contact / need - 1) < NEWTON_AGREE
    above = _planar(grip, need * (1 + NEWTON_BAND), "newton", contact)
    assert above.held and above.converged
    below = _planar(grip, need * (1 - NEWTON_BAND), "newton", contact)
    assert not below.held and below.converged
    _assert_dropped_to_the_free_chain(below, 1e-8)


@pytest.mark.parametrize("grip", ["I", "II"])
def test_dynamics_holds_just_above_and_drops_just_below_the_chains_threshold(grip):
    st = _planar(grip, STANDARD.mu_s, "dynamics")
    assert st.held and st.converged and st.residual <= max(DYN_TOL, DYN_TOL_PER_WEIGHT * STANDARD.M)
    need = _need_i_ii(grip, st.tip[0, 0], st.contact.moment)
    assert abs(st.contact.required_mu_contact / need - 1) < 5 * DYN_AGREE
    above = _planar(grip, need * (1 + DYN_BAND), "dynamics")
    assert above.held and above.converged
    below = _planar(grip, need * (1 - DYN_BAND), "dynamics")
    assert not below.held and below.converged
    _assert_dropped_to_the_free_chain(below, 1e-5)  # the dynamics' stop test (as tests/test_settle_dynamics)


# ---------------------------------------------------------------------------
# planar settle, Grip III: a contact below its threshold slides (and sticks again further on, or drops)


@pytest.mark.parametrize("method, band, agree", [("newton", III_NEWTON_BAND, NEWTON_AGREE),
                                                 ("dynamics", DYN_BAND, 5 * DYN_AGREE)])
def test_grip_iii_sticks_just_above_and_slides_just_below_the_chains_threshold(method, band, agree):
    st = _planar("III", STANDARD.mu_s, method)
    assert st.held and st.converged and st.tip_clear
    need = _need_iii(st)
    assert abs(st.contact.required_mu_contact / need - 1) < agree
    gamma0 = st.contact.gamma
    above = _planar("III", need * (1 + band), method)
    assert above.held and above.converged and abs(above.contact.gamma - gamma0) < STUCK
    below = _planar("III", need * (1 - band), method)
    assert below.converged
    assert not below.held or abs(below.contact.gamma - gamma0) > SLID


# ---------------------------------------------------------------------------
# the K-finger gripper: the symmetry skip (planar Newton; a sphere's own cone) and the K-finger dynamics

GRIPPERS = [("I", 3, "cylinder", None), ("II", 2, "box", None), ("I", 3, "sphere", -0.1), ("II", 3, "sphere", -0.2)]


def _gripper(grip, K, shape, beta, mu_s, method):
    kw = {} if beta is None else dict(contact_angle=beta)
    sc = build_gripper(grip, STANDARD.replace(mu_s=mu_s), Uniform(KAPPA[grip]), N, fingers=K, workpiece=shape, **kw)
    return settle_gripper(sc, method=method)


@pytest.mark.parametrize("method, band, agree", [("symmetric", NEWTON_BAND, NEWTON_AGREE),
                                                 ("dynamics", DYN_BAND, 5 * DYN_AGREE)])
@pytest.mark.parametrize("grip, K, shape, beta", GRIPPERS)
def test_gripper_holds_just_above_and_drops_just_below_the_chains_threshold(grip, K, shape, beta, method, band,
                                                                            agree):
    st = _gripper(grip, K, shape, beta, STANDARD.mu_s, method)
    assert st.held and st.converged and st.method == method and len(st.records) == K
    for rec in st.records:  # every finger is the same chain (symmetric scenes)
        need = _need_i_ii(grip, rec.tip[0], rec.moment, beta=rec.contact_angle if shape == "sphere" else 0.0)
        assert abs(rec.required_mu / need - 1) < agree
    need = _need_i_ii(grip, st.records[0].tip[0], st.records[0].moment,
                      beta=st.records[0].contact_angle if shape == "sphere" else 0.0)
    above = _gripper(grip, K, shape, beta, need * (1 + band), method)
    assert above.held and above.converged
    below = _gripper(grip, K, shape, beta, need * (1 - band), method)
    assert not below.held and below.converged
