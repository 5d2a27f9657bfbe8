"""``PickEnv``: pick a box with two soft fingers by commanding their curvature.

A thin Gymnasium layer over :func:`simgrip.sim.scene.build_scene`: the two fingers
(hinge chains whose stiffness ``EI/ds`` and rest angles ``kappa0 ds`` come from
:func:`simgrip.chain.chain_springs`) are built by the scene builder and attached
under the palm of ``models/pick_scene.xml``.  The pneumatic actuation is the
intrinsic curvature: each control step moves the actual curvature towards its
command with a first-order lag and writes the new rest angles into
``model.qpos_spring`` (no recompilation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from simgrip.chain import chain_springs, check_links
from simgrip.models import model_path
from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.profiles import Uniform
from simgrip.sim.scene import build_scene

__all__ = ["PickEnv", "BoxParams", "OBS_LAYOUT", "obs_layout"]

GRIP_ALIASES = {"I": "I", "i": "I", "pinch": "I", "III": "III", "iii": "III", "cradle": "III"}
PREFIX = "hand_"
_COS_TILT = math.cos(math.radians(30.0))  # knocked over beyond this tilt


@dataclass(frozen=True)
class BoxParams:
    """The box of one episode (SI): full width along ``x`` [m], mass [kg], finger-box friction."""

    width: float
    mass: float
    friction: float


def _range(name, value, lo=-math.inf, hi=math.inf, positive=True):
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (low, high) pair of numbers, got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a > b:
        raise ValueError(f"{name} must be a finite (low, high) pair with low <= high, got {value!r}")
    if positive and a <= 0:
        raise ValueError(f"{name} must be positive, got {value!r}")
    if a < lo or b > hi:
        raise ValueError(f"{name} must lie within [{lo}, {hi}], got {value!r}")
    return (a, b)


def _pos(name, value):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive number, got {value!r}")
    return v


def obs_layout(shape_points: int = 8) -> list[tuple[str, int]]:
    """``(name, size)`` of the observation's blocks, in order (see :class:`PickEnv`)."""
    return [
        ("palm_height", 1),
        ("kappa_command", 2),
        ("kappa_actual", 2),
        ("finger_shape", 2 * shape_points),
        ("tip_position", 4),
        ("box_position", 3),
        ("box_quat", 4),
        ("box_linvel", 3),
        ("box_angvel", 3),
        ("contact_force", 4),
    ]


#: Layout of the default observation (``shape_points = 8``): 42 entries.
OBS_LAYOUT = obs_layout(8)


class PickEnv(gym.Env):
    r"""Pick a box off a table with two soft pneumatic fingers (curvature control).

    ## Description

    A palm carries two mirrored soft fingers (planar hinge chains, ``n_links``
    links each, built by :func:`simgrip.sim.scene.build_scene`).  The pneumatic
    pressure is modelled by the fingers' intrinsic curvature
    :math:`\bar\kappa_0 = \ell\kappa_0` (uniform along the finger), which follows
    its command with a first-order lag of time constant ``kappa_tau``.  The
    agent curls the fingers around a box resting on a table and lifts the palm:
    the box must rise by ``target_height`` and stay there for ``hold_time``,
    squeezed no harder than needed.  Axes: ``x`` from the palm centre towards
    finger 0, ``z`` up (the paper's ``E1``, ``E2``); the table top is ``z = 0``.

    Grips (``grip``):

    | grip | id | scene |
    |------|----|-------|
    | ``"I"`` (pinch) | ``simgrip/Pick-v0`` | palm down, the fingertips pinch the box's side faces |
    | ``"III"`` (cradle) | ``simgrip/PickCradle-v0`` | the box (3.5 cm tall) stands on a narrow 4 cm pedestal; the fingers curl under its lower edges and carry it on their links |

    ## Physical defaults (SI) and the paper's groups

    A PneuNet-like silicone finger: length ``length = 0.10 m``; mass per length
    ``rho = 0.15 kg/m`` (15 g of elastomer and strain-limiting layer);
    bending stiffness ``EI = 3.0e-3 N m^2`` (a 15 mm x 15 mm elastomer section
    with ``E ~ 1 MPa`` gives ``E b h^3/12 ~ 4e-3``, less for the air chambers);
    tip sphere and link capsules of radius 4 mm (contact geometry; the mechanics
    is the centreline).  Box: 6 cm tall, 4 cm deep, width 4-6.5 cm, mass
    20-60 g, finger-box friction 0.5-1.2 (silicone on card or plastic).  Then
    ``D = EI/(rho g l^3) = 2.04`` and, per finger (half the box),
    ``M = m/(rho l) = 0.67 - 2.0``, ``b/l = 0.4 - 0.65``.
    :meth:`dimensionless` returns the current episode's groups.

    Simulation: ``timestep = 2 ms``, ``frame_skip = 10`` (control at 50 Hz),
    implicitfast integrator, elliptic friction cones, Newton solver (50
    iterations), ``impratio = 1``.  The hinges carry stiffness-proportional
    damping (``finger_damping_time = 20 ms``, lossy silicone) and an armature
    of ``1e-5 kg m^2`` (numerical: it slows the hinge modes so that 2 ms steps
    and the friction solve stay well conditioned; equilibria are unchanged).
    Without the armature the light links (1.25 g) let the tips creep along the
    box under friction and the scripted pick fails.  Tip and link contacts are
    condim 4 (torsional friction ``spin_friction * mu``, 4 mm, a soft tip's
    contact patch) so the box cannot swing about the line through the tips.  The palm slides vertically on a joint driven by a stiff position
    servo (4000 N/m, critically damped): a mocap body has no velocity, so it
    could not drag the box up by friction.  Contacts are explicit pairs only
    (tip and link of each finger, and the palm slab, with the box; box with
    table/pedestal); no finger self-collision, the fingers pass through the table.

    ## Action space

    ``Box(-1, 1, (2,), float32)`` (``per_finger=False``) or ``(3,)``
    (``per_finger=True``).  Values outside ``[-1, 1]`` are clipped; NaN, inf or
    a wrong shape raise ``ValueError``.

    | index | action | maps to |
    |-------|--------|---------|
    | 0 | curvature command (both fingers, or finger 0) | :math:`\bar\kappa_{cmd} = k_{lo} + (a+1)/2\,(k_{hi} - k_{lo})`, ``kappa_range = (k_lo, k_hi)``, default ``(-10, 0)``: ``-1`` curls fully, ``+1`` straightens |
    | (1) | curvature command of finger 1 (``per_finger=True``) | as above |
    | last | palm vertical velocity | ``a * palm_speed`` [m/s] (default 0.1 m/s), integrated into the palm's target height, which is kept in ``palm_range`` |

    ## Observation space

    ``Box(low, high, (26 + 2 shape_points,), float64)``; 42 entries by default.
    Values are clipped to the finite bounds listed (they are never reached in
    normal use).  Positions and velocities are relative to the palm (finger
    roots) in world axes; finger 1 is the mirror image of finger 0 (its tip has
    ``x < 0``).

    | slice (default) | name | size | unit | bounds |
    |-----------------|------|------|------|--------|
    | 0 | palm height above the table | 1 | m | [0, 1] |
    | 1:3 | curvature commands :math:`\bar\kappa_{cmd}` (finger 0, 1) | 2 | - | [-50, 50] |
    | 3:5 | actual curvatures (after the lag) | 2 | - | [-50, 50] |
    | 5:21 | finger shape: tangent angle (rad, each finger in its own frame, counter-clockwise positive) at ``shape_points`` equally spaced arc lengths ``s/l = (k+1/2)/K``, interpolated between link midpoints (independent of ``n_links``); finger 0 then finger 1 | 2K | rad | [-20, 20] |
    | 21:25 | fingertip positions ``(x, z)``, finger 0 then 1 | 4 | m | [-1, 1] |
    | 25:28 | box centre ``(x, y, z)`` | 3 | m | [-1, 1] |
    | 28:32 | box orientation quaternion ``(w, x, y, z)`` | 4 | - | [-1, 1] |
    | 32:35 | box linear velocity | 3 | m/s | [-10, 10] |
    | 35:38 | box angular velocity (box frame) | 3 | rad/s | [-100, 100] |
    | 38:42 | contact force of the box on each finger: normal, friction magnitude (finger 0, then 1) | 4 | N | [0, 100] |

    ## Rewards

    ``reward = lift + success + squeeze + drop``, each term in ``info`` as
    ``reward_lift``, ``reward_success``, ``reward_squeeze``, ``reward_drop``.

    | term | value |
    |------|-------|
    | lift | ``w_lift * clip(dz / target_height, 0, 1)`` each step, ``dz`` = box height gain |
    | success | ``w_success`` once, when the box has stayed ``>= target_height`` above its start, touched by both fingers, for ``hold_time`` |
    | squeeze | ``-w_squeeze * sum_f max(0, N_f - squeeze_margin * N_need) / (m_box g)``: normal force beyond ``squeeze_margin`` times the least one that holds the box, ``N_need = m_box g / (2 mu_s)`` |
    | drop | ``-w_drop`` once, when the box is dropped or knocked over (see below) |

    ## Starting state

    Box (width, mass, friction drawn uniformly from ``box_width_range``,
    ``box_mass_range``, ``friction_range`` with the ``reset`` seed; fixed
    values via ``reset(options={"box_width": ..., "box_mass": ...,
    "friction": ...})``) at rest on the table (Grip I) or the pedestal (Grip
    III), centred under the palm.  Palm at a height drawn from ``palm_start``;
    fingers straight with zero curvature command, left to settle under
    gravity for ``settle_time`` before the first observation.  ``info`` of
    ``reset`` holds the box parameters and the dimensionless groups.

    ## Episode end

    Terminates on success, on a drop (the box, once lifted by 5 mm, has sunk
    more than ``drop_distance`` relative to the palm from where it was when
    first lifted; releasing it counts as a drop) and on knocking it over
    (tilted more than 30 degrees, or pushed more than 3 cm sideways).  Time
    limit at registration: 200 steps (4 s) for ``Pick-v0`` and 250 for
    ``PickCradle-v0``; ``step`` itself never truncates.

    ## Arguments

    | argument | default | meaning |
    |----------|---------|---------|
    | ``grip`` | ``"I"`` | ``"I"``/``"pinch"`` or ``"III"``/``"cradle"`` |
    | ``render_mode`` | ``None`` | ``None`` or ``"rgb_array"`` |
    | ``n_links`` | 12 | links per finger |
    | ``length``, ``EI``, ``rho``, ``g`` | 0.1, 3e-3, 0.15, 9.81 | finger (SI) |
    | ``box_width_range``, ``box_mass_range``, ``friction_range`` | (0.04, 0.065), (0.02, 0.06), (0.5, 1.2) | domain randomisation |
    | ``box_height``, ``box_depth`` | 0.06 (cradle 0.035), 0.04 | box size [m] |
    | ``per_finger`` | False | one curvature command per finger |
    | ``kappa_range`` | (-10, 0) | curvature command bounds (dimensionless) |
    | ``kappa_tau`` | 0.1 | pneumatic lag [s] (0: none) |
    | ``palm_speed``, ``palm_range``, ``palm_start`` | 0.1, (0.05, 0.25), (0.105, 0.115) (cradle (0.13, 0.14)) | palm speed [m/s], target range, start range [m] |
    | ``target_height``, ``hold_time`` | 0.03, 0.5 | success [m, s] |
    | ``w_lift``, ``w_success``, ``w_squeeze``, ``w_drop`` | 1, 50, 0.2, 20 | reward weights |
    | ``squeeze_margin``, ``drop_distance`` | 2.0, 0.02 | squeeze allowance, drop threshold [m] |
    | ``timestep``, ``frame_skip``, ``settle_time`` | 0.002, 10, 0.1 | physics step [s], steps per action, settling at reset [s] |
    | ``finger_damping_time``, ``finger_armature`` | 0.02, 1e-5 | hinge damping / stiffness [s], hinge armature [kg m^2] |
    | ``r_tip``, ``spin_friction``, ``impratio`` | 0.004, 0.004, 1 | tip/link radius [m], torsional friction length [m], MuJoCo impratio |
    | ``shape_points`` | 8 | finger shape samples per finger |
    | ``width``, ``height``, ``camera`` | 480, 360, ``"front"`` | rendering |

    ## Version history

    * v0: initial version.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        grip: str = "I",
        render_mode: str | None = None,
        *,
        n_links: int = 12,
        length: float = 0.1,
        EI: float = 3.0e-3,
        rho: float = 0.15,
        g: float = 9.81,
        box_width_range=(0.04, 0.065),
        box_mass_range=(0.02, 0.06),
        friction_range=(0.5, 1.2),
        box_height: float | None = None,
        box_depth: float = 0.04,
        per_finger: bool = False,
        kappa_range=(-10.0, 0.0),
        kappa_tau: float = 0.1,
        palm_speed: float = 0.1,
        palm_range=(0.05, 0.25),
        palm_start=None,
        target_height: float = 0.03,
        hold_time: float = 0.5,
        w_lift: float = 1.0,
        w_success: float = 50.0,
        w_squeeze: float = 0.2,
        w_drop: float = 20.0,
        squeeze_margin: float = 2.0,
        drop_distance: float = 0.02,
        timestep: float = 0.002,
        frame_skip: int = 10,
        settle_time: float = 0.1,
        finger_damping_time: float = 0.02,
        shape_points: int = 8,
        r_tip: float = 0.004,
        spin_friction: float = 0.004,
        impratio: float = 1.0,
        finger_armature: float = 1e-5,
        width: int = 480,
        height: int = 360,
        camera: str = "front",
    ):
        if not isinstance(grip, str) or grip.strip() not in GRIP_ALIASES:
            raise ValueError(f"grip must be 'I' (pinch) or 'III' (cradle), got {grip!r}")
        self.grip = GRIP_ALIASES[grip.strip()]
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.n = check_links(n_links)
        self.length = _pos("length", length)
        self.EI = _pos("EI", EI)
        self.rho = _pos("rho", rho)
        self.g = _pos("g", g)
        self.box_width_range = _range("box_width_range", box_width_range, hi=2 * self.length)
        self.box_mass_range = _range("box_mass_range", box_mass_range)
        self.friction_range = _range("friction_range", friction_range)
        if box_height is None:
            box_height = 0.06 if self.grip == "I" else 0.035
        self.box_height = _pos("box_height", box_height)
        self.box_depth = _pos("box_depth", box_depth)
        self.per_finger = bool(per_finger)
        self.kappa_range = _range("kappa_range", kappa_range, positive=False)
        self.kappa_tau = float(kappa_tau)
        if not (math.isfinite(self.kappa_tau) and self.kappa_tau >= 0):
            raise ValueError(f"kappa_tau must be >= 0, got {kappa_tau!r}")
        self.palm_speed = _pos("palm_speed", palm_speed)
        self.palm_range = _range("palm_range", palm_range)
        if palm_start is None:
            palm_start = (0.105, 0.115) if self.grip == "I" else (0.13, 0.14)
        self.palm_start = _range("palm_start", palm_start, lo=self.palm_range[0], hi=self.palm_range[1])
        self.target_height = _pos("target_height", target_height)
        self.hold_time = float(hold_time)
        if not (math.isfinite(self.hold_time) and self.hold_time >= 0):
            raise ValueError(f"hold_time must be >= 0, got {hold_time!r}")
        self.w_lift, self.w_success, self.w_squeeze, self.w_drop = (
            float(w_lift), float(w_success), float(w_squeeze), float(w_drop))
        self.squeeze_margin = _pos("squeeze_margin", squeeze_margin)
        self.drop_distance = _pos("drop_distance", drop_distance)
        self.timestep = _pos("timestep", timestep)
        if not isinstance(frame_skip, (int, np.integer)) or frame_skip < 1:
            raise ValueError(f"frame_skip must be a positive integer, got {frame_skip!r}")
        self.frame_skip = int(frame_skip)
        self.settle_steps = int(round(float(settle_time) / self.timestep))
        self.finger_damping_time = float(finger_damping_time)
        if not (isinstance(shape_points, (int, np.integer)) and shape_points >= 2):
            raise ValueError(f"shape_points must be an integer >= 2, got {shape_points!r}")
        self.shape_points = int(shape_points)
        self.r_tip = _pos("r_tip", r_tip)
        self.spin_friction = _pos("spin_friction", spin_friction)
        self.impratio = _pos("impratio", impratio)
        self.finger_armature = float(finger_armature)
        if not (math.isfinite(self.finger_armature) and self.finger_armature >= 0):
            raise ValueError(f"finger_armature must be >= 0, got {finger_armature!r}")
        self.width, self.height, self.camera = int(width), int(height), str(camera)
        self.dt = self.timestep * self.frame_skip
        self._lag_alpha = 1.0 if self.kappa_tau == 0 else 1.0 - math.exp(-self.dt / self.kappa_tau)
        self.metadata = dict(self.metadata, render_fps=int(round(1.0 / self.dt)))

        self._build()

        na = 3 if self.per_finger else 2
        self.action_space = spaces.Box(-1.0, 1.0, (na,), dtype=np.float32)
        lows, highs = [], []
        bounds = {
            "palm_height": (0, 1), "kappa_command": (-50, 50), "kappa_actual": (-50, 50),
            "finger_shape": (-20, 20), "tip_position": (-1, 1), "box_position": (-1, 1),
            "box_quat": (-1, 1), "box_linvel": (-10, 10), "box_angvel": (-100, 100), "contact_force": (0, 100),
        }
        self.obs_layout = obs_layout(self.shape_points)
        for name, size in self.obs_layout:
            lo, hi = bounds[name]
            lows += [lo] * size
            highs += [hi] * size
        self._slices, start = {}, 0
        for name, size in self.obs_layout:
            self._slices[name] = slice(start, start + size)
            start += size
        sl = self._slices
        self._rel_idx = (sl["tip_position"].start + 1, sl["tip_position"].start + 3,
                         sl["box_position"].start + 2, sl["box_linvel"].start + 2)
        self._obs_low = np.array(lows, dtype=np.float64)
        self._obs_high = np.array(highs, dtype=np.float64)
        self.observation_space = spaces.Box(self._obs_low, self._obs_high, dtype=np.float64)
        self._renderer = None
        self.box = BoxParams(np.mean(self.box_width_range), np.mean(self.box_mass_range), np.mean(self.friction_range))
        self._reset_state()

    # ------------------------------------------------------------------ model
    def _build(self):
        L, n = self.length, self.n
        mid_w = float(np.mean(self.box_width_range))
        mid_m = float(np.mean(self.box_mass_range))
        phys = PhysicalParams(length=L, EI=self.EI, rho=self.rho, g=self.g, m=0.5 * mid_m,
                              b=min(mid_w, 1.9 * L), mu_s=float(np.mean(self.friction_range)), gamma=0.8 * L)
        self.physical = phys
        r_over_l = min(self.r_tip / L, 0.05)
        # The fingers come from the simulator's own scene builder (no second finger model).
        fingers = build_scene("free", phys, Uniform(0.0), n, fingers=2, r_tip=r_over_l, r_link=r_over_l)
        spec = mujoco.MjSpec.from_file(str(model_path("pick_scene.xml")))
        spec.option.timestep = self.timestep
        spec.option.impratio = self.impratio
        spec.option.gravity = [0.0, 0.0, -self.g]
        spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        # Align the finger spec's options with ours so attaching raises no conflict.
        for name in ("timestep", "tolerance", "iterations", "ls_iterations", "ls_tolerance", "noslip_iterations",
                     "noslip_tolerance", "integrator", "cone", "solver", "disableflags", "enableflags", "impratio",
                     "gravity"):
            setattr(fingers.spec.option, name, getattr(spec.option, name))

        # Palm: a vertical slide joint with a stiff, critically damped position servo.
        palm = spec.body("palm")
        palm.gravcomp = 1.0
        palm.add_joint(name="palm_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        palm_mass = 0.2
        palm.explicitinertial = True
        palm.mass = palm_mass
        palm.inertia = [1e-4, 1e-4, 1e-4]
        kp = 4000.0
        kv = 2.0 * math.sqrt(kp * (palm_mass + 2 * self.rho * L + self.box_mass_range[1]))
        act = spec.add_actuator(name="palm_servo", target="palm_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=kp, kv=kv)

        for f in range(2):
            palm.add_frame().attach_body(fingers.spec.body(f"f{f}_link0"), PREFIX, "")
        ds = L / n
        for f in range(2):
            for i in range(n):
                j = spec.joint(f"{PREFIX}f{f}_joint{i}")
                k = float(np.atleast_1d(j.stiffness)[0])  # EI/ds (2 EI/ds at the clamp), set by build_scene
                j.damping = [self.finger_damping_time * k] + [0.0] * (len(j.damping) - 1)
                j.armature = self.finger_armature
            tip = spec.geom(f"{PREFIX}f{f}_tip")
            if tip is None:  # the scene builder adds tips only for grips with tip contact / rendering
                tip = spec.body(f"{PREFIX}f{f}_link{n - 1}").add_geom(
                    name=f"{PREFIX}f{f}_tip", type=mujoco.mjtGeom.mjGEOM_SPHERE, pos=[ds, 0, 0],
                    size=[self.r_tip, 0, 0], contype=0, conaffinity=0, group=1, mass=0,
                    rgba=[0.95, 0.75, 0.2, 1])
            tip.size = [self.r_tip, 0, 0]
            for i in range(n):
                g = spec.geom(f"{PREFIX}f{f}_geom{i}")
                g.size = [self.r_tip, 0, 0]
                g.rgba = [0.88, 0.42, 0.22, 1]

        # Box: default size; resized per episode.
        hx, hy, hz = 0.5 * mid_w, 0.5 * self.box_depth, 0.5 * self.box_height
        spec.geom("box").size = [hx, hy, hz]
        self._pedestal_h = 0.0
        if self.grip == "III":
            self._pedestal_h = 0.04
            ph = 0.5 * self._pedestal_h
            spec.worldbody.add_geom(name="pedestal", type=mujoco.mjtGeom.mjGEOM_BOX,
                                    size=[0.006, hy, ph], pos=[0, 0, ph],
                                    contype=0, conaffinity=0, rgba=[0.45, 0.4, 0.35, 1])

        def pair(g1, g2, mu, name, condim=3):
            p = spec.add_pair(name=name, geomname1=g1, geomname2=g2)
            p.condim = condim
            p.friction = [mu, mu, self.spin_friction * mu, 0.0, 0.0]
            p.solref = [0.005, 1.0]
            p.solimp = [0.95, 0.99, 0.001, 0.5, 2.0]
            return p

        mu0 = float(np.mean(self.friction_range))
        self._finger_pairs = []
        for f in range(2):
            pair(f"{PREFIX}f{f}_tip", "box", mu0, f"pair_f{f}_tip", condim=4)
            self._finger_pairs.append(f"pair_f{f}_tip")
            for i in range(n - 1):  # the last link's far end is the tip sphere
                pair(f"{PREFIX}f{f}_geom{i}", "box", mu0, f"pair_f{f}_link{i}", condim=4)
                self._finger_pairs.append(f"pair_f{f}_link{i}")
        pair("palm_slab", "box", 0.5, "pair_palm_box")
        pair("box", "table", 0.6, "pair_box_table")
        if self.grip == "III":
            pair("box", "pedestal", 0.6, "pair_box_pedestal")
        self.spec = spec
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        m = self.model

        def jid(name):
            return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)

        def gid(name):
            return mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)

        joints = np.array([[jid(f"{PREFIX}f{f}_joint{i}") for i in range(n)] for f in range(2)])
        self.joint_qpos = m.jnt_qposadr[joints]
        self.joint_dof = m.jnt_dofadr[joints]
        self._spring_idx = self.joint_qpos.ravel()
        self._unit_rest = chain_springs(Uniform(1.0), n).rest  # rest angles are linear in a uniform kappa
        self._rest_buf = np.empty((2, n))
        self.palm_qpos = int(m.jnt_qposadr[jid("palm_z")])
        self.palm_dof = int(m.jnt_dofadr[jid("palm_z")])
        bj = jid("box_free")
        self.box_qpos = int(m.jnt_qposadr[bj])
        self.box_dof = int(m.jnt_dofadr[bj])
        self.box_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "box")
        self.box_geom = gid("box")
        self.tip_geom = np.array([gid(f"{PREFIX}f{f}_tip") for f in range(2)])
        self._finger_of_geom = np.full(m.ngeom, -1, dtype=int)
        for f in range(2):
            self._finger_of_geom[self.tip_geom[f]] = f
            for i in range(n):
                self._finger_of_geom[gid(f"{PREFIX}f{f}_geom{i}")] = f
        self._finger_pair_ids = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_PAIR, p) for p in self._finger_pairs])
        # shape sampling: tangent angles at s/l = (k+1/2)/K from link angles (cumulative hinge angles)
        K = self.shape_points
        s_link = (np.arange(n) + 0.5) / n
        s_k = (np.arange(K) + 0.5) / K
        interp = np.zeros((K, n))
        for k, s in enumerate(s_k):
            e = np.zeros(n)
            for i in range(n):
                e[:] = 0
                e[i] = 1
                interp[k, i] = np.interp(s, s_link, e)
        self._shape_matrix = interp @ np.tril(np.ones((n, n)))  # q -> theta(s_k)
        self._shape_matrix_t = np.ascontiguousarray(self._shape_matrix.T)
        self._cf = np.zeros(6)
        self._fog_list = self._finger_of_geom.tolist()
        self._elliptic = m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
        flat = self._spring_idx
        if np.array_equal(flat, np.arange(flat[0], flat[0] + flat.size)):
            # the hinges' qpos are contiguous: write the rest angles through a view
            self._spring_view = m.qpos_spring[flat[0]:flat[0] + flat.size].reshape(2, n)
        else:  # pragma: no cover - the builder always makes them contiguous
            self._spring_view = None
        self._tips = (int(self.tip_geom[0]), int(self.tip_geom[1]))
        # finger hinge qpos as a (2, n) view when contiguous, else a fancy index
        q0 = int(flat[0])
        contiguous = np.array_equal(flat, np.arange(q0, q0 + flat.size))
        self._fq = (slice(q0, q0 + flat.size),) if contiguous else (self.joint_qpos,)

    # ------------------------------------------------------------- helpers
    def dimensionless(self) -> DimensionlessParams:
        """The paper's groups for the current episode (per finger: half the box; ``b`` is the box width)."""
        return self.physical_params().dimensionless()

    def physical_params(self) -> PhysicalParams:
        """:class:`~simgrip.params.PhysicalParams` of the current episode (``m`` = half the box mass)."""
        return PhysicalParams(length=self.length, EI=self.EI, rho=self.rho, g=self.g, m=0.5 * self.box.mass,
                              b=self.box.width, mu_s=self.box.friction, gamma=0.8 * self.length)

    def _set_box(self, box: BoxParams):
        m, d = self.model, self.data
        hx, hy, hz = 0.5 * box.width, 0.5 * self.box_depth, 0.5 * self.box_height
        m.geom_size[self.box_geom] = [hx, hy, hz]
        m.geom_rbound[self.box_geom] = math.sqrt(hx * hx + hy * hy + hz * hz)
        m.geom_aabb[self.box_geom] = [0, 0, 0, hx, hy, hz]
        m.body_mass[self.box_body] = box.mass
        m.body_inertia[self.box_body] = [box.mass / 3 * (hy**2 + hz**2), box.mass / 3 * (hx**2 + hz**2),
                                         box.mass / 3 * (hx**2 + hy**2)]
        m.pair_friction[self._finger_pair_ids, 0:2] = box.friction
        m.pair_friction[self._finger_pair_ids, 2] = self.spin_friction * box.friction
        mujoco.mj_setConst(m, d)
        self.box = box

    def _set_kappa(self, kappa):
        if self._spring_view is not None:
            np.multiply.outer(kappa, self._unit_rest, out=self._spring_view)
        else:  # pragma: no cover
            np.multiply.outer(kappa, self._unit_rest, out=self._rest_buf)
            self.model.qpos_spring[self._spring_idx] = self._rest_buf.ravel()

    def _reset_state(self):
        self._kappa_cmd = np.zeros(2)
        self._kappa = np.zeros(2)
        self._palm_target = float(self.palm_start[0])
        self._z0 = 0.0
        self._lifted_rel = None
        self._hold = 0.0
        self._done = False

    def _contact_forces(self) -> list:
        """Force of the box on each finger: ``[normal_0, friction_0, normal_1, friction_1]`` [N]."""
        m, d = self.model, self.data
        out = [0.0, 0.0, 0.0, 0.0]
        if d.ncon == 0:
            return out
        fog, bg = self._fog_list, self.box_geom
        con = d.contact
        geoms = con.geom.tolist()
        if self._elliptic:
            # elliptic cones: a contact's constraint rows are its contact-frame force (normal, t1, t2, ...)
            adrs = con.efc_address.tolist()
            ef = d.efc_force
            for (g1, g2), adr in zip(geoms, adrs):
                f = fog[g2] if g1 == bg else (fog[g1] if g2 == bg else -1)
                if f >= 0:
                    out[2 * f] += float(ef[adr])
                    out[2 * f + 1] += math.hypot(ef[adr + 1], ef[adr + 2])
            return out
        cf = self._cf
        for i, (g1, g2) in enumerate(geoms):
            f = fog[g2] if g1 == bg else (fog[g1] if g2 == bg else -1)
            if f >= 0:
                mujoco.mj_contactForce(m, d, i, cf)
                out[2 * f] += float(cf[0])
                out[2 * f + 1] += math.hypot(cf[1], cf[2])
        return out

    def _get_obs(self, forces):
        d = self.data
        qpos, qvel, xpos = d.qpos, d.qvel, d.geom_xpos
        palm_z = float(qpos[self.palm_qpos])
        bq, bd = self.box_qpos, self.box_dof
        t0, t1 = self._tips
        obs = np.concatenate((
            (palm_z,), self._kappa_cmd, self._kappa,
            (qpos[self._fq].reshape(2, self.n) @ self._shape_matrix_t).ravel(),
            (xpos[t0, 0], xpos[t0, 2] - palm_z, xpos[t1, 0], xpos[t1, 2] - palm_z),
            qpos[bq:bq + 7], qvel[bd:bd + 6], forces,
        ))
        # relative to the palm (it moves along z only)
        obs[self._rel_idx[2]] -= palm_z
        obs[self._rel_idx[3]] -= qvel[self.palm_dof]
        np.maximum(obs, self._obs_low, out=obs)
        np.minimum(obs, self._obs_high, out=obs)
        return obs

    # --------------------------------------------------------------- API
    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"box_width", "box_mass", "friction", "palm_height"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}; use box_width, box_mass, friction, palm_height")
        rng = self.np_random
        width = float(rng.uniform(*self.box_width_range))
        mass = float(rng.uniform(*self.box_mass_range))
        mu = float(rng.uniform(*self.friction_range))
        palm_z = float(rng.uniform(*self.palm_start))
        width = _pos("box_width", options.get("box_width", width))
        if width / 2 >= self.length:
            raise ValueError(f"box_width = {width} m is wider than the fingers reach")
        mass = _pos("box_mass", options.get("box_mass", mass))
        mu = _pos("friction", options.get("friction", mu))
        palm_z = float(np.clip(_pos("palm_height", options.get("palm_height", palm_z)), *self.palm_range))
        m, d = self.model, self.data
        self._set_box(BoxParams(width, mass, mu))
        mujoco.mj_resetData(m, d)
        self._reset_state()
        self._set_kappa(self._kappa)
        d.qpos[self.palm_qpos] = palm_z
        self._palm_target = palm_z
        d.ctrl[0] = palm_z
        d.qpos[self.box_qpos:self.box_qpos + 3] = [0.0, 0.0, self._pedestal_h + 0.5 * self.box_height]
        d.qpos[self.box_qpos + 3:self.box_qpos + 7] = [1.0, 0.0, 0.0, 0.0]
        mujoco.mj_forward(m, d)
        if self.settle_steps:
            mujoco.mj_step(m, d, nstep=self.settle_steps)
        self._z0 = float(d.qpos[self.box_qpos + 2])
        self._xy0 = np.array(d.qpos[self.box_qpos:self.box_qpos + 2])
        forces = self._contact_forces()
        info = {
            "box_width": width, "box_mass": mass, "box_friction": mu, "palm_height": palm_z,
            "dimensionless": self.dimensionless(),
        }
        return self._get_obs(forces), info

    def _check_action(self, action) -> list:
        """The action as a list of floats clipped to [-1, 1]; ValueError on a wrong shape or non-finite values."""
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"action must be an array of {self.action_space.shape[0]} numbers, got {action!r}") from None
        if a.shape != self.action_space.shape:
            raise ValueError(f"action must have shape {self.action_space.shape}, got {a.shape}")
        vals = a.tolist()
        for v in vals:
            if not math.isfinite(v):
                raise ValueError(f"action must be finite (no NaN or inf), got {action!r}")
        return [-1.0 if v < -1.0 else (1.0 if v > 1.0 else v) for v in vals]

    def step(self, action):
        a = self._check_action(action)
        m, d = self.model, self.data
        lo, hi = self.kappa_range
        k0 = lo + 0.5 * (a[0] + 1.0) * (hi - lo)
        k1 = lo + 0.5 * (a[1] + 1.0) * (hi - lo) if self.per_finger else k0
        cmd = self._kappa_cmd
        cmd[0], cmd[1] = k0, k1
        # pneumatic lag: exact first-order response over one control step, rest angles held within it
        kap = self._kappa
        kap += self._lag_alpha * (cmd - kap)
        self._set_kappa(kap)
        self._palm_target = min(max(self._palm_target + a[-1] * self.palm_speed * self.dt,
                                    self.palm_range[0]), self.palm_range[1])
        d.ctrl[0] = self._palm_target
        mujoco.mj_step(m, d, nstep=self.frame_skip)

        forces = self._contact_forces()
        obs = self._get_obs(forces)
        bx, by, box_z, _, qx, qy, _ = d.qpos[self.box_qpos:self.box_qpos + 7].tolist()
        gain = box_z - self._z0
        rel = box_z - float(d.qpos[self.palm_qpos])
        n0, f0, n1, f1 = forces
        both = n0 > 0.0 and n1 > 0.0
        weight = self.box.mass * self.g
        allow = self.squeeze_margin * weight / (2.0 * self.box.friction)
        excess = max(n0 - allow, 0.0) + max(n1 - allow, 0.0)
        r_lift = self.w_lift * min(max(gain / self.target_height, 0.0), 1.0)
        r_squeeze = -self.w_squeeze * excess / weight
        if self._lifted_rel is None and gain > 0.005 and both:
            self._lifted_rel = rel
        dropped = self._lifted_rel is not None and rel < self._lifted_rel - self.drop_distance
        up_z = 1.0 - 2.0 * (qx * qx + qy * qy)  # z component of the box's z axis
        shifted = math.hypot(bx - self._xy0[0], by - self._xy0[1]) > 0.03
        knocked = up_z < _COS_TILT or shifted
        if gain >= self.target_height and both:
            self._hold += self.dt
        else:
            self._hold = 0.0
        success = self._hold >= self.hold_time - 1e-9
        r_success = self.w_success if success else 0.0
        r_drop = -self.w_drop if (dropped or knocked) and not success else 0.0
        terminated = bool(success or dropped or knocked)
        reward = r_lift + r_success + r_squeeze + r_drop
        info = {
            "reward_lift": r_lift, "reward_success": r_success, "reward_squeeze": r_squeeze,
            "reward_drop": r_drop, "is_success": success, "dropped": dropped and not success,
            "knocked_over": knocked and not success, "box_lift": gain,
            "normal_force": np.array((n0, n1)), "friction_force": np.array((f0, f1)), "hold_time": self._hold,
        }
        return obs, reward, terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gymnasium.make")
            return None
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, height=self.height, width=self.width)
        self._renderer.update_scene(self.data, camera=self.camera)
        return self._renderer.render().copy()

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
