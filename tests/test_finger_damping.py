"""The pick environments' finger dynamics (issue 20, item 3): damping model, integrator, release and command step.

The default ``simgrip/Pick-v1`` hand is settled with its palm held high (no contact), linearised about that
state (:func:`simgrip.envs.finger_dynamics.linearise`: palm slide and the 24 hinges) and released.  Three
levels are compared:

* the damping model: ``C = tau K_s`` on the hinges (``finger_damping_time``), stiffness-proportional, so
  ``zeta_i = omega_i tau / 2`` exactly without gravity (:func:`test_damping_is_rayleigh_without_gravity`);
* the continuous-time poles of ``(M, C, K)`` against the discrete map of MuJoCo's step (semi-implicit Euler,
  damping implicit): they differ at first order in ``dt`` (:func:`test_integrator_error_is_first_order`);
* the nonlinear MuJoCo model released along one pole's discrete eigenvector, its tip height fitted
  (:func:`test_release_decay_matches_discrete_poles`).

``DOC`` holds the figures the docstrings of ``envs/pick.py`` and ``envs/pick_multi.py`` state; the tests
measure them and check both that the docstrings still say them and that the measurement rounds to them.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip.envs import finger_dynamics as fd
from simgrip.envs.pick import PickEnv

PALM_HIGH = 0.2  # [m]: the curled or sagging fingers stay 8 cm above the 6 cm box
SETTLE_STEPS = 1500  # 3 s: the slowest pole decays at ~22/s, exp(-66) leaves nothing

#: The figures the environments' docstrings state, as written there, with the tolerance each is measured to
#: (half a unit of the last digit written: the docstring rounds the measurement).
DOC = {
    # the finger's first mode (fingers in antiphase, the palm still): continuous model, MuJoCo at dt = 2 ms
    "f_still": ("7.66 Hz", 7.66, 0.005),
    "zeta_still": ("zeta = 0.479", 0.479, 0.0005),
    "f_still_step": ("7.50 Hz", 7.50, 0.005),
    "zeta_still_step": ("zeta = 0.469", 0.469, 0.0005),
    # the fingers in phase, the palm servo taking part
    "f_phase": ("7.62 Hz", 7.62, 0.005),
    "zeta_phase": ("zeta = 0.476", 0.476, 0.0005),
    "f_phase_step": ("7.46 Hz", 7.46, 0.005),
    "zeta_phase_step": ("zeta = 0.465", 0.465, 0.0005),
    "f_phase_damped": ("damped 6.60 Hz", 6.60, 0.005),
    "wmax_dt": ("omega_max dt = 0.48", 0.48, 0.005),
    "settle": ("0.18 s", 0.18, 0.005),
    "reset_left": ("11 %", 0.11, 0.005),
    "t63": ("0.10 s", 0.10, 0.005),
    # the clamped finger (finger 0's hinges) without and with the armature: first and second mode
    "f1_no_armature": ("7.90 Hz", 7.90, 0.005),
    "f2_no_armature": ("48.7 Hz", 48.7, 0.05),
    "f2": ("26.0 Hz", 26.0, 0.05),
    "wmax_dt_no_armature": ("omega_max dt = 21", 21.0, 0.5),
    "cmd_settle": ("0.40 s", 0.40, 0.005),
}
#: PickMulti-v0's (K = 3) in-phase pair; its other pairs are the finger's own (``f_still``)
DOC_MULTI = {"f_phase": ("7.60 Hz", 7.60, 0.005), "zeta_phase": ("zeta = 0.474", 0.474, 0.0005)}


def _doc(cls) -> str:
    """``cls``'s docstring with its line breaks and indentation as single spaces."""
    return " ".join(cls.__doc__.split())


def _probe(env):
    """The tip's height above the palm [m] from ``qpos`` (``geom_xpos`` after ``mj_step`` is a step stale)."""
    tip, palm = int(env.fingers.tip_geom[0]), env.palm_qpos
    scratch = mujoco.MjData(env.model)

    def probe(d):
        scratch.qpos[:] = d.qpos
        mujoco.mj_kinematics(env.model, scratch)
        return scratch.geom_xpos[tip, 2] - d.qpos[palm]

    return probe


def _settled(env, kappa=0.0):
    env.reset(seed=0, options={"palm_height": PALM_HIGH})
    env._set_rest(kappa, kappa)
    mujoco.mj_step(env.model, env.data, SETTLE_STEPS)
    assert env.data.ncon == 0 or not np.any(np.isin(env.data.contact.geom, env.fingers.link_geom))
    return env


def _dofs(env):
    return np.concatenate([[env.palm_dof], env.fingers.joint_dof.ravel()])


@pytest.fixture(scope="module")
def pick():
    env = _settled(PickEnv())
    lin = fd.linearise(env.model, env.data, _dofs(env))
    return env, lin


def test_model_is_what_the_docstring_says(pick):
    """C on the hinges is finger_damping_time times the hinge stiffness, diagonal; the armature is on M's
    diagonal; the step is implicitfast (the damping implicit)."""
    env, lin = pick
    m = env.model
    hinges = env.fingers.joint_dof.ravel()
    k = m.jnt_stiffness[m.dof_jntid[hinges]]
    Ch = lin.C[1:, 1:]
    # FD of a linear function of qvel: exact to round-off, ~1e-10 of the entries
    np.testing.assert_allclose(np.diag(Ch), env.finger_damping_time * k, rtol=1e-7)
    assert np.abs(Ch - np.diag(np.diag(Ch))).max() <= 1e-9 * np.abs(Ch).max()
    np.testing.assert_array_equal(m.dof_armature[hinges], env.finger_armature)
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_armature_effect():
    """The armature's share of the clamped finger's modes, and the stability it buys (without it omega_max dt >> 2:
    only the implicit damping keeps the step stable)."""
    for armature, keys in ((0.0, ("f1_no_armature", "f2_no_armature")), (1e-5, ("f_still", "f2"))):
        env = _settled(PickEnv(finger_armature=armature))
        lin = fd.linearise(env.model, env.data, env.fingers.joint_dof[0])
        w, _ = fd.modal_damping(lin.M, lin.K, lin.C)
        for key, value in zip(keys, w[:2] / (2 * math.pi)):
            assert value == pytest.approx(DOC[key][1], abs=DOC[key][2]), key
        if armature == 0.0:
            assert w[-1] * lin.dt == pytest.approx(DOC["wmax_dt_no_armature"][1], abs=DOC["wmax_dt_no_armature"][2])
            assert np.abs(np.linalg.eigvals(fd.discrete_map(lin.M, lin.C, lin.K, lin.dt))).max() < 1.0


def test_damping_is_rayleigh_without_gravity():
    """With gravity off and the palm held (finger 0's hinges), K = K_s and the damping is Rayleigh: every mode's
    zeta_i = omega_i tau / 2 and the quadratic eigenproblem's poles are -zeta w +- i w sqrt(1 - zeta^2)."""
    env = PickEnv()
    env.model.opt.gravity[:] = 0.0
    env = _settled(env)
    dofs = env.fingers.joint_dof[0]
    lin = fd.linearise(env.model, env.data, dofs)
    w, zeta = fd.modal_damping(lin.M, lin.K, lin.C)
    tau = env.finger_damping_time
    np.testing.assert_allclose(zeta, w * tau / 2, rtol=1e-6)  # K and C from FD: ~1e-9
    s = fd.continuous_poles(lin.M, lin.C, lin.K)
    under = zeta < 1
    expect = -zeta[under] * w[under] + 1j * w[under] * np.sqrt(1 - zeta[under] ** 2)
    np.testing.assert_allclose(s[:under.sum()], expect, rtol=1e-6)


def test_integrator_error_is_first_order(pick):
    """The discrete map's poles approach the continuous ones at first order in dt (ratio 2 per halving), and the
    first pair's decay rate is low by zeta omega dt (|mu|^2 = 1/(1 + 2 zeta omega dt) for one mode)."""
    _, lin = pick
    sc = fd.continuous_poles(lin.M, lin.C, lin.K)[0]
    errs = [abs(fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt / 2**j)[0] - sc) for j in range(4)]
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    # first order: ratio 2 up to the next term, O(omega dt) ~ 0.1 at dt = 2 ms
    np.testing.assert_allclose(ratios, 2.0, atol=0.12)
    sd = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt)[0]
    omega, zeta = abs(sc), -sc.real / abs(sc)
    one_mode = math.log1p(2 * zeta * omega * lin.dt) / (2 * lin.dt)
    # the one-mode formula neglects the (small) non-proportional coupling to the overdamped modes
    assert -sd.real == pytest.approx(one_mode, rel=5e-3)


def test_stable_step_margin(pick):
    """The highest undamped mode's omega dt and the implicit damping's unconditional stability (tau > dt/2)."""
    env, lin = pick
    w, _ = fd.modal_damping(lin.M, lin.K, lin.C)
    _, value, tol = DOC["wmax_dt"]
    assert w[-1] * lin.dt == pytest.approx(value, abs=tol)
    assert w[-1] * lin.dt < 2.0  # stable even without damping
    assert env.finger_damping_time > lin.dt / 2
    mu = np.abs(np.linalg.eigvals(fd.discrete_map(lin.M, lin.C, lin.K, lin.dt)))
    assert mu.max() < 1.0


@pytest.mark.parametrize("pole", [0, 1, 2])
def test_release_decay_matches_discrete_poles(pick, pole):
    """Released along the discrete eigenvector of pole 0 (first pair in phase, the palm servo taking part), 1
    (first pair in antiphase, the palm still) or 2 (the slowest real pole: the higher modes are overdamped), the
    MuJoCo finger's tip height decays at the predicted rate and frequency."""
    env, lin = pick
    m, d = env.model, env.data
    base_q, base_v = d.qpos.copy(), d.qvel.copy()
    sd, V = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt, vectors=True)
    n = lin.dofs.size
    vec = V[:, pole] / np.abs(V[:n, pole]).max() * 1e-3  # 1 mrad: the nonlinearity shifts poles by O(1e-3)
    probe = _probe(env)
    y0 = probe(d)
    try:
        t, y = fd.release(m, d, lin.dofs, vec[:n].real, vec[n:].real, 0.4, lambda dd: probe(dd) - y0)
    finally:
        d.qpos[:], d.qvel[:] = base_q, base_v
    if sd[pole].imag > 0:
        fit = fd.fit_damped_cosine(t, y, sd[pole])
        tol = 1e-3  # O(amplitude) = 1e-3 nonlinearity; measured ~3e-5
    else:
        keep = t <= 0.12  # 6.7 time constants, before round-off of the decayed signal
        fit = fd.fit_exponential(t[keep], y[keep])
        # the 1e-3 of the nonlinearity excites the neighbouring real poles (4 % apart) as well
        tol = 5e-3
    assert fit.residual < 10 * tol
    assert abs(fit.pole - sd[pole]) <= tol * abs(sd[pole])


def _continuous_eig(lin):
    """Continuous poles (Im >= 0) and eigenvectors (displacement part) of ``lin``."""
    n = lin.dofs.size
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(lin.M, lin.K), -np.linalg.solve(lin.M, lin.C)]])
    s, V = np.linalg.eig(A)
    keep = s.imag >= -1e-9 * np.abs(s)
    return s[keep], V[:n, keep]


def _first_pair(s, V, still: bool):
    """The slowest-decaying complex pair whose palm share (the palm's displacement over the largest) is ~0
    (``still``: the fingers in antiphase) or not (in phase); None if there is none."""
    x = np.abs(V)
    share = x[0] / x.max(axis=0)
    ok = (s.imag > 0) & ((share < 1e-6) if still else (share > 1e-3))
    if not ok.any():
        return None
    cand = s[ok]
    return cand[np.argmax(cand.real)]


def _palm_share(lin, pole):
    """The palm's share of discrete pole ``pole``'s displacement (0: the palm still)."""
    _, V = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt, vectors=True)
    x = np.abs(V[:lin.dofs.size, pole])
    return x[0] / x.max()


def _first_pairs(lin):
    """``(still, phase)``: the continuous and discrete poles of the first pair with the palm still and in phase."""
    sc, Vc = _continuous_eig(lin)
    sd, Vd = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt, vectors=True)
    return tuple((_first_pair(sc, Vc, still), _first_pair(sd, Vd[:lin.dofs.size], still)) for still in (True, False))


def _figures(sc, sd, prefix):
    return {f"f_{prefix}": abs(sc) / (2 * math.pi), f"zeta_{prefix}": -sc.real / abs(sc),
            f"f_{prefix}_step": abs(sd) / (2 * math.pi), f"zeta_{prefix}_step": -sd.real / abs(sd)}


def test_documented_first_mode(pick):
    """The first pairs' figures as the docstrings state them: the continuous model's and MuJoCo's at dt.  Only
    the first pair of each symmetry is underdamped: the third pole is real."""
    env, lin = pick
    (sc_s, sd_s), (sc_p, sd_p) = _first_pairs(lin)
    measured = {**_figures(sc_s, sd_s, "still"), **_figures(sc_p, sd_p, "phase"),
                "f_phase_damped": sd_p.imag / (2 * math.pi)}
    for key, value in measured.items():
        _, doc_value, tol = DOC[key]
        assert value == pytest.approx(doc_value, abs=tol), key
    sd = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt)
    assert sd[1].imag > 0 and sd[2].imag == 0
    assert fd.continuous_poles(lin.M, lin.C, lin.K)[2].imag == 0


@pytest.mark.parametrize("kappa, label, freq, zeta", [(-3.0, "kappa_bar = -3: 9.30 Hz, zeta = 0.555", 9.30, 0.555),
                                                      (-6.0, "-6: 14.17 Hz, zeta = 0.891", 14.17, 0.891),
                                                      (-10.0, "-10: overdamped", None, None)])
def test_curled_finger(kappa, label, freq, zeta):
    """Curled, the finger's first mode (palm still, continuous model) stiffens and damps more, as the docstring
    says (to half a unit of its last digit); fully curled it is overdamped."""
    env = _settled(PickEnv(), kappa)
    lin = fd.linearise(env.model, env.data, _dofs(env))
    (still, _), _ = _first_pairs(lin)
    assert label in _doc(PickEnv)
    if freq is None:
        assert still is None
    else:
        assert abs(still) / (2 * math.pi) == pytest.approx(freq, abs=0.005)
        assert -still.real / abs(still) == pytest.approx(zeta, abs=0.0005)


def test_pick_multi_finger_is_the_same():
    """PickMulti-v0 (K = 3): its palm-still pairs are Pick-v1's finger mode (same finger), its in-phase pair is
    shifted by the palm servo carrying three fingers."""
    from simgrip.envs.pick_multi import PickMultiEnv

    env = PickMultiEnv()
    env.reset(seed=0, options={"palm_height": PALM_HIGH})
    mujoco.mj_step(env.model, env.data, SETTLE_STEPS)
    lin = fd.linearise(env.model, env.data, _dofs(env))
    (sc_s, sd_s), (sc_p, _) = _first_pairs(lin)
    for key, value in _figures(sc_s, sd_s, "still").items():
        assert value == pytest.approx(DOC[key][1], abs=DOC[key][2]), key
    assert abs(sc_p) / (2 * math.pi) == pytest.approx(DOC_MULTI["f_phase"][1], abs=DOC_MULTI["f_phase"][2])
    assert -sc_p.real / abs(sc_p) == pytest.approx(DOC_MULTI["zeta_phase"][1], abs=DOC_MULTI["zeta_phase"][2])


def test_reset_settling_time():
    """Fingers released straight (as ``reset`` starts them) reach their sag within 2 % after the documented
    time; the envelope of the slowest pole predicts it to within half a damped period."""
    env = PickEnv()
    env.reset(seed=0, options={"palm_height": PALM_HIGH})
    m, d = env.model, env.data
    mujoco.mj_resetData(m, d)
    env._set_rest(0.0, 0.0)
    d.qpos[env.palm_qpos] = d.ctrl[0] = PALM_HIGH
    d.qpos[env.box_qpos:env.box_qpos + 4] = [0.0, 0.0, 0.03, 1.0]
    probe = _probe(env)
    mujoco.mj_forward(m, d)
    start = probe(d)
    t, y = fd.release(m, d, [env.palm_dof], [0.0], [0.0], 1.0, probe)
    ts = fd.settling_time(t, y, y[-1])
    _, value, tol = DOC["settle"]
    assert ts == pytest.approx(value, abs=tol)
    lin = fd.linearise(m, d, _dofs(env))
    s1 = fd.discrete_poles(lin.M, lin.C, lin.K, lin.dt)[0]
    envelope = math.log(50.0) / -s1.real
    assert abs(ts - envelope) <= math.pi / s1.imag
    # what reset's settle_time leaves of the transient
    left = abs(y[env.settle_steps - 1] - y[-1]) / abs(start - y[-1])
    _, value, tol = DOC["reset_left"]
    assert left == pytest.approx(value, abs=tol)


def test_command_step_response(pick):
    """A step of the curvature command through ``env.step``: the tip follows the first-order lag (kappa_tau,
    held per control step) filtered by the finger's linear model; t63 and the 2 % settling time."""
    env = _settled(PickEnv())
    m, d = env.model, env.data
    lin = fd.linearise(m, d, _dofs(env))
    B = fd.input_force(m, d, lin.dofs, lambda u: env._set_rest(u, u), 0.0)
    probe = _probe(env)
    J = fd.output_row(m, d, lin.dofs, probe)
    y0 = probe(d)
    dk = -0.05  # a small step: linear to ~dk, the tip moves 2.5 mm
    action = np.array([1.0 + 2.0 * dk / (env.kappa_range[1] - env.kappa_range[0]), 0.0])
    steps = 40
    y = []
    for _ in range(steps):
        env.step(action)
        y.append(probe(d) - y0)
    y = np.array(y)
    u = dk * (1.0 - (1.0 - env._lag_alpha) ** np.arange(1, steps + 1))
    lin_y = fd.forced_response(lin, B, u, env.frame_skip)[env.frame_skip - 1::env.frame_skip] @ J
    static = J @ np.linalg.solve(lin.K, B * dk)
    # the linear model to O(dk) = 5 % of the step's own nonlinearity, times the 2.5 mm scale: 0.5 % is met at 0.2 %
    assert np.abs(y - lin_y).max() <= 5e-3 * abs(static)
    tc = env.dt * np.arange(1, steps + 1)
    frac = y / static
    i = int(np.argmax(frac >= 1 - math.exp(-1)))
    t63 = tc[i - 1] + (1 - math.exp(-1) - frac[i - 1]) / (frac[i] - frac[i - 1]) * env.dt
    # lag alone: kappa_tau; the finger adds its mean delay 2 zeta / omega_n (~20 ms)
    _, value, tol = DOC["t63"]
    assert t63 == pytest.approx(value, abs=tol)
    _, value, tol = DOC["cmd_settle"]
    assert fd.settling_time(tc, y, static) == pytest.approx(value, abs=tol)


def test_docstrings_state_the_figures():
    from simgrip.envs.pick_multi import PickMultiEnv

    for label, _, _ in DOC.values():
        assert label in _doc(PickEnv), label
    for key in ("f_still", "zeta_still"):
        assert DOC[key][0] in _doc(PickMultiEnv), key
    for label, _, _ in DOC_MULTI.values():
        assert label in _doc(PickMultiEnv), label


def test_bad_input():
    env = PickEnv()
    with pytest.raises(ValueError, match="dofs"):
        fd.linearise(env.model, env.data, [env.model.nv])
    with pytest.raises(ValueError, match="dofs"):
        fd.linearise(env.model, env.data, [env.box_dof])  # a free joint's dof
    with pytest.raises(ValueError, match="t and y"):
        fd.fit_exponential([0.0, 1.0], [1.0, 0.5])
    with pytest.raises(ValueError, match="one sign"):
        fd.fit_exponential(np.arange(10.0), np.cos(np.arange(10.0)))
    with pytest.raises(ValueError, match="band"):
        fd.settling_time(np.arange(10.0), np.ones(10), 1.0, band=2.0)
    with pytest.raises(ValueError, match="duration"):
        fd.release(env.model, env.data, [env.palm_dof], [0.0], [0.0], -1.0, lambda d: 0.0)
    with pytest.raises(ValueError, match="hold"):
        fd.forced_response(fd.linearise(env.model, env.data, [env.palm_dof]), [1.0], [1.0], 0)
