"""``PickEnv``: pick a box with two soft fingers by commanding their curvature.

A thin Gymnasium layer over the pick model of :mod:`simgrip.envs.pick_model`: the
two fingers (hinge chains whose stiffness ``EI/ds`` and rest angles ``kappa0 ds``
come from :func:`simgrip.chain.chain_springs`) are built by simgrip's finger
builder under the palm of ``models/pick_scene.xml``.  The pneumatic actuation is the
intrinsic curvature: each control step moves the actual curvature towards its
command with a first-order lag and writes the new rest angles into
``model.qpos_spring`` (no recompilation).

The pieces live beside it: the observation's layout, bounds and normalisation
in :mod:`simgrip.envs.pick_observation`, the box-finger contact forces in
:mod:`simgrip.envs.pick_contacts`, the reward terms in
:mod:`simgrip.envs.pick_reward`; this module holds the environment's
arguments, episode bookkeeping (lift, hold, drop, knock-over) and the
Gymnasium API.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from simgrip.envs.arguments import check_bool as _bool
from simgrip.envs.arguments import check_camera, check_reset, check_size, check_within, set_finger_arguments
from simgrip.envs.arguments import check_positive as _pos
from simgrip.envs.arguments import check_range as _range
from simgrip.envs.arguments import set_task_arguments
from simgrip.envs.palm_servo import palm_command
from simgrip.envs.pick_contacts import BoxContactForces
from simgrip.envs.pick_model import build_pick_model, resize_workpiece
from simgrip.envs.pick_observation import OBS_LAYOUT, PickObservation, obs_layout
from simgrip.envs.pick_reward import PickReward, progress
from simgrip.envs.pick_step import CheckedStep
from simgrip.envs.pick_validity import FingerValidity
from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.sim.checks import PhysicsError, StateCheck, check_invalid_state
from simgrip.sim.gl import make_renderer

__all__ = ["PickEnv", "BoxParams", "OBS_LAYOUT", "obs_layout"]  # the last two from pick_observation

GRIP_ALIASES = {"I": "I", "i": "I", "pinch": "I", "III": "III", "iii": "III", "cradle": "III"}
_COS_TILT = math.cos(math.radians(30.0))  # knocked over beyond this tilt


@dataclass(frozen=True)
class BoxParams:
    """The box of one episode (SI): full width along ``x`` [m], mass [kg], finger-box friction."""

    width: float
    mass: float
    friction: float


class PickEnv(CheckedStep, gym.Env):
    r"""Pick a box off a table with two soft pneumatic fingers (curvature control).

    ## Description

    A palm carries two mirrored soft fingers (planar hinge chains, ``n_links``
    links each, built by :func:`simgrip.sim.fingers.add_fingers`).  The pneumatic
    pressure is modelled by the fingers' intrinsic curvature
    :math:`\bar\kappa_0 = \ell\kappa_0` (uniform along the finger), which follows
    its command with a first-order lag of time constant ``kappa_tau``.  The
    agent curls the fingers around a box resting on a table and lifts the palm:
    the box must rise by ``target_height`` and stay there for ``hold_time``,
    squeezed no harder than needed.  Axes: ``x`` from the palm centre towards
    finger 0, ``z`` up (the paper's ``E1``, ``E2``); the table top is ``z = 0``.
    The task is planar: nothing moves along ``y``.

    Grips (``grip``):

    | grip | id | scene |
    |------|----|-------|
    | ``"I"`` (pinch) | ``simgrip/Pick-v1`` | palm down, the fingertips pinch the box's side faces |
    | ``"III"`` (cradle) | ``simgrip/PickCradle-v1`` | the box (3.5 cm tall) stands on a narrow 4 cm pedestal; the fingers curl under its lower edges and carry it on their links |

    ## Physical defaults (SI) and the paper's groups

    A PneuNet-like silicone finger: length ``length = 0.10 m``; mass per length ``rho = 0.15 kg/m`` (15 g of
    elastomer and strain-limiting layer); bending stiffness ``EI = 3.0e-3 N m^2`` (a 15 mm x 15 mm elastomer
    section with ``E ~ 1 MPa`` gives ``E b h^3/12 ~ 4e-3``, less for the air chambers); tip sphere and link
    capsules of radius 4 mm (contact geometry; the mechanics is the centreline).  Box: 6 cm tall, 4 cm deep,
    width 4-6.5 cm, mass 20-60 g, finger-box friction 0.5-1.2 (silicone on card or plastic).  Then ``D = EI/(rho
    g l^3) = 2.04`` and, per finger (half the box), ``M = m/(rho l) = 0.67 - 2.0``, ``b/l = 0.4 - 0.65``.
    :meth:`dimensionless` returns the current episode's groups.

    Simulation: ``timestep = 2 ms``, ``frame_skip = 10`` (control at 50 Hz), implicitfast integrator, elliptic
    friction cones, Newton solver (50 iterations), ``impratio = 1``.  The hinges carry stiffness-proportional
    damping (``finger_damping_time = 20 ms``, lossy silicone) and an armature of ``1e-5 kg m^2`` (numerical: it
    slows the hinge modes so that 2 ms steps and the friction solve stay well conditioned; equilibria are
    unchanged). Tip and link contacts are condim 4 (torsional friction ``spin_friction * mu``) so the box cannot
    swing about the line through the tips.  The palm slides vertically on a joint driven by a stiff, critically
    damped position servo.  Contacts are explicit pairs only (tip and links of each finger, and the palm slab,
    with the box; box with table/pedestal).  A MuJoCo warning or a non-finite state during ``reset`` or ``step``
    raises :class:`simgrip.sim.checks.PhysicsError`.

    Dynamics of the default finger (straight and sagging, palm held; measured by
    ``tests/test_finger_damping.py`` with :mod:`simgrip.envs.finger_dynamics`): its first bending mode (fingers
    in antiphase, the palm still) has 7.66 Hz and zeta = 0.479 in the continuous model, 7.50 Hz and zeta = 0.469
    in MuJoCo at the 2 ms step (the integrator's first-order error); in phase, with the palm servo taking part,
    7.62 Hz, zeta = 0.476 (7.46 Hz, zeta = 0.465, damped 6.60 Hz at 2 ms).  The damping is
    stiffness-proportional (``zeta_i = omega_i finger_damping_time / 2`` without gravity), so every higher mode
    is overdamped; curled, the first mode stiffens and damps more (palm still, continuous model: kappa_bar = -3:
    9.30 Hz, zeta = 0.555; -6: 14.17 Hz, zeta = 0.891; -10: overdamped).  Released straight, the fingers reach
    their sag within 2 % after 0.18 s (after ``settle_time`` 11 % of it is left); a step of the curvature
    command moves the tip 63 % of the way after 0.10 s and within 2 % after 0.40 s (``kappa_tau`` dominates).
    The highest mode has omega_max dt = 0.48 (undamped limit 2; with the damping implicit the step is stable for
    any ``timestep < 2 finger_damping_time``).  The armature lowers the first mode by 3 % (7.90 Hz without it)
    and the second from 48.7 Hz to 26.0 Hz; without it omega_max dt = 21 and only the implicit damping keeps the
    2 ms step stable.

    ## Action space

    ``Box(-1, 1, (2,), float32)`` (``per_finger=False``) or ``(3,)``
    (``per_finger=True``).  Values outside ``[-1, 1]`` are clipped; NaN, inf or
    a wrong shape raise ``ValueError``.  ``action_names`` names them in order.

    | index | action | maps to |
    |-------|--------|---------|
    | 0 | curvature command (both fingers, or finger 0) | :math:`\bar\kappa_{cmd} = k_{lo} + (a+1)/2\,(k_{hi} - k_{lo})`, ``kappa_range = (k_lo, k_hi)``, default ``(-10, 0)``: ``-1`` curls fully, ``+1`` straightens |
    | (1) | curvature command of finger 1 (``per_finger=True``) | as above |
    | last | palm vertical velocity | ``a * palm_speed`` [m/s] (default 0.1 m/s), integrated into the palm's target height, which is kept in ``palm_range`` |

    ## Observation space

    ``Box(low, high, (11 + K,), float64)`` with ``K = shape_points``: 19
    entries by default; ``(21 + 2 K,)`` (37) with ``per_finger=True``.  Every
    entry varies during an episode.  One command drives both fingers unless
    ``per_finger``: the scene is then mirror-symmetric (finger 1 is finger 0's
    mirror image to ~1e-9, the box moves along ``z`` only), so finger 1 and the
    box's ``x``, tilt and spin are left out; with ``per_finger`` they are in
    (the rows marked pf).  Nothing out of the plane is observed.  Lengths are
    in finger lengths ``l`` (``length``), velocities in ``l`` per second,
    angles in radians, forces in units of the mean box weight ``W = g *
    mean(box_mass_range)`` (a constant of the env, not the episode's box).
    Positions and velocities are relative to the palm (finger roots), in
    world axes.  Values are clipped to the bounds listed, which normal use does
    not reach.  ``obs_layout`` holds the ``(name, size)`` blocks and
    ``obs_slices`` their slices.

    | index (default) | name | size | meaning | unit | bounds |
    |-----------------|------|------|---------|------|--------|
    | 0 | ``palm_height`` | 1 | palm (finger roots) above the table | l | [0, 10] |
    | 1 | ``kappa_command`` | 1 (pf 2) | curvature command, in action units (the action that gives it) | - | [-2, 2] |
    | 2 | ``kappa_actual`` | 1 (pf 2) | actual curvature after the lag, in action units | - | [-2, 2] |
    | 3:11 | ``finger_shape`` | K (pf 2K) | tangent angle (each finger in its own frame, counter-clockwise positive, 0 along a straight finger) at ``K`` arc lengths ``s/l = (k+1/2)/K``, interpolated between link midpoints (independent of ``n_links``); finger 0 (then finger 1) | rad | [-B, B], ``B = max(20, 2 max abs kappa_range)`` |
    | 11:13 | ``tip_position`` | 2 (pf 4) | fingertip ``(x, z)`` relative to the palm; finger 0 (then finger 1, its tip at ``x < 0``) | l | [-5, 5] |
    | 13 | ``box_position`` | 1 (pf 2) | box centre ``z`` (pf: ``(x, z)``) relative to the palm | l | [-10, 10] |
    | pf | ``box_tilt`` | (pf 1) | box rotation about ``y`` (its ``z`` axis towards ``+x`` is positive) | rad | [-pi, pi] |
    | 14 | ``box_velocity`` | 1 (pf 2) | box centre velocity ``v_z`` (pf: ``(v_x, v_z)``) relative to the palm | l/s | [-100, 100] |
    | pf | ``box_spin`` | (pf 1) | box angular velocity about ``y`` times 0.1 s (``SPIN_TIME``) | rad | [-100, 100] |
    | 15 | ``box_lift`` | 1 | box height gained since the start of the episode, in units of ``target_height`` (1 = at the target) | - | [-20, 20] |
    | 16:18 | ``contact_force`` | 2 (pf 4) | ``log(1 + F/W)`` of the box's contact force on finger 0 (then finger 1): normal, friction magnitude | - | [0, 20] |
    | 18 | ``hold`` | 1 | time held at the target, in units of ``hold_time`` (success at 1) | - | [0, 1] |

    ## Rewards

    ``reward = lift + success + squeeze + drop``; each term is in ``info`` as
    ``reward_lift``, ``reward_success``, ``reward_squeeze``, ``reward_drop``.
    Let ``phi = clip(dz / target_height, 0, 1)`` be the progress (``dz`` the box's
    height gain since the start of the episode; ``phi = 0`` once the box is
    lost).

    | term | value | over an episode |
    |------|-------|-----------------|
    | lift | ``w_lift * (phi_t - phi_{t-1})``: progress paid as height gained, taken back when the box sinks or is lost | sums to ``w_lift * phi_final`` in ``[0, w_lift]`` (10) |
    | success | ``w_success`` once, on the step the box has stayed ``>= target_height`` above its start, touched by both fingers, for ``hold_time``; the episode terminates | ``w_success`` (20) |
    | squeeze | ``-w_squeeze * mean_f x_f / (1 + x_f)``, ``x_f = max(0, S_f - squeeze_margin * N_need) / (m g)``: ``S_f`` is the horizontal (squeezing) component of finger ``f``'s normal forces on the box, ``N_need = m g / (2 mu)`` the least that holds it; pressing on the box's top is not counted | in ``[-w_squeeze, 0]`` per step (0.04) |
    | drop | ``-w_drop`` once, when the box is dropped or knocked over (the episode terminates) | ``-w_drop`` (-10) |

    Ordering, with the defaults and the registered time limits (``T`` = 200 or
    250 steps): any success returns at least ``w_lift + w_success - w_squeeze T
    >= 20``; any episode without success at most ``w_lift = 10`` (hovering just
    below the target), doing nothing 0, a drop at most ``-w_drop``.  Since
    ``w_squeeze T <= w_drop``, ending an episode by dropping the box never pays
    more than going on, however hard the fingers squeeze.

    ## Starting state

    Box (width, mass, friction drawn uniformly from ``box_width_range``,
    ``box_mass_range``, ``friction_range`` with the ``reset`` seed; fixed
    values via ``reset(options={"box_width": ..., "box_mass": ...,
    "friction": ..., "palm_height": ...})``) at rest on the table (Grip I) or
    the pedestal (Grip III), centred under the palm.  Palm at a height drawn
    from ``palm_start``; fingers straight with zero curvature, left to settle
    under gravity for ``settle_time`` before the first observation.  ``info``
    of ``reset`` holds the box parameters and the dimensionless groups.

    ## Episode end

    Terminates on success, on a drop (the box, once lifted by 5 mm, has sunk
    more than ``drop_distance`` relative to the palm from where it was when
    first lifted; releasing it counts as a drop) and on knocking it over
    (tilted more than 30 degrees, or pushed more than 3 cm sideways).  Time
    limit at registration: 200 steps (4 s) for ``Pick-v1`` and 250 for
    ``PickCradle-v1``; ``step`` itself never truncates.  Calling ``step``
    after the episode has terminated (or before the first ``reset``) raises
    :class:`gymnasium.error.ResetNeeded`: as Gymnasium's ``Env.step`` says,
    the user needs to call ``reset`` then.

    ## Info

    Every ``step``'s ``info``: ``is_success`` (the episode ended in success: the box held ``target_height`` up
    for ``hold_time``), ``dropped``, ``knocked_over`` (it ended in that failure), ``box_lift`` (height gained
    since the start over ``target_height``; ``workpiece_lift`` in the other envs), ``normal_force``,
    ``friction_force``, ``side_force`` (per finger, on the box [N]), ``hold_time`` [s], the reward's terms
    (``reward_lift``, ``reward_success``, ``reward_squeeze``, ``reward_drop``) and ``valid`` (no finger through
    itself or the other; else ``invalid`` lists the messages).

    ## Arguments

    Every argument is checked: a bad value raises ``ValueError`` naming it.  They are read once, at
    construction (the reward weights at each ``reset``): to change one, make a new environment.

    | argument | default | meaning |
    |----------|---------|---------|
    | ``grip`` | ``"I"`` | ``"I"``/``"pinch"`` or ``"III"``/``"cradle"`` |
    | ``render_mode`` | ``None`` | ``None`` or ``"rgb_array"`` |
    | ``n_links`` | 12 | links per finger |
    | ``length``, ``EI``, ``rho``, ``g`` | 0.1, 3e-3, 0.15, 9.81 | finger (SI) |
    | ``box_width_range``, ``box_mass_range``, ``friction_range`` | (0.04, 0.065), (0.02, 0.06), (0.5, 1.2) | domain randomisation |
    | ``box_height``, ``box_depth`` | 0.06 (cradle 0.035), 0.04 | box size [m] |
    | ``per_finger`` | False | one curvature command per finger |
    | ``kappa_range`` | (-10, 0) | curvature command bounds (dimensionless, low < high) |
    | ``kappa_tau`` | 0.1 | pneumatic lag [s] (0: none) |
    | ``palm_speed``, ``palm_range``, ``palm_start`` | 0.1, (0.05, 0.25), (0.105, 0.115) (cradle (0.13, 0.14)) | palm speed [m/s], target range, start range [m] |
    | ``palm_ramp`` | False | the palm's target held over a control step (False) or ramped within it (:mod:`simgrip.envs.palm_servo`) |
    | ``target_height``, ``hold_time`` | 0.06 (cradle 0.08), 0.5 | success: box height gain [m] (more than curling the fingers alone gives: up to 4.7 cm pinched, 5.7 cm cradled), hold [s] |
    | ``w_lift``, ``w_success``, ``w_squeeze``, ``w_drop`` | 10, 20, 0.04, 10 | reward weights (>= 0) |
    | ``squeeze_margin``, ``drop_distance`` | 2.0, 0.02 | squeeze allowance (times the least normal force that holds), drop threshold [m] |
    | ``timestep``, ``frame_skip``, ``settle_time`` | 0.002, 10, 0.1 | physics step [s] (below ``2 finger_damping_time``), steps per action (``timestep * frame_skip <= 1 s``), settling at reset [s] (at most 10) |
    | ``finger_damping_time``, ``finger_armature`` | 0.02, 1e-5 | hinge damping / stiffness [s], hinge armature [kg m^2] |
    | ``r_tip``, ``spin_friction``, ``impratio`` | 0.004, 0.004, 1 | tip/link radius [m], torsional friction length [m], MuJoCo impratio |
    | ``shape_points`` | 8 | finger shape samples per finger (2 to 1000) |
    | ``width``, ``height``, ``camera`` | 480, 360, ``"front"`` | rendering (pixels, a camera of the model) |

    ## Version history

    * v1: reward terms that rank success above every failure (progress paid as
      height gained, a bounded squeeze penalty on the side contacts only, no
      success bonus after the end: ``step`` after termination raises);
      observations in finger lengths and box weights with the out-of-plane and
      mirrored entries dropped (42 -> 19, 37 with ``per_finger``); every constructor argument
      validated; pickling and ``copy.deepcopy`` continue the episode exactly;
      ``target_height`` raised from 3 cm to 6 cm (cradle 8 cm), above what curling
      the fingers alone lifts the box.
      v0 is retired: ``gym.make("simgrip/Pick-v0")`` raises Gymnasium's
      ``DeprecatedEnv`` pointing to v1.
    * v0: initial version.
    """

    _tactile_unit: float | None = None  # the tactile scale W [N] (None: g times the mean mass)

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
        target_height: float | None = None,
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
        camera: str = "front",
        palm_ramp: bool = False,
    ):
        if not isinstance(grip, str) or grip.strip() not in GRIP_ALIASES:
            raise ValueError(f"grip must be 'I' (pinch) or 'III' (cradle), got {grip!r}")
        self.grip = GRIP_ALIASES[grip.strip()]
        set_finger_arguments(self, render_mode=render_mode, n_links=n_links, length=length, EI=EI, rho=rho, g=g,
                             r_tip=r_tip)
        self.box_width_range = _range("box_width_range", box_width_range, hi=2 * self.length, why="twice length")
        self.box_mass_range = _range("box_mass_range", box_mass_range)
        self.friction_range = _range("friction_range", friction_range)
        box_height = (0.06 if self.grip == "I" else 0.035) if box_height is None else box_height
        self.box_height = check_size("box_height", box_height, self.length)
        self.box_depth = check_size("box_depth", box_depth, self.length)
        self.per_finger = _bool("per_finger", per_finger)
        if palm_start is None:
            palm_start = (0.105, 0.115) if self.grip == "I" else (0.13, 0.14)
        if target_height is None:
            # higher than curling the fingers alone raises the box (up to ~4.7 cm pinched, ~5.7 cm cradled)
            target_height = 0.06 if self.grip == "I" else 0.08
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
        na = 3 if self.per_finger else 2
        self.action_space = spaces.Box(-1.0, 1.0, (na,), dtype=np.float32)
        self._action_shape = (na,)
        self.action_names = ("curvature_0", "curvature_1", "palm_z") if self.per_finger else ("curvature", "palm_z")
        # W of the tactile observation log(1 + F/W) [N]: the mean weight, or a subclass's sensor scale
        self._force_unit = self._tactile_unit or self.g * float(np.mean(self.box_mass_range))
        self._observe = PickObservation(
            n_links=self.n, shape_points=self.shape_points, per_finger=self.per_finger, kappa_range=self.kappa_range,
            length=self.length, target_height=self.target_height, hold_time=self.hold_time,
            force_unit=self._force_unit, palm_qpos=self.palm_qpos, palm_dof=self.palm_dof, box_qpos=self.box_qpos,
            box_dof=self.box_dof, tips=(int(self.fingers.tip_geom[0]), int(self.fingers.tip_geom[1])),
            hinge_qpos=self._fq)
        self.obs_layout, self.obs_slices = self._observe.layout, self._observe.slices
        self.observation_space = spaces.Box(self._observe.low, self._observe.high, dtype=np.float64)
        self._bind_views()
        self._renderer = None
        self.box = BoxParams(np.mean(self.box_width_range), np.mean(self.box_mass_range), np.mean(self.friction_range))
        self._reset_state()

    # ------------------------------------------------------------------ model
    def _build(self):
        """Build the model (:func:`simgrip.envs.pick_model.build_pick_model`) and keep what ``step`` reads."""
        L, n = self.length, self.n
        mid_w = float(np.mean(self.box_width_range))
        mu0 = float(np.mean(self.friction_range))
        self.physical = PhysicalParams(length=L, EI=self.EI, rho=self.rho, g=self.g,
                                       m=0.5 * float(np.mean(self.box_mass_range)), b=min(mid_w, 1.9 * L),
                                       mu_s=mu0, gamma=0.8 * L)
        pm = build_pick_model(self.grip, n_links=n, length=L, EI=self.EI, rho=self.rho, g=self.g, r_tip=self.r_tip,
                              box_size=(mid_w, self.box_depth, self.box_height), box_mass_max=self.box_mass_range[1],
                              friction=mu0, spin_friction=self.spin_friction, timestep=self.timestep,
                              impratio=self.impratio, damping_time=self.finger_damping_time,
                              armature=self.finger_armature, palm_ramp=self.palm_ramp, palm_range=self.palm_range)
        self.spec, self.model = pm.spec, pm.model
        self._palm = palm_command(self, pm.model)
        self.data = mujoco.MjData(self.model)
        self.fingers = pm.fingers
        self._validity = FingerValidity(self.model, pm.fingers)  # info["valid"] (issue 17)
        self.palm_qpos, self.palm_dof = pm.palm_qpos, pm.palm_dof
        self.box_qpos, self.box_dof, self.box_body, self.box_geom = pm.box_qpos, pm.box_dof, pm.box_body, pm.box_geom
        self._finger_pair_ids = pm.finger_pairs
        self._pedestal_h = pm.pedestal_height
        self._unit_rest = pm.unit_rest
        self._rest_buf = np.empty((2, n))
        self._unit_rest2 = np.array([self._unit_rest, self._unit_rest])  # both fingers' rows
        self._spring_idx = pm.fingers.joint_qpos.ravel()
        hinges = pm.fingers.hinge_qpos
        self._fq = (hinges,) if hinges is not None else (pm.fingers.joint_qpos,)
        self._contact_forces = BoxContactForces(self.model, self.box_geom, pm.fingers.finger_of_geom)

    @property
    def joint_qpos(self) -> np.ndarray:
        """qpos addresses of the finger hinges, (2, n_links) (read-only)."""
        return self.fingers.joint_qpos

    @property
    def joint_dof(self) -> np.ndarray:
        """dof addresses of the finger hinges, (2, n_links) (read-only)."""
        return self.fingers.joint_dof

    @property
    def tip_geom(self) -> np.ndarray:
        """Geom ids of the two tip spheres (read-only)."""
        return self.fingers.tip_geom

    # ------------------------------------------------------------- helpers
    def dimensionless(self) -> DimensionlessParams:
        """The paper's groups for the current episode (per finger: half the box; ``b`` is the box width)."""
        return self.physical_params().dimensionless()

    def physical_params(self) -> PhysicalParams:
        """:class:`~simgrip.params.PhysicalParams` of the current episode (``m`` = half the box mass)."""
        return PhysicalParams(length=self.length, EI=self.EI, rho=self.rho, g=self.g, m=0.5 * self.box.mass,
                              b=self.box.width, mu_s=self.box.friction, gamma=0.8 * self.length)

    def _set_box(self, box: BoxParams):
        """Resize the box to ``box`` (:func:`~simgrip.envs.pick_model.resize_workpiece`) and keep it."""
        size = (0.5 * box.width, 0.5 * self.box_depth, 0.5 * self.box_height)
        resize_workpiece(self.model, self.data, shape="box", geom=self.box_geom, body=self.box_body,
                         pairs=self._finger_pair_ids, size=size, mass=box.mass, friction=box.friction,
                         spin_friction=self.spin_friction)
        self.box = box

    def _set_rest(self, k0: float, k1: float):
        """Write the rest angles of curvatures ``k0``, ``k1`` (fingers 0 and 1) into ``model.qpos_spring``."""
        if self._spring_view is not None:
            # one command for both fingers: one scalar times both rows (the same products as per finger)
            np.multiply(self._unit_rest2, k0 if k0 == k1 else np.array(((k0,), (k1,))), out=self._spring_view)
        else:  # pragma: no cover
            np.multiply.outer((k0, k1), self._unit_rest, out=self._rest_buf)
            self.model.qpos_spring[self._spring_idx] = self._rest_buf.ravel()

    def _reset_state(self):
        self._kcmd = (0.0, 0.0)  # commanded curvatures of fingers 0 and 1
        self._kact = (0.0, 0.0)  # actual curvatures (after the lag)
        self._z0 = 0.0
        self._xy0 = (0.0, 0.0)  # the box's starting (x, y)
        self._lifted_rel = None
        self._hold = 0.0
        self._phi = 0.0
        self._reward = PickReward(box_mass=self.box.mass, g=self.g, friction=self.box.friction, w_lift=self.w_lift,
                                  w_success=self.w_success, w_squeeze=self.w_squeeze, w_drop=self.w_drop,
                                  squeeze_margin=self.squeeze_margin)
        self._needs_reset = True  # until reset() has run; again once the episode terminates

    # Pickling and deep copies: the state is the model (its rest angles change at run time), the data
    # (including the solver's warm start), the lag filter, the palm target, the episode's bookkeeping and
    # the RNG, all plain attributes; what must be rebuilt is the views into the model and the data bound by
    # _bind_views (a pickled view would be a stale copy) and the renderer (a GL context, made again on the
    # next render()).
    _VIEWS = ("_spring_view", "_check", "_qpos", "_qvel", "_ctrl", "_tips", "_hot")

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_renderer"] = None
        for name in self._VIEWS:
            state[name] = None
        if isinstance(state.get("spec"), mujoco.MjSpec):  # the builder's MjSpec cannot be pickled
            state["spec"] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._bind_views()

    def _bind_views(self):
        """Bind what every step reads and writes, once: ``_spring_view`` (the fingers' rest angles inside
        ``model.qpos_spring``, when contiguous), ``_check`` (the state check), views of ``data.qpos``,
        ``data.qvel``, ``data.ctrl`` and the tips' ``geom_xpos`` rows."""
        d = self.data
        self._check = StateCheck(d)
        flat = self._spring_idx
        if np.array_equal(flat, np.arange(flat[0], flat[0] + flat.size)):
            self._spring_view = self.model.qpos_spring[flat[0]:flat[0] + flat.size].reshape(2, self.n)
        else:  # pragma: no cover - the builder always makes them contiguous
            self._spring_view = None
        self._qpos, self._qvel, self._ctrl = d.qpos, d.qvel, d.ctrl
        self._tips = (d.geom_xpos[int(self.fingers.tip_geom[0])], d.geom_xpos[int(self.fingers.tip_geom[1])])
        # what step() reads, in one tuple (one attribute lookup); the constants beside it never change
        self._hot = (self.model, d, self._check, self._qpos, self._qvel, self._ctrl, self._tips[0], self._tips[1],
                     self._contact_forces, self._observe, d.warning.number, self._spring_view, self._unit_rest2)
        self._consts = (self.kappa_range[0], self.kappa_range[1], self.per_finger, self._lag_alpha, self.dt,
                        self.frame_skip, self.box_qpos, self.palm_qpos, self.target_height, self.hold_time,
                        self.drop_distance)

    def _get_obs(self, forces, q: list, v: list):
        """The observation (``q``, ``v``: ``data.qpos.tolist()``, ``data.qvel.tolist()``)."""
        (c0, c1), (k0, k1) = self._kcmd, self._kact
        return self._observe.observe(q, v, self._tips[0], self._tips[1], c0, c1, k0, k1, forces, self._z0, self._hold)

    # --------------------------------------------------------------- API
    def reset(self, *, seed=None, options=None):
        seed, options = check_reset(seed, options, ("box_width", "box_mass", "friction", "palm_height"))
        super().reset(seed=seed)
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
        palm_z = check_within("palm_height", options.get("palm_height", palm_z), *self.palm_range, "palm_range")
        m, d = self.model, self.data
        self._set_box(BoxParams(width, mass, mu))
        mujoco.mj_resetData(m, d)
        self._reset_state()
        self._set_rest(0.0, 0.0)
        d.qpos[self.palm_qpos] = palm_z
        self._palm.reset(d, palm_z)
        d.qpos[self.box_qpos:self.box_qpos + 3] = [0.0, 0.0, self._pedestal_h + 0.5 * self.box_height]
        d.qpos[self.box_qpos + 3:self.box_qpos + 7] = [1.0, 0.0, 0.0, 0.0]
        self._start_shape()  # the fingers' shape before the settle (a subclass's pre-grasp; here straight)
        with check_invalid_state(d, "reset: settling the fingers and box"):
            mujoco.mj_forward(m, d)
            if self.settle_steps:
                mujoco.mj_step(m, d, nstep=self.settle_steps)
        self._z0 = float(d.qpos[self.box_qpos + 2])
        self._xy0 = tuple(d.qpos[self.box_qpos:self.box_qpos + 2].tolist())
        self._needs_reset = False
        forces = self._contact_forces(self.model, self.data)
        info = {
            "box_width": width, "box_mass": mass, "box_friction": mu, "palm_height": palm_z,
            "dimensionless": self.dimensionless(),
        }
        return self._get_obs(forces, d.qpos.tolist(), d.qvel.tolist()), info

    def _start_shape(self):
        """Shape the fingers before the reset's settle: straight here (see :mod:`simgrip.envs.pick_fragile_v4`)."""

    def _step_checked(self, a: list):
        # step(action) checked the episode and the action (pick_step.CheckedStep). Every line here runs once per control step beside
        # frame_skip mj_step calls: constants and views are bound once (_bind_views), arrays read as lists (one
        # tolist each) and combined in Python.
        lo, hi, per_finger, alpha, dt, fs, bq, pq, target, hold_time, drop = self._consts
        model, data, check, qpos, qvel, ctrl, tip0, tip1, contact_forces, observe, warnings, rest, unit = self._hot
        k0 = lo + 0.5 * (a[0] + 1.0) * (hi - lo)
        k1 = lo + 0.5 * (a[1] + 1.0) * (hi - lo) if per_finger else k0
        self._kcmd = (k0, k1)
        # pneumatic lag: exact first-order response over one control step, rest angles held within it
        c0, c1 = self._kact
        c0, c1 = c0 + alpha * (k0 - c0), c1 + alpha * (k1 - c1)
        self._kact = (c0, c1)
        if rest is not None and c0 == c1:  # _set_rest(c0, c1), written out for its usual case
            np.multiply(unit, c0, out=rest)
        else:
            self._set_rest(c0, c1)
        self._palm.command(ctrl, a[-1])  # the palm's target, held or ramped over the step (envs.palm_servo)
        warnings.fill(0)  # check.clear()
        mujoco.mj_step(model, data, fs)  # nstep = frame_skip (positional: pybind's keyword parsing costs more)
        q, v = qpos.tolist(), qvel.tolist()
        if any(warnings.tolist()) or not math.isfinite(sum(q) + sum(v)):  # StateCheck's test, its call saved
            why = check(q, v)  # (None where a huge finite state overflowed the sums)
            if why is not None:
                self._needs_reset = True
                raise PhysicsError(f"step diverged ({why})")

        forces = contact_forces(model, data)
        bx, by, box_z, qx, qy = q[bq], q[bq + 1], q[bq + 2], q[bq + 4], q[bq + 5]
        gain = box_z - self._z0
        rel = box_z - q[pq]
        n0, f0, n1, f1, s0, s1 = forces
        self._normal = (n0, n1)  # info["normal_force"] as floats, for the subclasses' per-step rules
        both = n0 > 0.0 and n1 > 0.0
        lifted_rel = self._lifted_rel
        if lifted_rel is None and gain > 0.005 and both:
            self._lifted_rel = lifted_rel = rel
        dropped = lifted_rel is not None and rel < lifted_rel - drop
        up_z = 1.0 - 2.0 * (qx * qx + qy * qy)  # z component of the box's z axis
        x0, y0 = self._xy0
        shifted = math.hypot(bx - x0, by - y0) > 0.03
        knocked = up_z < _COS_TILT or shifted
        self._hold = hold = self._hold + dt if gain >= target and both else 0.0
        success = hold > 0.0 and hold >= hold_time - 1e-9  # (held this step: hold_time 0 still needs the lift)
        lost = (dropped or knocked) and not success
        phi = progress(gain, target, lost)
        reward, r_lift, r_success, r_squeeze, r_drop = self._reward(phi, self._phi, success, lost, s0, s1)
        self._phi = phi
        terminated = success or lost
        self._needs_reset = terminated
        obs = observe.observe(q, v, tip0, tip1, k0, k1, c0, c1, forces, self._z0, hold)
        info = {
            "reward_lift": r_lift, "reward_success": r_success, "reward_squeeze": r_squeeze, "reward_drop": r_drop,
            "is_success": success, "dropped": dropped and not success,
            "knocked_over": knocked and not success, "box_lift": gain,
            "normal_force": np.array((n0, n1)), "friction_force": np.array((f0, f1)),
            "side_force": np.array((s0, s1)), "hold_time": hold,
        }
        invalid = self._validity(q, data)  # a finger through itself or the other (envs.pick_validity)
        info["valid"] = not invalid
        if invalid:
            info["invalid"] = invalid
        return obs, reward, terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gymnasium.make")
            return None
        if self._renderer is None:
            self._renderer = make_renderer(self.model, self.height, self.width)  # headless: EGL, then OSMesa
        self._renderer.update_scene(self.data, camera=self.camera)
        return self._renderer.render().copy()

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
