"""K-finger scenes through the compile-once cache of :mod:`simgrip.sim.reuse` (same arguments, checks, result).

:func:`build_gripper` is :func:`simgrip.gripper.scene.build_gripper` (and the
Grip III cradle, :func:`simgrip.gripper.cradle.build_cradle`) with the scene
compiled once per structure and its parameters set in place, bit-identical to
a fresh build (``tests/test_scene_reuse.py``).  The cache, its keys, its
bound and its ownership rules are :mod:`simgrip.sim.reuse`'s; this module
uses its internals (the entries, the key, the in-place setters), so that the
scene layer does not import the gripper back.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.chain import chain_springs, link_positions
from simgrip.gripper import scene as G
from simgrip.gripper.cradle import START_NUMERIC, build_cradle, corner_name
from simgrip.gripper.placement import check_offset, check_workpiece_yaw, place_fingers
from simgrip.params import _finite
from simgrip.profiles import as_profile
from simgrip.sim.fingers import check_finger_links
from simgrip.sim.reuse import (_cached_or_built, _finish, _refilled, _set_body_pos, _signature, _structure)
from simgrip.sim.scene import check_params, check_positive, root_spec, set_joint_angles
from simgrip.sim.workpiece import BOX_HEIGHT, contact_links, corner_placement, cradle_start, workpiece_inertia

__all__ = ["build_gripper"]


def build_gripper(grip: str, params, profile, n_links: int, **kw):
    """:func:`simgrip.gripper.scene.build_gripper` through the cache (same arguments, same checks, same result).

    ``yaw``, ``offset``, ``workpiece_yaw`` and ``contact_angle`` are structure (keyed); the parameters, the
    profiles and ``initial_angles`` are set in place.  The scene returned is owned by the cache (valid until
    the next call for its structure in this thread).
    """
    args = (grip, params, profile, n_links)
    bound = _signature(G.build_gripper).bind(*args, **kw)
    bound.apply_defaults()
    a = bound.arguments
    g, K, shape = G.check_gripper(grip, a["fingers"], a["workpiece"])
    if g == "III":
        return _cradle(args, kw, a, K)
    dimless, phys = check_params(params)
    profs = G._profiles(profile, K)
    n = check_finger_links(n_links)
    r_tip = check_positive("r_tip", a["r_tip"], 0.05)
    r_link = check_positive("r_link", a["r_link"], 0.05)
    yaw = _finite("yaw", a["yaw"], unit="radians")
    beta = G._check_contact_angle(a["contact_angle"], shape)
    b = dimless.b
    off = check_offset(a["offset"])
    psi = check_workpiece_yaw(a["workpiece_yaw"])
    finger_springs = tuple(chain_springs(p, n) for p in profs)
    springs = finger_springs[0]
    q0 = G._start(a["initial_angles"], K, n)
    if (2.0 * r_tip >= 2.0 * (0.5 * b) * math.sin(math.pi / K) or not 0.5 * b - r_tip > 0.0
            or (shape == "sphere" and not 0.5 * b * math.cos(beta) - r_tip > 0.0)
            or (shape == "sphere" and any(not np.array_equal(f.rest, springs.rest) for f in finger_springs[1:]))):
        return G.build_gripper(*args, **kw)  # raises the builder's message
    L = phys.length
    azimuths = G.finger_azimuths(K, yaw)
    size = G._workpiece_size(shape, K, 0.5 * b - r_tip, L)
    place = place_fingers(shape, azimuths - yaw, size / L, r_tip, off, psi)
    z0 = float(link_positions(np.cumsum(q0[0]), springs.ds)[-1, 1]) * L
    cy, sy = math.cos(yaw), math.sin(yaw)
    centre = [(cy * off[0] - sy * off[1]) * L, (sy * off[0] + cy * off[1]) * L, z0]
    mass = G.workpiece_body_mass(phys, K)
    key = ("gripper", g, K, shape, n, L.hex(),
           _structure(G.build_gripper, args, kw, ("grip", "params", "profile", "n_links", "initial_angles")))
    const_inputs = (phys.rho.hex(), mass.hex(), size.tobytes(), np.array(centre).tobytes())

    entry, sc = _cached_or_built(key, const_inputs, lambda: G.build_gripper(*args, **kw))
    if entry is None:
        return sc
    with _refilled(key, entry, finger_springs, phys, r_link) as sc:
        m = sc.model
        wb = sc.workpiece_body
        _set_body_pos(m, wb, centre)
        m.body_mass[wb] = mass
        m.body_inertia[wb] = [max(v, 10.0 * mujoco.mjMINVAL) for v in workpiece_inertia(shape, size, mass)]
        gsize = list(size) if shape == "box" else [size[0], size[1] if shape == "cylinder" else 0.0, 0.0]
        m.geom_size[sc.workpiece_geom] = gsize
        m.pair_friction[:, :2] = phys.mu_s
        sc.params, sc.physical, sc.profile, sc.springs = dimless, phys, profs[0], springs
        sc.size, sc.reach, sc.normals = size, place.reach, place.normal
        sc.profiles, sc.finger_springs = profs, finger_springs
        _finish(entry, const_inputs, lambda s: set_joint_angles(s, q0))
    return entry.scene


def _cradle(args, kw, a, K):
    """The K-finger Grip III (:func:`simgrip.gripper.cradle.build_cradle`) through the cache."""
    _, params, profile, n_links = args
    if (a["contact_angle"] != 0.0 or np.any(np.asarray(a["offset"], dtype=float) != 0.0)
            or a["workpiece_yaw"] != 0.0 or isinstance(profile, (list, tuple, np.ndarray))):
        return G.build_gripper(*args, **kw)  # raises the builder's message
    dimless, phys = check_params(params)
    prof = as_profile(profile)
    n = check_finger_links(n_links)
    r_link = check_positive("r_link", a["r_link"], 0.05)
    ca = _signature(build_cradle).parameters
    r_corner = check_positive("r_corner", ca["r_corner"].default, 0.05)
    window = check_positive("contact_window", ca["contact_window"].default, 1.0)
    springs = chain_springs(prof, n)
    given = a["initial_angles"]
    if given is None:
        q0 = cradle_start(dimless.b, dimless.gamma, prof, n)
    else:
        q = np.asarray(given, dtype=float)
        if q.shape not in ((n,), (K, n)) or not np.all(np.isfinite(q)) or (q.ndim == 2 and np.any(q != q[:1])):
            return G.build_gripper(*args, **kw)  # raises the builder's message
        q0 = np.array(q if q.ndim == 1 else q[0])
    L = phys.length
    hx, zc, s = corner_placement(q0, springs, dimless.b, dimless.gamma, r_link, r_corner, L)
    if not hx > 0.0:
        return G.build_gripper(*args, **kw)  # raises the builder's message
    links = contact_links(s, springs, window)
    hz = 0.5 * BOX_HEIGHT * L
    size = np.array([hx, hx, hz])
    mass = G.workpiece_body_mass(phys, K)
    key = ("cradle", K, n, L.hex(), tuple(int(i) for i in links),
           _structure(G.build_gripper, args, kw, ("grip", "params", "profile", "n_links", "initial_angles")))
    const_inputs = (phys.rho.hex(), mass.hex(), size.tobytes(), float(zc + hz).hex())

    entry, sc = _cached_or_built(key, const_inputs, lambda: G.build_gripper(*args, **kw))
    if entry is None:
        return sc
    with _refilled(key, entry, [springs] * K, phys, r_link) as sc:
        m = sc.model
        yaw = float(sc.yaw)
        i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, START_NUMERIC)
        m.numeric_data[int(m.numeric_adr[i]):int(m.numeric_adr[i]) + n] = q0
        wb = sc.workpiece_body
        _set_body_pos(m, wb, [0.0, 0.0, zc + hz])
        m.body_mass[wb] = mass
        m.body_inertia[wb] = [max(v, 10.0 * mujoco.mjMINVAL) for v in workpiece_inertia("box", size, mass)]
        m.geom_size[sc.workpiece_geom] = list(size)
        # the corner capsules' frames come from fromto: compile them alone, exactly as build_cradle adds them
        spec = root_spec("simgrip_cradle_corners", phys.g)
        body = spec.worldbody.add_body(name="b")
        corner_cls = spec.find_default("corner")
        for k in range(K):
            az = float(sc.azimuths[k]) - yaw
            e, t = np.array([math.cos(az), math.sin(az)]), np.array([-math.sin(az), math.cos(az)])
            p0, p1 = hx * e - hx * t, hx * e + hx * t
            body.add_geom(corner_cls, name=corner_name(k), fromto=[p0[0], p0[1], -hz, p1[0], p1[1], -hz],
                          size=[r_corner * L, 0.0, 0.0])
        small = spec.compile()
        for k in range(K):
            g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, corner_name(k))
            for f in ("geom_pos", "geom_quat", "geom_size"):
                getattr(m, f)[g] = getattr(small, f)[k]
        m.pair_friction[:, :2] = phys.mu_s
        sc.params, sc.physical, sc.profile, sc.springs = dimless, phys, prof, springs
        sc.size, sc.reach = size, np.full(K, 0.5 * dimless.b)
        sc.profiles, sc.finger_springs = (prof,) * K, (springs,) * K
        _finish(entry, const_inputs, lambda s: set_joint_angles(s, np.tile(q0, (K, 1))))
    return entry.scene
