"""K-finger grippers: identical fingers spaced evenly around a vertical palm axis, a workpiece free in 3-D.

:func:`build_gripper` builds the scene with :class:`mujoco.MjSpec` from the
same parts as the planar scene (:mod:`simgrip.sim.scene`): the root options
and default classes (``models/defaults.xml``), the hinge chains of
:func:`simgrip.sim.fingers.add_fingers` (same springs and rest angles,
:mod:`simgrip.chain`) and the explicit contact pairs of
:mod:`simgrip.sim.contacts`.

Geometry (lengths over ``l``; the palm axis is the world ``z`` axis):

* Finger ``k`` (``k = 0 .. K-1``) is clamped at the origin, pointing
  horizontally along the azimuth ``a_k = yaw + 2 pi k / K``; it bends in its
  own vertical plane (hinges about the root body's ``-y``), so each finger
  reads exactly like the planar finger in its own frame ``E1 = (cos a_k,
  sin a_k, 0)``, ``E2 = z``.
* The workpiece is free in 3-D (one free joint, 6 dof) and weighs
  ``K m g`` (``M`` keeps the paper's meaning: workpiece mass per finger):

  - ``"box"`` (``K = 2`` or ``4``): faces at ``b/2 - r_tip`` from the axis
    facing the fingers, one finger centred on each face (``K = 2``: depth
    :data:`~simgrip.sim.workpiece.BOX_DEPTH` across, as the planar box);
  - ``"cylinder"`` (any ``K >= 2``): vertical axis, radius ``b/2 - r_tip``;
  - ``"sphere"`` (any ``K >= 2``): radius ``b/2 - r_tip``.

  As in the planar scene a touching tip sphere (radius ``r_tip``) has its
  centre, the rod's end, at distance ``b/2`` from the workpiece's axis
  (sphere: from its centre); box and cylinder are :data:`BOX_HEIGHT` tall so
  that the tip meets a vertical face.  The whole scene (fingers and
  workpiece) is rotated by ``yaw`` about the palm axis.
* Beyond the symmetric grasp: the workpiece may sit off the palm axis
  (``offset``, over ``l``) and turn about its own vertical axis
  (``workpiece_yaw``), both in the scene's frame (``yaw`` turns them with
  the rest); box and cylinder only (:mod:`simgrip.gripper.placement`
  finds where each finger's plane meets it, the *reach*).  Each finger may
  have its own curvature profile (``profile`` a sequence of ``K``): the same
  stiffness, its own rest angles.
* Contact: one pair per finger, its tip sphere with the workpiece (Grips I,
  II); no other pair can occur in these grips.

The builder runs no solver: the fingers start at ``initial_angles`` (default
straight) and the workpiece's centre level with their tips;
:func:`simgrip.gripper.settle.settle_gripper` starts from the hinge chain's
grip equilibrium.  Grip III (the cradle) is built for a box with ``K = 4``
(each finger carries the bottom edge of its face) by
:mod:`simgrip.gripper.cradle`.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.chain import chain_springs, link_positions
from simgrip.params import DimensionlessParams, Grip, PhysicalParams, _finite, check_grip
from simgrip.profiles import as_profile
from simgrip.sim.contacts import add_pair
from simgrip.sim.fingers import add_fingers, check_finger_links
from simgrip.gripper.placement import check_offset, check_workpiece_yaw, place_fingers
from simgrip.sim.scene import check_params, check_positive, root_spec, set_joint_angles
from simgrip.sim import workpiece as _workpiece
from simgrip.sim.workpiece import BOX_DEPTH, BOX_HEIGHT, workpiece_inertia
from simgrip.gripper.model import (_WORKPIECE_GEOM, GripperScene, _yaw_quat, compile_gripper, finger_azimuths,
                                   orient_fingers, workpiece_body_mass)

__all__ = ["GRIPPER_GRIPS", "WORKPIECES", "GripperScene", "build_gripper", "check_gripper", "finger_azimuths",
           "compile_gripper", "orient_fingers", "set_finger_angles", "uniform_profiles", "workpiece_body_mass",
           "workpiece_inertia"]

#: Workpiece shapes of a K-finger gripper.
WORKPIECES = ("box", "cylinder", "sphere")
#: The most fingers a gripper has: grippers have 2-6, research hands ~10; MuJoCo's compile grows as fingers x
#: links^3 (32 fingers of 1000 links: ~2.5 minutes before any settle)
MAX_FINGERS = 32
#: Grips a K-finger gripper is built for.
GRIPPER_GRIPS = ("I", "II", "III")
#: Default tip sphere radius over ``l`` (as the planar scene's).
DEFAULT_R_TIP = 2e-3
#: Default link capsule radius over ``l``.
DEFAULT_R_LINK = 2e-3
#: Least inertial mass of the workpiece per finger over ``rho l``: the planar scene's floor, one value for both.
MIN_WORKPIECE_MASS = _workpiece.MIN_WORKPIECE_MASS

def check_gripper(grip, fingers, workpiece) -> tuple[Grip, int, str]:
    """``(grip, K, workpiece)`` normalised (``grip`` a checked :class:`~simgrip.params.Grip`), or ValueError
    naming the bad one.

    ``fingers`` is an integer ``>= 2``; ``workpiece`` one of :data:`WORKPIECES`;
    a box takes ``K = 2`` or ``4`` (one finger centred on each of two or four faces);
    ``grip`` one of :data:`GRIPPER_GRIPS`; Grip III (the cradle) a box with ``K = 4``
    (:mod:`simgrip.gripper.cradle`).
    """
    g = check_grip(grip)
    if g not in GRIPPER_GRIPS:
        raise ValueError(f"grip must be one of {GRIPPER_GRIPS} for a K-finger gripper (the free rod "
                         f"is built by simgrip.sim.scene), got {grip!r}")
    if g == "III" and (not isinstance(workpiece, str) or workpiece.strip().lower() != "box" or isinstance(fingers, bool)
                       or fingers != 4):
        raise ValueError(f"workpiece must be 'box' with fingers = 4 for Grip III (each finger carries the bottom edge "
                         f"of its face; two fingers are the planar cradle, simgrip.sim.scene), got workpiece = "
                         f"{workpiece!r}, fingers = {fingers!r}")
    if isinstance(fingers, bool) or not isinstance(fingers, (int, np.integer)) or not 2 <= fingers <= MAX_FINGERS:
        raise ValueError(f"fingers must be an integer in [2, {MAX_FINGERS}], got {fingers!r}")
    if not isinstance(workpiece, str) or workpiece.strip().lower() not in WORKPIECES:
        raise ValueError(f"workpiece must be one of {WORKPIECES}, got {workpiece!r}")
    w = workpiece.strip().lower()
    if w == "box" and int(fingers) not in (2, 4):
        raise ValueError(f"fingers must be 2 or 4 for workpiece 'box' (one finger centred on each face), "
                         f"got fingers = {fingers!r}; a cylinder or sphere takes any fingers >= 2")
    return g, int(fingers), w


# ---------------------------------------------------------------------------
# builder


def build_gripper(
    grip: str,
    params: PhysicalParams | DimensionlessParams,
    profile,
    n_links: int,
    *,
    fingers: int = 3,
    workpiece: str = "cylinder",
    yaw: float = 0.0,
    contact_angle: float = 0.0,
    r_tip: float = DEFAULT_R_TIP,
    r_link: float = DEFAULT_R_LINK,
    initial_angles=None,
    offset=(0.0, 0.0),
    workpiece_yaw: float = 0.0,
    contact: str | None = None,
    box_gap: float | None = None,
) -> GripperScene:
    """Build and compile a K-finger gripper holding a workpiece (see the module docstring).

    Parameters
    ----------
    grip : {"I", "II", "III"}
        Palm down (tip pinch), palm up, or the cradle (box, ``K = 4``:
        :func:`simgrip.gripper.cradle.build_cradle`, started from
        ``initial_angles`` or the geometric cradle shape).
    params : PhysicalParams or DimensionlessParams
        ``M`` is the workpiece mass per finger; ``b`` the workpiece's width
        (box), diameter (cylinder, sphere) through the tip centres.
    profile : CurvatureProfile, float or callable, or a sequence of K of them
        Intrinsic curvature ``kappa_bar(s_bar)`` of every finger, or one per finger.
    n_links : int
        Links per finger.
    fingers : int
        ``K >= 2`` (box: 2 or 4).
    workpiece : {"box", "cylinder", "sphere"}
    yaw : float
        Rotation of the whole scene about the palm axis [rad].
    contact_angle : float
        Sphere only: elevation ``beta`` [rad] of the contact normal (sphere
        centre to tip, in each finger's plane) at the start, ``|beta| < pi/2``;
        the settle starts the tips at ``X = (b/2) cos beta`` on the sphere
        (friction then keeps the contact near there).  0 (the equator) for
        box and cylinder.
    r_tip, r_link : float
        Tip sphere and link capsule radii over ``l``; ``K`` tip spheres must fit
        around the circle of radius ``b/2`` (ValueError naming ``fingers``).
    initial_angles : array (n,) or (K, n), optional
        Joint angles of the start shape [rad]; default straight.  The
        workpiece's centre starts level with finger 0's tip.
    offset : (dx, dy)
        The workpiece's centre off the palm axis over ``l``, in the scene's
        frame (turned by ``yaw``); box and cylinder only, the palm axis inside
        the workpiece's footprint, two fingers: along their plane (ValueError
        naming ``offset``).
    workpiece_yaw : float
        The workpiece's turn about its vertical axis relative to the fingers
        [rad]; a box's fingers must still meet flat faces (ValueError naming
        ``workpiece_yaw``).
    contact : {None, "point", "surface", "full"}
        ``"full"`` (Grips I/II): every link and tip may touch the workpiece, the
        other fingers and its own links (:mod:`simgrip.sim.full_contact`); the
        workpiece then lies ``box_gap`` below the palm (above it, Grip II)
        instead of level with the tips.  Otherwise one pair per tip.
    box_gap : float, optional
        With ``contact="full"``: gap over ``l`` between the palm plane and the
        workpiece's nearest point (default
        :data:`~simgrip.sim.full_contact.DEFAULT_BOX_GAP`).

    Returns
    -------
    GripperScene
    """
    grip, K, shape = check_gripper(grip, fingers, workpiece)
    return _build_gripper(grip, params, profile, n_links, K=K, shape=shape, yaw=yaw, contact_angle=contact_angle,
                          r_tip=r_tip, r_link=r_link, initial_angles=initial_angles, offset=offset,
                          workpiece_yaw=workpiece_yaw, contact=contact, box_gap=box_gap)


def _build_gripper(grip: Grip, params, profile, n_links, *, K: int, shape: str, yaw=0.0, contact_angle=0.0,
                   r_tip=DEFAULT_R_TIP, r_link=DEFAULT_R_LINK, initial_angles=None, offset=(0.0, 0.0),
                   workpiece_yaw=0.0, contact=None, box_gap=None) -> GripperScene:
    """:func:`build_gripper` with ``(grip, K, shape)`` already through :func:`check_gripper` (not checked again)."""
    from simgrip.sim.full_contact import DEFAULT_BOX_GAP, check_contact_mode, enable_full_contact, full_box_centre

    mode = check_contact_mode(contact)
    if mode == "full" and grip == "III":
        raise ValueError("contact: 'full' is built for Grips I/II (the cradle's box would need a top below the palm)")
    if box_gap is not None and mode != "full":
        raise ValueError("box_gap: only a full-contact gripper (contact='full') places its workpiece by a gap")
    gap = DEFAULT_BOX_GAP if box_gap is None else check_positive("box_gap", box_gap, 1.0)
    if grip == "III":
        from simgrip.gripper.cradle import build_cradle

        if contact_angle != 0.0 or np.any(np.asarray(offset, dtype=float) != 0.0) or workpiece_yaw != 0.0:
            raise ValueError("offset, workpiece_yaw and contact_angle must be 0 for Grip III (the cradle is built "
                             "symmetric only)")
        return build_cradle(params, profile, n_links, fingers=K, yaw=yaw, r_tip=r_tip, r_link=r_link,
                            initial_angles=initial_angles)
    dimless, phys = check_params(params)
    profs = _profiles(profile, K)
    prof = profs[0]
    n = check_finger_links(n_links)
    r_tip = check_positive("r_tip", r_tip, 0.05)
    r_link = check_positive("r_link", r_link, 0.05)
    yaw = _finite("yaw", yaw, unit="radians")
    beta = _check_contact_angle(contact_angle, shape)
    if 2.0 * r_tip >= 2.0 * (0.5 * dimless.b) * math.sin(math.pi / K):
        raise ValueError(f"fingers = {K}: the tip spheres (radius {r_tip:g} l) overlap on the circle of diameter "
                         f"b = {dimless.b:g} l")
    if not 0.5 * dimless.b - r_tip > 0.0:
        raise ValueError(f"b must exceed 2 r_tip = {2 * r_tip:g}, got b = {dimless.b:g}")
    if shape == "sphere" and not 0.5 * dimless.b * math.cos(beta) - r_tip > 0.0:
        limit = math.acos(2.0 * r_tip / dimless.b)
        raise ValueError(f"contact_angle: at {beta:.6g} rad ({math.degrees(beta):.6g} deg) the contact on the sphere "
                         f"lies at X = (b/2) cos(contact_angle) = {0.5 * dimless.b * math.cos(beta):.3g} l from the "
                         f"palm axis, inside the tip sphere's radius {r_tip:g} l; |contact_angle| must stay below "
                         f"acos(2 r_tip / b) = {limit:.6g} rad ({math.degrees(limit):.6g} deg) for b = {dimless.b:g}")
    off = check_offset(offset)
    psi = check_workpiece_yaw(workpiece_yaw)
    finger_springs = tuple(chain_springs(p, n) for p in profs)
    springs = finger_springs[0]
    if shape == "sphere" and any(not np.array_equal(f.rest, springs.rest) for f in finger_springs[1:]):
        raise ValueError("profile must be the same for every finger of a sphere (its tips start on one circle of "
                         "latitude)")
    q0 = _start(initial_angles, K, n)

    L = phys.length
    spec = root_spec(f"simgrip_gripper_{grip}_{K}{shape}_{n}", phys.g)
    add_fingers(spec, spec.worldbody, springs, fingers=K, length=L, EI=phys.EI, rho=phys.rho, r_link=r_link * L,
                r_tip=r_tip * L)
    azimuths = finger_azimuths(K, yaw)
    orient_fingers(spec, azimuths)
    for k in range(K):  # each finger's own rest angles (every finger has the same stiffness)
        for i, rest in enumerate(finger_springs[k].rest):
            spec.joint(f"f{k}_joint{i}").springref = float(rest)
    size = _workpiece_size(shape, K, 0.5 * dimless.b - r_tip, L)
    place = place_fingers(shape, azimuths - yaw, size / L, r_tip, off, psi)
    z0 = float(link_positions(np.cumsum(q0[0]), springs.ds)[-1, 1]) * L
    cy, sy = math.cos(yaw), math.sin(yaw)
    if mode == "full":  # below the palm (Grip II: above it), its nearest point box_gap away
        z0 = full_box_centre(grip, gap * L, float(size[2] if shape == "box" else size[1] if shape == "cylinder"
                                                  else size[0]))
    centre = [(cy * off[0] - sy * off[1]) * L, (sy * off[0] + cy * off[1]) * L, z0]
    _add_workpiece(spec, shape, size, workpiece_body_mass(phys, K), centre, yaw + psi)
    if mode == "full":
        enable_full_contact(spec, [f"f{k}_{g}" for k in range(K) for g in [f"geom{i}" for i in range(n)] + ["tip"]],
                            [_WORKPIECE_GEOM], phys.mu_s, root_bodies=[f"f{k}_link0" for k in range(K)])
    for k in range(K if mode == "pairs" else 0):
        add_pair(spec, f"pair_f{k}_tip", f"f{k}_tip", _WORKPIECE_GEOM, phys.mu_s)

    scene = compile_gripper(
        spec, fingers=K, n=n, grip=grip, workpiece=shape, params=dimless, physical=phys, profile=prof,
        springs=springs, azimuths=azimuths, yaw=yaw, size=size, r_tip=r_tip, r_link=r_link, contact_angle=beta,
        offset=off, workpiece_yaw=psi, profiles=profs, finger_springs=finger_springs, reach=place.reach,
        normals=place.normal, contact=mode)
    set_finger_angles(scene, q0)
    return scene


def _check_contact_angle(value, shape: str) -> float:
    try:
        beta = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"contact_angle must be a real number (radians), got {value!r}") from None
    if not (math.isfinite(beta) and abs(beta) < 0.5 * math.pi):
        raise ValueError(f"contact_angle must lie in (-pi/2, pi/2), got {value!r}")
    if shape != "sphere" and beta != 0.0:
        raise ValueError(f"contact_angle must be 0 for workpiece {shape!r} (its surface is vertical), got {value!r}")
    return beta


def uniform_profiles(kappas, fingers: int) -> tuple:
    """One uniform profile per finger from ``kappas`` (``K`` curvatures ``kappa_bar``), for ``build_gripper``.

    ValueError naming ``kappa_per_finger`` unless there are exactly ``fingers`` finite values of
    magnitude at most :data:`~simgrip.params.KAPPA_LIMIT`.
    """
    from simgrip.params import KAPPA_LIMIT
    from simgrip.profiles import Uniform

    try:
        k = np.asarray(kappas, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"kappa_per_finger must be {fingers} real numbers, got {kappas!r}") from None
    if k.ndim != 1 or len(k) != int(fingers):
        raise ValueError(f"kappa_per_finger must give one curvature per finger ({fingers}), got {kappas!r}")
    if not np.all(np.isfinite(k)) or np.any(np.abs(k) > KAPPA_LIMIT):
        raise ValueError(f"kappa_per_finger must be finite with |kappa| <= {KAPPA_LIMIT:g}, got {kappas!r}")
    return tuple(Uniform(float(v)) for v in k)


def _profiles(profile, K: int) -> tuple:
    """One profile per finger: ``profile`` for all, or a sequence of ``K`` (ValueError naming ``profile``)."""
    if isinstance(profile, (list, tuple, np.ndarray)):
        if len(profile) != K:
            raise ValueError(f"profile must be one profile or one per finger ({K}), got {len(profile)}")
        return tuple(as_profile(p) for p in profile)
    return (as_profile(profile),) * K


def _start(initial_angles, K: int, n: int) -> np.ndarray:
    if initial_angles is None:
        return np.zeros((K, n))
    q = np.asarray(initial_angles, dtype=float)
    if q.shape not in ((n,), (K, n)) or not np.all(np.isfinite(q)):
        raise ValueError(f"initial_angles must be {n} or {K}x{n} finite joint angles, got shape {q.shape}")
    return np.array(np.broadcast_to(q, (K, n)))


def _workpiece_size(shape: str, K: int, r: float, L: float) -> np.ndarray:
    """Geom size [m] of the workpiece whose surface lies ``r`` (over l) from its axis (centre)."""
    if shape == "box":
        across = r if K == 4 else 0.5 * BOX_DEPTH
        return np.array([r, across, 0.5 * BOX_HEIGHT]) * L
    if shape == "cylinder":
        return np.array([r, 0.5 * BOX_HEIGHT, 0.0]) * L
    return np.array([r, 0.0, 0.0]) * L


def _add_workpiece(spec, shape: str, size, mass: float, centre, yaw: float) -> None:
    """The workpiece body on a free joint, its geom and the solid's inertia, at ``centre`` [m] turned by ``yaw``."""
    body = spec.worldbody.add_body(name="workpiece_body", pos=[float(v) for v in centre], quat=_yaw_quat(yaw))
    body.add_freejoint(name="workpiece_free")
    body.explicitinertial = True
    body.mass = mass
    body.ipos = [0.0, 0.0, 0.0]
    cls = spec.find_default("workpiece")
    if shape == "box":
        kind, gsize = mujoco.mjtGeom.mjGEOM_BOX, list(size)
    elif shape == "cylinder":
        kind, gsize = mujoco.mjtGeom.mjGEOM_CYLINDER, [size[0], size[1], 0.0]
    else:
        kind, gsize = mujoco.mjtGeom.mjGEOM_SPHERE, [size[0], 0.0, 0.0]
    # MuJoCo refuses inertias below mjMINVAL; only a weightless workpiece (the mass floor) in small units gets
    # there, and a weightless body's rotational inertia does not enter the statics
    body.inertia = [max(v, 10.0 * mujoco.mjMINVAL) for v in workpiece_inertia(shape, size, mass)]
    body.add_geom(cls, name=_WORKPIECE_GEOM, type=kind, size=gsize)


def set_finger_angles(scene: GripperScene, angles) -> None:
    """Set every finger's hinge angles [rad] (shape (n,) or (K, n)), zero velocities, forward."""
    set_joint_angles(scene, angles)
