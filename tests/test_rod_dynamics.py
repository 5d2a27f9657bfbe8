"""The hinge chain's dynamics against an independent continuous rod (issue 20, item 4).

Case: the curled heavy rod (kappa_bar0 = -3, D = 1, l = rho = g = 1) held in its weightless shape (the circle
arc theta = -3 s, which meets the free end's theta'(1) = kappa0) and released under gravity, with
Kelvin-Voigt damping tau = 0.03 sqrt(l/g) (the chain's hinge damping ``tau * stiffness`` discretises it).
The peer is :mod:`simgrip.reference.rod_dynamics` (spectral Galerkin in theta, inextensible, no shear, no
rotary inertia; implicit midpoint in time); the chain is simgrip's MuJoCo scene (``build_scene("free")``,
``implicitfast``).

Orders.  The chain is second order in ``ds = 1/n`` (midpoint masses and springs, :mod:`simgrip.chain`; its
link rotary inertia ``rho ds^3/12`` is O(ds^2) too); its time step (4e-4, first order in the implicit
damping) adds ``zeta omega dt ~ 1e-5``.  The peer converges spectrally in its modes (8 and 12 modes agree to
1e-9) and at second order in its step: its error is estimated in the test as 4/3 of the change from halving
the step (~1e-6).  The chain's error at ``n`` may then be its n = 16 error scaled by ``(16/n)^2`` (x 1.3 for
the next order term) plus the peer's estimated error.  Frequencies and damping are compared on the
linearisations about the equilibrium, order 2 in ``n``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip.envs import finger_dynamics as fd
from simgrip.params import DimensionlessParams
from simgrip.reference.rod_dynamics import equilibrium, linear_poles, rod_dynamics, simulate
from simgrip.scenes import build_scene
from simgrip.sim.scene import DEFAULT_R_LINK

KAPPA, D, TAU = -3.0, 1.0, 0.03
T_END = 4.3  # three periods of the first mode (omega_d = 4.44)
TIMES = np.round(np.arange(0.0, T_END + 1e-9, 0.02), 10)
CHAIN_DT = 4e-4
#: the peer's time step: implicit midpoint, phase error (omega dt)^2/24 ~ 1e-5 for the first mode, per radian
PEER_DT = 2e-3


def chain_scene(n, r_link=DEFAULT_R_LINK):
    scene = build_scene("free", DimensionlessParams(D=D), KAPPA, n, r_link=r_link)
    m = scene.model
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    m.opt.timestep = CHAIN_DT
    m.dof_damping[:] = TAU * m.jnt_stiffness[m.dof_jntid]
    return scene


def chain_tip(qpos_hinges, n):
    phi = np.cumsum(qpos_hinges)
    return np.array([np.cos(phi).sum(), np.sin(phi).sum()]) / n


def chain_run(n):
    """The chain's tip at TIMES, released from its weightless shape (hinges at their rest angles)."""
    scene = chain_scene(n)
    m, d = scene.model, mujoco.MjData(scene.model)
    qa = np.asarray(scene.joint_qpos[0])
    d.qpos[qa] = m.qpos_spring[qa]
    steps = np.rint(TIMES / CHAIN_DT).astype(int)
    out, k = [], 0
    for step in range(steps[-1] + 1):
        if step == steps[k]:
            out.append(chain_tip(d.qpos[qa], n))
            k += 1
        if k == steps.size:
            break
        mujoco.mj_step(m, d)
    return np.array(out)


def peer_run(modes, dt):
    rod = rod_dynamics(D, KAPPA, modes=modes, tau=TAU)
    a0 = np.zeros(modes)
    a0[0] = KAPPA / 2  # phi_1 = 2 s: theta = kappa s
    return simulate(rod, TIMES, a0, dt=dt)


@pytest.fixture(scope="module")
def peer():
    """The peer's tip at TIMES (12 modes, PEER_DT) and its estimated error: Richardson in the step (second
    order: 4/3 of the change from 2 PEER_DT); the modes' error is spectral (1e-9 from 8 to 12 modes, and
    :func:`test_linear_frequency_and_damping_converge`)."""
    fine, coarse = peer_run(12, PEER_DT), peer_run(12, 2 * PEER_DT)
    return fine, float(np.abs(fine - coarse).max() * 4 / 3)


def test_peer_statics_match_the_bvp():
    """The peer's equilibrium is the elastica BVP's (spectral: 1e-8 at 16 modes) and its tip is the
    static limit the release decays to."""
    from simgrip.reference.elastica import solve

    bvp = solve("free", DimensionlessParams(D=D), KAPPA, tol=1e-10)
    tip = np.asarray(bvp.position_at(1.0), dtype=float).ravel()
    rod = rod_dynamics(D, KAPPA)
    np.testing.assert_allclose(rod.tip(equilibrium(rod)), tip[:2], atol=1e-8)


def test_peer_converges(peer):
    """Its own estimated error is well below the chain's at n = 64 (so the comparison resolves the chain)."""
    _, err = peer
    assert err < 1e-5  # measured 4e-6; the chain's n = 64 error is ~20 times larger


def test_chain_tip_trajectory_converges_to_the_peer(peer):
    fine, peer_err = peer
    errs = {n: float(np.abs(chain_run(n) - fine).max()) for n in (16, 32, 64)}
    for n in (32, 64):
        assert errs[n] <= 1.3 * errs[16] * (16 / n) ** 2 + peer_err, (n, errs)
    order = math.log2(errs[16] / errs[32])
    assert 1.8 <= order <= 2.4, errs  # measured 2.07
    assert errs[64] < 1e-4  # of l, over three periods; the motion's amplitude is 1.2e-2


def _chain_equilibrium(scene):
    """The chain's static equilibrium by Newton on MuJoCo's own forces (its K from finite differences)."""
    m, d = scene.model, mujoco.MjData(scene.model)
    qa, dofs = np.asarray(scene.joint_qpos[0]), np.asarray(scene.joint_dof[0])
    d.qpos[qa] = m.qpos_spring[qa]
    lin = fd.linearise(m, d, dofs)
    for _ in range(60):  # simplified Newton (K of the start): linear convergence, ~10 iterations
        mujoco.mj_forward(m, d)
        dq = np.linalg.solve(lin.K, (d.qfrc_passive - d.qfrc_bias)[dofs])
        d.qpos[qa] += dq
        if np.abs(dq).max() < 1e-12:
            return d, fd.linearise(m, d, dofs)
    raise AssertionError("chain equilibrium: Newton did not converge")


def test_linear_frequency_and_damping_converge():
    """The first pole of the chain's linearisation (MuJoCo's M, C, K) converges at second order to the peer's
    (spectral).  The links' capsule radius gives the chain a rotary inertia ``rho r^2/4`` per length the line
    of mass lacks (a thick rod's, not a discretisation error): it is made negligible here (r = 1e-6 l) to
    show the order, and its share at the default radius is bounded."""
    rod = rod_dynamics(D, KAPPA, modes=12, tau=TAU)
    s_ref = linear_poles(rod, equilibrium(rod))[0]
    rod8 = rod_dynamics(D, KAPPA, modes=8, tau=TAU)
    assert abs(linear_poles(rod8, equilibrium(rod8))[0] - s_ref) < 1e-7 * abs(s_ref)  # spectral
    errs = {}
    for n in (16, 32, 64):
        _, lin = _chain_equilibrium(chain_scene(n, r_link=1e-6))
        s = fd.continuous_poles(lin.M, lin.C, lin.K)[0]
        errs[n] = abs(s - s_ref) / abs(s_ref)
    assert 1.9 <= math.log2(errs[16] / errs[32]) <= 2.1 and 1.9 <= math.log2(errs[32] / errs[64]) <= 2.1, errs
    assert errs[64] < 2e-5  # measured 1.1e-5: (16/64)^2 of n = 16's 1.7e-4
    _, lin = _chain_equilibrium(chain_scene(64))
    thick = abs(fd.continuous_poles(lin.M, lin.C, lin.K)[0] - s_ref) / abs(s_ref)
    # the rotary inertia's share: (k r)^2 / 8 with the mode's wavenumber k ~ 2, r = DEFAULT_R_LINK
    assert abs(thick - errs[64]) <= (2.0 * DEFAULT_R_LINK) ** 2


def test_bad_input():
    with pytest.raises(ValueError, match="D must"):
        rod_dynamics(-1.0, KAPPA)
    with pytest.raises(ValueError, match="tau must"):
        rod_dynamics(D, KAPPA, tau=float("nan"))
    with pytest.raises(ValueError, match="modes must"):
        rod_dynamics(D, KAPPA, modes=1)
    with pytest.raises(ValueError, match="points must"):
        rod_dynamics(D, KAPPA, modes=8, points=4)
    with pytest.raises(ValueError, match="kappa0 must"):
        rod_dynamics(D, lambda s: np.full_like(s, np.inf))
    rod = rod_dynamics(D, KAPPA, modes=4)
    with pytest.raises(ValueError, match="times must"):
        simulate(rod, [0.1, 0.05])
    with pytest.raises(ValueError, match="grid of dt"):
        simulate(rod, [0.0, 0.0031], dt=2e-3)
    with pytest.raises(ValueError, match="a0 must"):
        simulate(rod, [0.0, 0.002], np.zeros(3))
    with pytest.raises(ValueError, match="dt must"):
        simulate(rod, [0.0], dt=0.0)


def pyelastica_tip(n_elem: int, radius: float = 0.02) -> np.ndarray:
    """PyElastica's Cosserat rod (``n_elem`` elements, undamped) released from the weightless arc under gravity:
    the tip ``(X, Y)`` at TIMES.  ``rho A = EI = 1``: ``E = 4/(pi r^4)``, ``G = E/3``; extension ``EA =
    4/r^2``, shear ``G A = EA/3``, rotary inertia ``rho I = r^2/4`` (all absent from the peer and the chain:
    relative effects ``~ (k r)^2`` with the mode's wavenumber ``k ~ 2``).  The clamp holds the first element's
    director (PositionVerlet, step a fifth of the axial wave's ``ds / c``, ``c = 2/r``)."""
    import elastica as ea

    class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.CallBacks):
        pass

    area, inertia = math.pi * radius**2, math.pi * radius**4 / 4
    rod = ea.CosseratRod.straight_rod(n_elem, np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 1.0,
                                      radius, 1.0 / area, youngs_modulus=1.0 / inertia,
                                      shear_modulus=1.0 / (3 * inertia))
    ds = 1.0 / n_elem
    nodes = np.arange(n_elem + 1) * ds
    rod.position_collection[0] = np.sin(KAPPA * nodes) / KAPPA
    rod.position_collection[2] = (1 - np.cos(KAPPA * nodes)) / KAPPA
    th = KAPPA * (np.arange(n_elem) + 0.5) * ds
    zero = np.zeros(n_elem)
    rod.director_collection[0] = [-np.sin(th), zero, np.cos(th)]  # d1: the normal in the x-z plane
    rod.director_collection[1] = [zero, -np.ones(n_elem), zero]   # d2 = d3 x d1 = -y: bending about it is theta
    rod.director_collection[2] = [np.cos(th), zero, np.sin(th)]   # d3: the tangent
    rod.rest_kappa[1, :] = KAPPA
    sim = Sim()
    sim.append(rod)
    sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
    sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -1.0]))
    out = []

    class Tip(ea.CallBackBaseClass):
        def __init__(self, step_skip):
            super().__init__()
            self.every = step_skip

        def make_callback(self, system, time, current_step):
            if current_step % self.every == 0:
                out.append([system.position_collection[0, -1], system.position_collection[2, -1]])

    every = int(math.ceil(0.02 / (0.2 * ds * radius / 2)))
    sim.collect_diagnostics(rod).using(Tip, step_skip=every)
    sim.finalize()
    ea.integrate(ea.PositionVerlet(), sim, float(TIMES[-1]), int(round(TIMES[-1] / (0.02 / every))),
                 progress_bar=False)
    return np.array(out)[:TIMES.size]


def test_pyelastica_peer():
    """PyElastica (optional: ``pip install simgrip[peer]``) against the spectral peer, both undamped.  The
    Cosserat rod's clamp holds its first element (the clamp sits half an element off ``s = 0``), a first-order
    error: it halves from 32 to 64 elements (0.6 allows the next order); the extension, shear and rotary
    inertia add ``~ (k r)^2 ~ 2e-3`` of the motion at r = 0.02."""
    pytest.importorskip("elastica")
    rod = rod_dynamics(D, KAPPA)
    a0 = np.zeros(12)
    a0[0] = KAPPA / 2
    ref = simulate(rod, TIMES, a0, dt=PEER_DT)
    errs = {n: float(np.abs(pyelastica_tip(n) - ref).max()) for n in (32, 64)}
    amplitude = float(np.abs(ref - ref[0]).max())
    assert errs[64] <= 0.6 * errs[32], errs
    assert errs[64] < 0.3 * amplitude, (errs, amplitude)


def test_peer_vibrations_match_the_modes_reference():
    """Undamped, the peer's small vibrations about its equilibrium are :mod:`simgrip.modes`' linearised elastica
    (Chebyshev collocation of the BVP's variational equations: a different method of the same rod)."""
    from simgrip.modes import reference_modes

    ref = reference_modes("free", DimensionlessParams(D=D), KAPPA, 3).omega
    rod = rod_dynamics(D, KAPPA)
    poles = linear_poles(rod, equilibrium(rod))[:3]
    np.testing.assert_allclose(np.abs(poles.real), 0.0, atol=1e-9)
    np.testing.assert_allclose(poles.imag, ref, rtol=1e-7)  # both spectral: agree to ~1e-10
