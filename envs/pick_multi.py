"""``PickMultiEnv``: pick a box, cylinder or sphere with K soft fingers around a palm (curvature control).

A thin Gymnasium layer over the K-finger pick models of
:mod:`simgrip.envs.pick_multi_model` (the fingers built by simgrip's finger
builder and placed as :func:`simgrip.gripper.scene.build_gripper` places them).
The observation, contact forces and reward terms live in
:mod:`simgrip.envs.pick_multi_observation`; this module holds the arguments,
the episode bookkeeping (the workpiece's draw: :mod:`simgrip.envs.pick_multi_workpiece`) and the Gymnasium API,
in the conventions of :class:`simgrip.envs.pick.PickEnv` (``simgrip/Pick-v1``).
"""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from simgrip.envs.arguments import check_camera, check_reset, check_size, check_within, set_finger_arguments
from simgrip.envs.arguments import set_task_arguments
from simgrip.envs.palm_servo import palm_command
from simgrip.envs.arguments import check_bool as _bool
from simgrip.envs.arguments import check_number as _num
from simgrip.envs.arguments import check_range as _range
from simgrip.envs.pick_multi_model import build_pick_multi_model, half_height, set_workpiece
from simgrip.envs.pick_multi_observation import MultiObservation, MultiReward, WorkpieceContactForces
from simgrip.envs.pick_multi_workpiece import WORKPIECE_OPTIONS, WorkpieceParams, check_draw_ranges, draw_workpiece
from simgrip.envs.pick_reward import progress
from simgrip.envs.pick_step import CheckedStep
from simgrip.envs.pick_validity import FingerValidity
from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.sim.checks import PhysicsError, StateCheck, check_invalid_state
from simgrip.sim.gl import make_renderer
from simgrip.gripper.scene import WORKPIECES, check_gripper

__all__ = ["PickMultiEnv", "WorkpieceParams"]

_COS_TILT = math.cos(math.radians(30.0))  # knocked over beyond this tilt (box, cylinder)
_SHIFT = 0.03  # knocked away beyond this horizontal shift [m]
_LIFTED = 0.005  # the workpiece counts as lifted once this high above its start [m]
_array = np.array  # (the step's info arrays: one global lookup instead of two)


class PickMultiEnv(CheckedStep, gym.Env):
    r"""Pick a box, cylinder or sphere off a table with ``K`` soft pneumatic fingers (curvature control).

    ## Description

    A palm carries ``K = fingers`` identical soft fingers (planar hinge
    chains, ``n_links`` links each, built by
    :func:`simgrip.sim.fingers.add_fingers`) spaced evenly around its
    vertical axis: finger ``k`` points along the azimuth ``2 pi k / K`` (finger
    0 along ``+x``) and bends in its own vertical plane, as in
    :func:`simgrip.gripper.scene.build_gripper`.  The pneumatic pressure is the
    fingers' uniform intrinsic curvature :math:`\bar\kappa_0 = \ell\kappa_0`,
    which follows its command with a first-order lag (``kappa_tau``).  The
    agent curls the fingers around a workpiece resting on the table and lifts
    the palm: the workpiece must rise by ``target_height`` and stay there for
    ``hold_time``.  Axes: ``z`` up, the palm axis is the world ``z`` axis; the
    table top is ``z = 0``.  Finger, physics and contact settings are those of
    ``simgrip/Pick-v1`` (:class:`simgrip.envs.pick.PickEnv`: same defaults,
    time step, frame skip, damping, armature, elliptic cones, condim-4 tip and
    link contacts, palm servo); a MuJoCo warning or a non-finite state raises
    :class:`simgrip.sim.checks.PhysicsError`.  Dynamics: the finger's
    first mode is ``Pick-v1``'s (7.66 Hz, zeta = 0.479; its higher modes
    overdamped); with ``K = 3`` the fingers in phase, carrying the palm servo,
    have 7.60 Hz and zeta = 0.474 (``tests/test_finger_damping.py``).

    ## Workpieces (randomised per episode, seeded by ``reset(seed=...)``)

    | quantity | default range | notes |
    |----------|---------------|-------|
    | shape | uniform over ``shapes`` | ``"box"`` (only ``K = 2`` or ``4``: one finger on each face), ``"cylinder"`` (vertical axis), ``"sphere"``; default: every shape ``K`` allows |
    | width ``b`` | ``size_range = (0.04, 0.065)`` m | box side (square section), cylinder or sphere diameter |
    | height | ``workpiece_height = 0.06`` m | box and cylinder (a sphere is ``b`` tall) |
    | mass | ``mass_range = (0.02, 0.06)`` kg | the whole workpiece: ``M = m / (K rho l)`` per finger |
    | friction | ``friction_range = (0.5, 1.2)`` | finger-workpiece |
    | offset | radius ``<= offset_max = 0.005`` m | centre's horizontal offset from the palm axis, uniform over the disc; ``K = 2``: along the fingers' line (``x``), the radius drawn alike (a centre off the line through two contacts turns about it) |
    | yaw | ``yaw_range = (-0.15, 0.15)`` rad; ``K = 2``: ``(0, 0)`` | rotation about the vertical (a box's faces turn away from the fingers; two fingers pinching a turned box turn it about the line through the tips and out of the grip: the scripted pick holds 20 of 20 unturned boxes, 12 of 20 turned within +-0.05 rad) |

    Fixed values via ``reset(options={"shape", "width", "mass", "friction",
    "offset", "yaw", "palm_height"})``.  Each shape has its own compiled
    model (:mod:`simgrip.envs.pick_multi_model`; same addresses): ``model``
    and ``data`` are the current episode's.

    ## Action space

    ``Box(-1, 1, (2,), float32)`` (``shared_curvature=True``) or ``(K + 1,)``.
    Values outside ``[-1, 1]`` are clipped; NaN, inf or a wrong shape raise
    ``ValueError``.  As ``Pick-v1``:

    | index | action | maps to |
    |-------|--------|---------|
    | 0 (.. K-1) | curvature command (all fingers, or finger ``k``) | :math:`\bar\kappa_{cmd} = k_{lo} + (a+1)/2\,(k_{hi} - k_{lo})`, ``kappa_range = (-10, 0)``: ``-1`` curls fully, ``+1`` straightens |
    | last | palm vertical velocity | ``a * palm_speed`` [m/s] (0.1), integrated into the palm's target height, kept in ``palm_range`` |

    ## Observation space

    ``Box(low, high, (16 + (P + 4) K,), float64)`` with ``P = shape_points``
    (8): 52 entries for ``K = 3``; ``(14 + (P + 6) K,)`` without
    ``shared_curvature``.  Conventions of ``Pick-v1``: lengths over the
    finger length ``l``, velocities in ``l`` per second, angles in radians,
    curvatures in action units, forces as ``log(1 + F/W)`` with ``W = g
    mean(mass_range)``; positions and velocities relative to the palm in world
    axes; values clipped to the bounds.  Every finger is observed (an
    off-centre workpiece breaks the symmetry).  ``obs_layout`` and
    ``obs_slices`` name the blocks.

    | name | size | meaning | unit | bounds |
    |------|------|---------|------|--------|
    | ``palm_height`` | 1 | palm (finger roots) above the table | l | [0, 10] |
    | ``kappa_command`` | 1 (K) | curvature command, in action units | - | [-2, 2] |
    | ``kappa_actual`` | 1 (K) | actual curvature after the lag, in action units | - | [-2, 2] |
    | ``finger_shape`` | K P | tangent angle of finger ``k`` (in its own plane, counter-clockwise about its ``-E3``, 0 along a straight finger) at ``s/l = (j+1/2)/P``; finger 0 first | rad | [-B, B], ``B = max(20, 2 max abs kappa_range)`` |
    | ``tip_position`` | 2 K | fingertip ``(X, Z)`` of each finger in its own plane: ``X`` along its azimuth from the palm axis, ``Z`` up from the palm | l | [-5, 5] |
    | ``workpiece_position`` | 3 | centre ``(x, y, z)`` relative to the palm | l | [-10, 10] |
    | ``workpiece_tilt`` | 2 | ``(x, y)`` components of the workpiece's own ``z`` axis (0 upright) | - | [-1, 1] |
    | ``workpiece_velocity`` | 3 | centre velocity relative to the palm | l/s | [-100, 100] |
    | ``workpiece_spin`` | 3 | angular velocity (world axes) times 0.1 s | rad | [-100, 100] |
    | ``workpiece_lift`` | 1 | height gained since the start, over ``target_height`` | - | [-20, 20] |
    | ``contact_force`` | 2 K | ``log(1 + F/W)`` of the workpiece's force on finger ``k``: normal, friction magnitude | - | [0, 20] |
    | ``hold`` | 1 | time held at the target over ``hold_time`` (success at 1) | - | [0, 1] |

    ## Rewards

    As ``Pick-v1``: ``reward = lift + success + squeeze + drop`` (terms in
    ``info``): ``lift = w_lift (phi_t - phi_{t-1})`` with the progress ``phi
    = clip(dz / target_height, 0, 1)`` (0 once the workpiece is lost);
    ``success = w_success`` once; ``squeeze = -w_squeeze mean_k x_k/(1+x_k)``
    with ``x_k = max(0, S_k - squeeze_margin m g/(K mu)) / (m g)``, ``S_k``
    the horizontal component of finger ``k``'s normal forces
    (:func:`~simgrip.envs.pick_multi_observation.multi_reward`); ``drop =
    -w_drop`` once.  Defaults 10, 20, 0.04, 10: a success returns at least
    ``w_lift + w_success - w_squeeze T >= 20``, anything else at most 10.

    ## Episode end

    Success: the workpiece has stayed ``>= target_height`` (0.06 m) above its
    start, touched by at least two fingers, for ``hold_time`` (0.5 s).  Lost
    (terminates, ``-w_drop``): dropped (once lifted by 5 mm with two fingers on
    it, it sank more than ``drop_distance`` relative to the palm), or knocked
    over (a box or cylinder tilted more than 30 degrees, or any workpiece
    pushed more than 3 cm sideways from its start).  Time limit at
    registration 200 steps (4 s); ``step`` never truncates, and after the end
    raises :class:`gymnasium.error.ResetNeeded` until ``reset``.

    ## Info

    Every ``step``'s ``info``: ``is_success`` (the episode ended in success, as above), ``dropped``,
    ``knocked_over`` (it ended in that failure), ``workpiece_lift`` (height gained since the start over
    ``target_height``), ``normal_force``, ``friction_force``, ``side_force`` (per finger, on the workpiece
    [N]), ``hold_time`` [s], ``fingers_touching``, the reward's terms (``reward_lift``, ``reward_success``,
    ``reward_squeeze``, ``reward_drop``), and ``valid`` (no finger through
    itself or another; else ``invalid`` lists the messages).

    ## Arguments

    Every argument is checked: a bad value raises ``ValueError`` naming it.

    | argument | default | meaning |
    |----------|---------|---------|
    | ``fingers`` | 3 | ``K >= 2`` |
    | ``shapes`` | every shape ``K`` allows | workpiece shapes drawn from (box needs ``K`` = 2 or 4) |
    | ``shared_curvature`` | True | one curvature command for all fingers (else one per finger) |
    | ``render_mode``, ``width``, ``height``, ``camera`` | None, 480, 360, ``"gripper"`` | ``"rgb_array"`` renders headless (cameras ``gripper``, ``front``, ``oblique``) |
    | ``n_links`` | 12 | links per finger |
    | ``length``, ``EI``, ``rho``, ``g`` | 0.1, 3e-3, 0.15, 9.81 | finger (SI) |
    | ``size_range``, ``mass_range``, ``friction_range``, ``offset_max``, ``yaw_range``, ``workpiece_height`` | see above | randomisation |
    | ``kappa_range``, ``kappa_tau`` | (-10, 0), 0.1 | curvature bounds, pneumatic lag [s] |
    | ``palm_speed``, ``palm_range``, ``palm_start`` | 0.1, (0.05, 0.25), (0.105, 0.115) | [m/s], [m], [m] |
    | ``palm_ramp`` | False | the palm's target held over a control step or ramped within it (:mod:`simgrip.envs.palm_servo`) |
    | ``target_height``, ``hold_time`` | 0.06, 0.5 | success [m], [s] |
    | ``w_lift``, ``w_success``, ``w_squeeze``, ``w_drop``, ``squeeze_margin``, ``drop_distance`` | 10, 20, 0.04, 10, 2, 0.02 | reward and drop |
    | ``timestep``, ``frame_skip``, ``settle_time``, ``finger_damping_time``, ``finger_armature`` | 0.002, 10, 0.1, 0.02, 1e-5 | physics |
    | ``shape_points``, ``r_tip``, ``spin_friction``, ``impratio`` | 8, 0.004, 0.004, 1 | as ``Pick-v1`` |

    ## Version history

    * v0: first version.
    """

    _tactile_unit: float | None = None  # the tactile scale W [N] (None: g times the mean mass)

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(
        self,
        fingers: int = 3,
        shapes=None,
        shared_curvature: bool = True,
        render_mode: str | None = None,
        n_links: int = 12,
        length: float = 0.1,
        EI: float = 3.0e-3,
        rho: float = 0.15,
        g: float = 9.81,
        size_range=(0.04, 0.065),
        mass_range=(0.02, 0.06),
        friction_range=(0.5, 1.2),
        offset_max: float = 0.005,
        yaw_range=None,
        workpiece_height: float = 0.06,
        kappa_range=(-10.0, 0.0),
        kappa_tau: float = 0.1,
        palm_speed: float = 0.1,
        palm_range=(0.05, 0.25),
        palm_start=(0.105, 0.115),
        target_height: float = 0.06,
        hold_time: float = 0.5,
        w_lift: float = 10.0,
        w_success: float = 20.0,
        w_squeeze: float = 0.04,
        w_drop: float = 10.0,
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
        camera: str = "gripper",
        palm_ramp: bool = False,
    ):
        _, self.K, _ = check_gripper("I", fingers, "cylinder")
        if shapes is None:
            shapes = WORKPIECES if self.K in (2, 4) else tuple(s for s in WORKPIECES if s != "box")
        if isinstance(shapes, str) or not shapes:
            raise ValueError(f"shapes must be a non-empty sequence of {WORKPIECES}, got {shapes!r}")
        chosen = []
        for s in shapes:
            if not isinstance(s, str) or s not in WORKPIECES:
                raise ValueError(f"shapes must be drawn from {WORKPIECES}, got {shapes!r}")
            if s == "box" and self.K not in (2, 4):
                raise ValueError(f"shapes: 'box' needs fingers = 2 or 4 (one finger centred on each face), "
                                 f"got fingers = {self.K}")
            if s not in chosen:
                chosen.append(s)
        self.shapes = tuple(chosen)
        self.shared_curvature = _bool("shared_curvature", shared_curvature)
        set_finger_arguments(self, render_mode=render_mode, n_links=n_links, length=length, EI=EI, rho=rho, g=g,
                             r_tip=r_tip)
        self.size_range = _range("size_range", size_range, hi=1.9 * self.length, why="1.9 times length")
        self.mass_range = _range("mass_range", mass_range)
        self.friction_range = _range("friction_range", friction_range)
        self.offset_max = _num("offset_max", offset_max, positive=False)
        if yaw_range is None:  # a two-finger pinch turns a turned box out of the grip (see the table)
            yaw_range = (0.0, 0.0) if self.K == 2 else (-0.15, 0.15)
        self.yaw_range = _range("yaw_range", yaw_range, lo=-math.pi, hi=math.pi, positive=False)
        self.workpiece_height = check_size("workpiece_height", workpiece_height, self.length)
        check_draw_ranges(fingers=self.K, length=self.length, EI=self.EI, rho=self.rho, g=self.g,
                          size_range=self.size_range, mass_range=self.mass_range, friction_range=self.friction_range,
                          offset_max=self.offset_max)
        # the tip spheres must fit around the smallest workpiece
        if self.r_tip >= (0.5 * self.size_range[0] + self.r_tip) * math.sin(math.pi / self.K):
            raise ValueError(f"size_range: with fingers = {self.K} the tip spheres (radius {self.r_tip} m) "
                             f"overlap around a workpiece {self.size_range[0]} m wide")
        set_task_arguments(
            self, kappa_range=kappa_range, kappa_tau=kappa_tau, palm_speed=palm_speed, palm_range=palm_range,
            palm_start=palm_start, target_height=target_height, hold_time=hold_time, w_lift=w_lift,
            w_success=w_success, w_squeeze=w_squeeze, w_drop=w_drop, squeeze_margin=squeeze_margin,
            drop_distance=drop_distance, timestep=timestep, frame_skip=frame_skip, settle_time=settle_time,
            finger_damping_time=finger_damping_time, shape_points=shape_points, spin_friction=spin_friction,
            impratio=impratio, finger_armature=finger_armature, width=width, height=height, camera=camera,
            palm_ramp=palm_ramp)
        self._build()
        check_camera(self.model, self.camera)
        nk = 1 if self.shared_curvature else self.K
        self.action_space = spaces.Box(-1.0, 1.0, (nk + 1,), dtype=np.float32)
        self._action_shape = (nk + 1,)
        #: the actions' names in order (:mod:`simgrip.envs.warm_start` matches policies by them)
        self.action_names = (("curvature",) if nk == 1 else tuple(f"curvature_{k}" for k in range(nk))) + ("palm_z",)
        self.observation_space = spaces.Box(self._observe.low, self._observe.high, dtype=np.float64)
        self.obs_layout, self.obs_slices = self._observe.layout, self._observe.slices
        self._renderers = {}
        # the constants step reads, in one tuple (read once, at construction)
        self._consts = (self.kappa_range[0], self.kappa_range[1], self._lag_alpha, self.dt, self.frame_skip,
                        self.work_qpos, self.palm_qpos, self.target_height, self.hold_time, self.drop_distance)
        self._reset_state()

    # ------------------------------------------------------------------ model
    def _build(self):
        """One model per shape (:func:`~simgrip.envs.pick_multi_model.build_pick_multi_model`), same addresses."""
        kw = dict(fingers=self.K, n_links=self.n, length=self.length, EI=self.EI, rho=self.rho, g=self.g,
                  r_tip=self.r_tip, width=float(np.mean(self.size_range)), height=self.workpiece_height,
                  mass_max=self.mass_range[1], friction=float(np.mean(self.friction_range)),
                  spin_friction=self.spin_friction, timestep=self.timestep, impratio=self.impratio,
                  damping_time=self.finger_damping_time, armature=self.finger_armature, palm_ramp=self.palm_ramp,
                  palm_range=self.palm_range)
        self._models = {s: build_pick_multi_model(s, **kw) for s in self.shapes}
        self._datas = {s: mujoco.MjData(pm.model) for s, pm in self._models.items()}
        pm = self._models[self.shapes[0]]
        for other in self._models.values():  # what step and the observation read is at the same addresses
            same = (other.palm_qpos, other.palm_dof, other.work_qpos, other.work_dof, other.work_geom) == \
                (pm.palm_qpos, pm.palm_dof, pm.work_qpos, pm.work_dof, pm.work_geom)
            if not (same and np.array_equal(other.fingers.joint_qpos, pm.fingers.joint_qpos)
                    and np.array_equal(other.fingers.finger_of_geom, pm.fingers.finger_of_geom)):
                raise RuntimeError(f"the {other.shape!r} model's addresses differ from the {pm.shape!r} model's")
        self.fingers = pm.fingers
        self._validity = FingerValidity(pm.model, pm.fingers)  # info["valid"] (issue 17; same addresses every shape)
        self.azimuths = pm.azimuths
        self.palm_qpos, self.palm_dof = pm.palm_qpos, pm.palm_dof
        self._palm = palm_command(self, pm.model)  # (the same actuator in every shape's model)
        self.work_qpos, self.work_dof = pm.work_qpos, pm.work_dof
        self._hinges = pm.fingers.hinge_qpos
        # W of the tactile observation log(1 + F/W) [N]: the mean weight, or a subclass's sensor scale
        self._force_unit = self._tactile_unit or self.g * float(np.mean(self.mass_range))
        self._observe = MultiObservation(
            fingers=self.K, n_links=self.n, shape_points=self.shape_points, shared_curvature=self.shared_curvature,
            kappa_range=self.kappa_range, length=self.length, target_height=self.target_height,
            hold_time=self.hold_time, force_unit=self._force_unit, palm_qpos=pm.palm_qpos,
            palm_dof=pm.palm_dof, work_qpos=pm.work_qpos, work_dof=pm.work_dof, hinge_qpos=self._hinges)
        self._forces = WorkpieceContactForces(self.K, pm.work_geom, pm.fingers.finger_of_geom)
        self._select(self.shapes[0])
        self.workpiece = WorkpieceParams(self.shapes[0], float(np.mean(self.size_range)),
                                         float(np.mean(self.mass_range)), float(np.mean(self.friction_range)),
                                         (0.0, 0.0), 0.0)

    def _select(self, shape: str):
        """Make ``shape``'s model and data the current ones."""
        self._pm = self._models[shape]
        self.model, self.data = self._pm.model, self._datas[shape]
        flat = self._pm.fingers.joint_qpos.ravel()
        self._spring = self.model.qpos_spring[flat[0]:flat[0] + flat.size].reshape(self.K, self.n)
        self._check = StateCheck(self.data)
        self._unit_rest = np.tile(self._pm.unit_rest, (self.K, 1))
        d = self.data  # what step reads and writes, in one tuple (one attribute lookup)
        self._hot = (self.model, d, self._check, d.qpos, d.qvel, d.ctrl, d.warning.number)

    @property
    def joint_qpos(self) -> np.ndarray:
        """qpos addresses of the finger hinges, (K, n_links) (read-only)."""
        return self.fingers.joint_qpos

    @property
    def tip_geom(self) -> np.ndarray:
        """Geom ids of the K tip spheres (read-only)."""
        return self.fingers.tip_geom

    # ------------------------------------------------------------- helpers
    def physical_params(self) -> PhysicalParams:
        """The current episode's per-finger :class:`~simgrip.params.PhysicalParams`: ``m`` = workpiece mass / K,
        ``b`` its width through the faces (add ``2 r_tip`` for the tip centres' distance)."""
        w = self.workpiece
        return PhysicalParams(length=self.length, EI=self.EI, rho=self.rho, g=self.g, m=w.mass / self.K, b=w.width,
                              mu_s=w.friction, gamma=0.8 * self.length)

    def dimensionless(self) -> DimensionlessParams:
        """The paper's groups for the current episode, per finger (:meth:`physical_params`)."""
        return self.physical_params().dimensionless()

    def _reset_state(self):
        nk = 1 if self.shared_curvature else self.K
        self._kcmd = [0.0] * nk  # commanded curvatures (Python floats: the step's arithmetic, that of numpy)
        self._kact = [0.0] * nk  # actual curvatures (after the lag)
        self._z0 = 0.0
        self._xy0 = (0.0, 0.0)
        self._lifted_rel = None
        self._hold = 0.0
        self._phi = 0.0
        w = self.workpiece
        self._reward = MultiReward(fingers=self.K, mass=w.mass, g=self.g, friction=w.friction, w_lift=self.w_lift,
                                   w_success=self.w_success, w_squeeze=self.w_squeeze, w_drop=self.w_drop,
                                   squeeze_margin=self.squeeze_margin)
        self._tilts = w.shape != "sphere"  # a sphere has no tilt to knock over
        self._needs_reset = True

    def _set_kappa(self, kappa: list):
        """Rest angles of every finger for the curvatures ``kappa`` (1 shared or K floats), written into the model."""
        np.multiply(self._unit_rest, kappa[0] if len(kappa) == 1 else np.array(kappa)[:, None], out=self._spring)

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_renderers"] = {}
        state["_spring"] = state["_check"] = state["_hot"] = None
        # the builder's MjSpec cannot be pickled; models, data and addresses travel (one copy each: pickle keeps
        # self.model / self.data and their entries in the dicts the same objects)
        state["_models"] = {s: dataclasses.replace(pm, spec=None) for s, pm in state["_models"].items()}
        state["_pm"] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._select(self.workpiece.shape)

    def _start_shape(self):
        """Shape the fingers before the reset's settle: straight here (see :mod:`simgrip.envs.pick_fragile_v4`)."""

    def _get_obs(self, forces):
        return self._observe(self.data, forces, self._kcmd, self._kact, self._z0, self._hold)

    # --------------------------------------------------------------- API
    def reset(self, *, seed=None, options=None):
        seed, options = check_reset(seed, options, (*WORKPIECE_OPTIONS, "palm_height"))
        super().reset(seed=seed)
        rng = self.np_random
        work = draw_workpiece(rng, options, shapes=self.shapes, fingers=self.K, size_range=self.size_range,
                              mass_range=self.mass_range, friction_range=self.friction_range,
                              offset_max=self.offset_max, yaw_range=self.yaw_range, length=self.length)
        palm_z = float(rng.uniform(*self.palm_start))
        palm_z = check_within("palm_height", options.get("palm_height", palm_z), *self.palm_range, "palm_range")
        shape, width, mass, mu, offset, yaw = (work.shape, work.width, work.mass, work.friction, work.offset,
                                               work.yaw)

        self._select(shape)
        m, d = self.model, self.data
        size = set_workpiece(self._pm, d, width=width, height=self.workpiece_height, mass=mass, friction=mu,
                             spin_friction=self.spin_friction)
        self.workpiece = work
        mujoco.mj_resetData(m, d)
        self._reset_state()  # (after self.workpiece: the episode's reward constants)
        self._set_kappa(self._kact)
        d.qpos[self.palm_qpos] = palm_z
        self._palm.reset(d, palm_z)
        wq = self.work_qpos
        d.qpos[wq:wq + 3] = [offset[0], offset[1], half_height(shape, size)]
        d.qpos[wq + 3:wq + 7] = [math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)]
        self._start_shape()  # the fingers' shape before the settle (a subclass's pre-grasp; here straight)
        with check_invalid_state(d, "reset: settling the fingers and workpiece"):
            mujoco.mj_forward(m, d)
            if self.settle_steps:
                mujoco.mj_step(m, d, nstep=self.settle_steps)
        self._z0 = float(d.qpos[wq + 2])
        self._xy0 = (float(d.qpos[wq]), float(d.qpos[wq + 1]))
        self._needs_reset = False
        info = {"shape": shape, "width": width, "mass": mass, "friction": mu, "offset": offset, "yaw": float(yaw),
                "palm_height": palm_z, "dimensionless": self.dimensionless()}
        return self._get_obs(self._forces(d)), info

    def _step_checked(self, a: list):
        # step(action) checked the episode and the action (pick_step.CheckedStep). Runs once per control step beside frame_skip
        # mj_step calls: the constants bound once (_consts) and the views per model (_select, _hot), the state read
        # as lists once, the reward's constants bound per episode (MultiReward), the arithmetic that of
        # multi_reward and MultiObservation (min / max written out as comparisons, the same values)
        lo, hi, alpha, dt, fs, wq, pq, target, hold_time, drop = self._consts
        m, d, check, qpos, qvel, ctrl, warnings = self._hot
        # pneumatic lag: exact first-order response over one control step, rest angles held within it
        if len(a) == 2:  # one shared command (the default): the comprehensions below, written out
            c = lo + 0.5 * (a[0] + 1.0) * (hi - lo)
            k = self._kact[0]
            k = k + alpha * (c - k)
            self._kcmd, self._kact = cmd, kap = [c], [k]
            np.multiply(self._unit_rest, k, out=self._spring)  # one scalar times every finger's unit rest angles
        else:
            self._kcmd = cmd = [lo + 0.5 * (v + 1.0) * (hi - lo) for v in a[:-1]]
            self._kact = kap = [k + alpha * (c - k) for c, k in zip(cmd, self._kact)]
            if len(kap) == 1:
                np.multiply(self._unit_rest, kap[0], out=self._spring)
            else:
                self._set_kappa(kap)
        self._palm.command(ctrl, a[-1])  # the palm's target, held or ramped over the step (envs.palm_servo)
        warnings.fill(0)  # check.clear()
        mujoco.mj_step(m, d, fs)  # nstep (positional: pybind's keyword parsing costs more)
        q, v = qpos.tolist(), qvel.tolist()
        if any(warnings.tolist()) or not math.isfinite(sum(q) + sum(v)):  # StateCheck's test, its call saved
            why = check(q, v)  # (None where a huge finite state overflowed the sums)
            if why is not None:
                self._needs_reset = True
                raise PhysicsError(f"step diverged ({why})")

        forces = self._forces(d)
        normal, friction, side = forces
        self._normal = normal  # info["normal_force"] as floats, for the subclasses' per-step rules
        x, y, z, qx, qy = q[wq], q[wq + 1], q[wq + 2], q[wq + 4], q[wq + 5]
        gain = z - self._z0
        rel = z - q[pq]
        touching = 0  # the fingers touching (sum of f > 0.0, counted without a comprehension's frame)
        for f in normal:
            if f > 0.0:
                touching += 1
        lifted_rel = self._lifted_rel
        if lifted_rel is None and gain > _LIFTED and touching >= 2:
            self._lifted_rel = lifted_rel = rel
        dropped = lifted_rel is not None and rel < lifted_rel - drop
        tilted = self._tilts and 1.0 - 2.0 * (qx * qx + qy * qy) < _COS_TILT
        x0, y0 = self._xy0
        knocked = tilted or math.hypot(x - x0, y - y0) > _SHIFT
        self._hold = hold = self._hold + dt if gain >= target and touching >= 2 else 0.0
        success = hold > 0.0 and hold >= hold_time - 1e-9  # (held this step: hold_time 0 still needs the lift)
        lost = (dropped or knocked) and not success
        phi = progress(gain, target, lost)
        reward, r_lift, r_success, r_squeeze, r_drop = self._reward(phi, self._phi, success, lost, side)
        self._phi = phi
        terminated = bool(success or lost)
        self._needs_reset = terminated
        info = {
            "reward_lift": r_lift, "reward_success": r_success, "reward_squeeze": r_squeeze, "reward_drop": r_drop,
            "is_success": success, "dropped": dropped and not success, "knocked_over": knocked and not success,
            "workpiece_lift": gain, "normal_force": _array(normal), "friction_force": _array(friction),
            "side_force": _array(side), "hold_time": hold, "fingers_touching": touching,
        }
        invalid = self._validity(q, d)  # a finger through itself or another (envs.pick_validity)
        info["valid"] = not invalid
        if invalid:
            info["invalid"] = invalid
        obs = self._observe.observe(qpos, q, v, cmd, kap, forces, self._z0, hold)
        return obs, reward, terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gymnasium.make")
            return None
        shape = self.workpiece.shape
        if shape not in self._renderers:
            self._renderers[shape] = make_renderer(self.model, self.height, self.width)  # headless
        renderer = self._renderers[shape]
        renderer.update_scene(self.data, camera=self.camera)
        return renderer.render().copy()

    def close(self):
        for r in self._renderers.values():
            r.close()
        self._renderers = {}
