"""The settle's fixed cost cut without changing a bit (issue 19): each shortcut against what it replaces.

The static solve's bookkeeping was made cheaper (the contact pairs' distances written out instead of
``einsum``/``np.where``, the chain model's topology read once per compiled model, MuJoCo's contact arrays
read through one view, a contact-free state's positions not recomputed at the same state).  Every
shortcut must give exactly what the code it replaced gives: these tests compare them bit for bit.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.chain_model import ChainModel
from simgrip.settle.chain_newton import ChainNewton
from simgrip.sim.contacts import pair_contacts

CASES = [("I", -6.0, 1), ("II", 5.0, 1), ("III", -4.0, 1), ("I", -6.0, 2), ("III", -4.0, 2)]


def _distances_before(cm: ChainModel, phi, nodes, y) -> np.ndarray:
    """``ChainModel.pair_distances`` as it was written before (``einsum`` rows, both branches and ``np.where``)."""
    cm.pair_distances(phi, nodes, y)  # (its per-model arrays)
    O = np.empty((len(cm.pairs), 2))
    A = np.empty(len(cm.pairs))
    for f in range(cm.fingers):
        Of, af, _, _ = cm.pose(f, y)
        mine = cm._pf == f
        O[mine], A[mine] = Of, af
    ca, sa = np.cos(A), np.sin(A)
    gl = cm._gl
    rgl = np.empty_like(gl)
    rgl[:, 0] = ca * gl[:, 0] - sa * gl[:, 1]
    rgl[:, 1] = sa * gl[:, 0] + ca * gl[:, 1]
    c = O + rgl
    a, b = nodes[cm._pf, cm._pl], nodes[cm._pf, cm._pl + 1]
    seg = b - a
    u = np.clip(np.einsum("ij,ij->i", c - a, seg) / np.einsum("ij,ij->i", seg, seg), 0.0, 1.0)
    caps = np.hypot(*(c - a - u[:, None] * seg).T) - cm._rad
    nrm = np.empty_like(gl)
    nrm[:, 0], nrm[:, 1] = ca, sa
    face = np.einsum("ij,ij->i", nrm, b - O) - (np.einsum("ij,ij->i", nrm, rgl) + cm._hx) - cm._rad
    return np.where(cm._sph, face, caps)


@pytest.mark.parametrize("grip,kappa,fingers", CASES)
def test_pair_distances_are_the_einsum_ones_bit_for_bit(grip, kappa, fingers):
    """The written-out row sums are ``einsum``'s, ``(0 + x0 y0) + x1 y1`` (signed zeros too), at the settled state
    and at random states around it, the workpiece moved and turned."""
    sc = build_scene(grip, STANDARD, Uniform(kappa), 12, fingers=fingers)
    settle(sc)
    cm = ChainModel(sc)
    phi0, w0 = cm.split(sc.data.qpos)
    rng = np.random.default_rng(19)
    for k in range(40):
        phi = phi0 + (0.0 if k == 0 else 0.05) * rng.normal(size=phi0.size)
        w = w0 + (0.0 if k == 0 else 0.05) * rng.normal(size=w0.size)
        if k % 7 == 3:
            phi[: phi.size // 2] = 0.0  # straight links: zero products, signed zeros
        nodes = cm.nodes(phi)
        assert cm.pair_distances(phi, nodes, w).tobytes() == _distances_before(cm, phi, nodes, w).tobytes()


def test_pair_contacts_and_the_stick_tangent_are_unchanged():
    """``pair_contacts`` finds the contacts the set comparison found (either geom order); the sticks' tangent is
    ``np.cross((0, 1, 0), normal)`` bit for bit."""
    sc = build_scene("I", STANDARD, Uniform(-6.0), 16, fingers=2)
    st = settle(sc)
    assert st.held
    d = sc.data
    mujoco.mj_forward(sc.model, d)
    assert d.ncon >= 2
    for i in range(sc.model.npair):
        g1, g2 = int(sc.model.pair_geom1[i]), int(sc.model.pair_geom2[i])
        want = [c for c in range(d.ncon) if {int(d.contact.geom1[c]), int(d.contact.geom2[c])} == {g1, g2}]
        assert pair_contacts(d, g1, g2) == want == pair_contacts(d, g2, g1)
    run = ChainNewton(sc)
    run.stick_now()
    assert len(run.sticks) == 2
    for s in run.sticks:
        c = pair_contacts(d, *s.geoms)[0]
        t = np.cross(np.array([0.0, 1.0, 0.0]), np.array(d.contact.frame[c][:3]))
        t /= np.linalg.norm(t)
        assert (d.xmat[s.t_body].reshape(3, 3).T @ t).tobytes() == s.t_local.tobytes()


def test_chain_structure_is_read_once_per_model():
    """The topology the chain model reads is kept per compiled model: the same objects for a second settle of the
    scene, read again when the scene holds another model, and equal to a fresh read."""
    sc = build_scene("III", STANDARD, Uniform(-4.0), 12)
    a, b = ChainModel(sc), ChainModel(sc)
    assert a.link_index is b.link_index and a.pair_link is b.pair_link
    other = build_scene("III", STANDARD, Uniform(-4.0), 12)
    c = ChainModel(other)
    assert c.link_index is not a.link_index
    assert c.link_index == a.link_index and c.pair_link == a.pair_link and c.pairs == a.pairs
    bodies = np.asarray(sc.link_body).reshape(sc.fingers, sc.n)
    assert a.link_index == {int(bd): (f, i) for f in range(sc.fingers) for i, bd in enumerate(bodies[f])}


@pytest.mark.parametrize("grip", ["free", "I"])
def test_settled_data_is_what_a_last_sync_gives(grip):
    """A contact-free state's positions are not computed again at the same state (the judge's balance, the settle's
    last sync): the scene's data after the settle holds exactly what ``mj_kinematics`` and ``mj_comPos`` (free rod)
    or ``mj_forward`` (a grip) give at its ``qpos``."""
    sc = build_scene(grip, STANDARD, Uniform(-3.0 if grip == "free" else -6.0), 16)
    settle(sc)
    m, d = sc.model, sc.data
    fresh = mujoco.MjData(m)
    fresh.qpos[:] = d.qpos
    if grip == "free":
        mujoco.mj_kinematics(m, fresh)
        mujoco.mj_comPos(m, fresh)
    else:
        fresh.qacc_warmstart[:] = d.qacc_warmstart  # (the solver's warm start is history; positions are not)
        mujoco.mj_forward(m, fresh)
    for name in ("xpos", "xquat", "xmat", "xipos", "ximat", "geom_xpos", "geom_xmat", "subtree_com", "cinert", "cdof"):
        assert np.array_equal(getattr(d, name), getattr(fresh, name)), name
