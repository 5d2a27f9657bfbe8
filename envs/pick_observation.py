"""The pick environment's observation: its layout, bounds and normalisation.

:func:`obs_layout` names the observation's blocks; :class:`PickObservation`
holds what turns a MuJoCo state into the observation vector of
:class:`simgrip.envs.pick.PickEnv` (its docstring's table says what each entry
means).  Without ``per_finger`` the observation keeps finger 0 and the box's
``z`` of the per-finger layout (the bounds are reduced by one index array);
lengths are divided by the finger length, forces by the mean box weight, and
every entry is clipped to its bound.  It is computed on every environment
step, right after the physics, on Python floats (the state read as lists, the
finger shapes by linear interpolation of the link angles) and turned into an
array once.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["OBS_LAYOUT", "SPIN_TIME", "PickObservation", "finger_bounds", "obs_layout"]

#: The box's spin is observed as ``omega_y * SPIN_TIME`` (rad per 0.1 s).
SPIN_TIME = 0.1


def obs_layout(shape_points: int = 8, per_finger: bool = False) -> list[tuple[str, int]]:
    """``(name, size)`` of the observation's blocks, in order (see :class:`~simgrip.envs.pick.PickEnv`)."""
    # One command drives both fingers unless per_finger: the scene is then mirror-symmetric, finger 1 is
    # finger 0's mirror image (to ~1e-9) and the box moves along z only, so those entries are left out.
    nf = 2 if per_finger else 1
    blocks = [
        ("palm_height", 1),
        ("kappa_command", nf),
        ("kappa_actual", nf),
        ("finger_shape", nf * shape_points),
        ("tip_position", 2 * nf),
        ("box_position", nf),
        ("box_tilt", nf - 1),
        ("box_velocity", nf),
        ("box_spin", nf - 1),
        ("box_lift", 1),
        ("contact_force", 2 * nf),
        ("hold", 1),
    ]
    return [(name, size) for name, size in blocks if size]


#: Layout of the default observation (``shape_points = 8``, ``per_finger = False``): 19 entries.
OBS_LAYOUT = obs_layout(8)


def finger_bounds(kappa_range) -> dict:
    """``{name: (low, high)}`` of the observation blocks every pick environment has (the palm, curvatures,
    finger shapes, tips, contact forces, hold; units as the observation's), for ``kappa_range = (low, high)``."""
    lo, hi = kappa_range
    k_bound = max(2.0, abs(2.0 * (0.0 - lo) / (hi - lo) - 1.0))  # the fingers start straight (kappa = 0)
    a_bound = max(20.0, 2.0 * max(abs(lo), abs(hi)))
    return {"palm_height": (0, 10), "kappa_command": (-k_bound, k_bound), "kappa_actual": (-k_bound, k_bound),
            "finger_shape": (-a_bound, a_bound), "tip_position": (-5, 5), "contact_force": (0, 20), "hold": (0, 1)}


def _bounds(kappa_range, shape_points: int, per_finger: bool):
    """Layout, slices, the index array reducing the per-finger layout (or None), lower and upper bounds."""
    bounds = {**finger_bounds(kappa_range), "box_position": (-10, 10), "box_tilt": (-math.pi, math.pi),
              "box_velocity": (-100, 100), "box_spin": (-100, 100), "box_lift": (-20, 20)}
    # the observation is computed in the per-finger layout; without per_finger it keeps finger 0 and the box's z
    full, lows, highs, index = obs_layout(shape_points, True), [], [], {}
    for name, size in full:
        index[name] = list(range(len(lows), len(lows) + size))
        lows += [bounds[name][0]] * size
        highs += [bounds[name][1]] * size
    layout = obs_layout(shape_points, per_finger)
    keep = {"box_position": [1], "box_velocity": [1]}  # (x, z) -> z
    pick, slices = [], {}
    for name, size in layout:
        slices[name] = slice(len(pick), len(pick) + size)
        pick += [index[name][k] for k in keep.get(name, range(size))] if not per_finger else index[name]
    pick = None if per_finger else np.array(pick)
    low, high = np.array(lows, dtype=np.float64), np.array(highs, dtype=np.float64)
    if pick is not None:
        low, high = low[pick], high[pick]
    return layout, slices, pick, low, high


def _shape_function(hinges, lerp: tuple):
    """``shape(q) -> list``: one finger's shape samples from ``q = data.qpos.tolist()``, ``hinges`` its qpos
    addresses (a slice or a list), ``lerp`` the ``(i, w_a, w_b)`` of each sample (``theta = w_a c[i] + w_b
    c[i+1]``, ``c`` the link angles: the hinges' running sum).  Compiled once with the loops written out: the
    same additions and products in the same order as ``itertools.accumulate`` and the weighted sums (issue 18:
    the observation runs on every step)."""
    addrs = list(range(hinges.start, hinges.stop)) if isinstance(hinges, slice) else [int(a) for a in hinges]
    body = [f"    c0 = q[{addrs[0]}]"] + [f"    c{k} = c{k - 1} + q[{a}]" for k, a in enumerate(addrs[1:], 1)]
    samples = ", ".join(f"{float(wa)!r} * c{i} + {float(wb)!r} * c{i + 1}" for i, wa, wb in lerp)
    src = "def shape(q):\n" + "\n".join(body) + f"\n    return [{samples}]\n"
    scope: dict = {}
    exec(compile(src, "<pick_observation shape>", "exec"), scope)  # noqa: S102 - our own source
    return scope["shape"]


class PickObservation:
    """Turns the state of a pick model into the environment's observation vector.

    Parameters
    ----------
    n_links, shape_points, per_finger, kappa_range, length, target_height, hold_time
        As :class:`~simgrip.envs.pick.PickEnv`'s arguments (``length`` [m],
        ``target_height`` [m], ``hold_time`` [s]).
    force_unit : float
        Forces are observed as ``log(1 + F / force_unit)`` [N].
    palm_qpos, palm_dof, box_qpos, box_dof : int
        Addresses of the palm slide and the box's free joint.
    tips : tuple of int
        Geom ids of the two tip spheres.
    hinge_qpos : index
        qpos index of the fingers' hinges, finger 0 then finger 1 (``2 * n_links``): a slice (contiguous, the
        builder's case) or an index array.

    Attributes
    ----------
    layout, slices, low, high
        ``(name, size)`` blocks, their slices and the bounds of the observation.
    """

    #: clip by comparisons only when every entry is inside its bound (:meth:`observe`; False: clip every entry,
    #: the same values, for tests)
    _fast_clip = True

    def __init__(self, *, n_links, shape_points, per_finger, kappa_range, length, target_height, hold_time,
                 force_unit, palm_qpos, palm_dof, box_qpos, box_dof, tips, hinge_qpos):
        self.layout, self.slices, self._pick, self.low, self.high = _bounds(kappa_range, shape_points, per_finger)
        self.n = n_links
        self.kappa_range = kappa_range
        self.length = length
        self.target_height = target_height
        self.hold_time = hold_time
        self.force_unit = force_unit
        self.palm_qpos, self.palm_dof, self.box_qpos, self.box_dof = palm_qpos, palm_dof, box_qpos, box_dof
        self.tips = tips
        self.hinge_qpos = hinge_qpos
        self._inv_l = 1.0 / length
        self._consts = (self._inv_l, palm_qpos, palm_dof, box_qpos, box_dof, force_unit, kappa_range[0],
                        kappa_range[1] - kappa_range[0], target_height, hold_time)
        self._low, self._high = self.low.tolist(), self.high.tolist()
        # the shape samples' count (finger 0's, first in ``mid``) and bound [rad] (observe's second comparison-only case)
        self._n_shape = shape_points
        self._shape_lo, self._shape_hi = (float(x) for x in finger_bounds(kappa_range)["finger_shape"])
        # each finger's hinges in qpos: a slice where contiguous (the builder's case), else a list of addresses
        hq = hinge_qpos[0] if isinstance(hinge_qpos, tuple) and len(hinge_qpos) == 1 else hinge_qpos
        n = n_links
        if isinstance(hq, slice):
            self._hinges = tuple(slice(hq.start + f * n, hq.start + (f + 1) * n) for f in (0, 1))
        else:
            flat = np.asarray(hq).ravel().tolist()
            self._hinges = (flat[:n], flat[n:2 * n])
        # shape sampling: the tangent angle (the link angle, a cumulative sum of hinge angles, at each link's
        # midpoint s/l = (j+1/2)/n) interpolated linearly at s/l = (k+1/2)/K, held at the end values beyond the
        # first and last midpoints (np.interp's rule): theta_k = w_a c[i] + w_b c[i+1]
        s_link = (np.arange(n) + 0.5) / n
        lerp = []
        for s_k in (np.arange(shape_points) + 0.5) / shape_points:
            i = int(min(max(np.searchsorted(s_link, s_k, side="right") - 1, 0), n - 2))
            w = float(min(max((s_k - s_link[i]) / (s_link[i + 1] - s_link[i]), 0.0), 1.0))
            lerp.append((i, 1.0 - w, w))
        self._lerp = tuple(lerp)
        self._shapes = tuple(_shape_function(h, self._lerp) for h in self._hinges)

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_shapes"] = None  # compiled functions: made again from the hinges and weights (__setstate__)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._shapes = tuple(_shape_function(h, self._lerp) for h in self._hinges)

    def __call__(self, data, forces, kappa_cmd, kappa, z0: float, hold: float, qpos: list | None = None) -> np.ndarray:
        """The observation of ``data``.

        ``forces`` are :class:`~simgrip.envs.pick_contacts.BoxContactForces`' ``[normal_0, friction_0,
        normal_1, friction_1, ...]`` [N]; ``kappa_cmd``, ``kappa`` the commanded and actual curvatures (2,);
        ``z0`` the box's starting height [m]; ``hold`` the time held at the target [s]; ``qpos`` optionally
        ``data.qpos.tolist()`` when the caller has it.
        """
        xpos = data.geom_xpos
        c0, c1 = kappa_cmd
        k0, k1 = kappa
        return self.observe(data.qpos.tolist() if qpos is None else qpos, data.qvel.tolist(), xpos[self.tips[0]],
                            xpos[self.tips[1]], float(c0), float(c1), float(k0), float(k1), forces, z0, hold)

    def finger_shape(self, q: list, finger: int) -> list:
        """Tangent angles [rad] of ``finger`` at the ``shape_points`` arc lengths, from ``q = data.qpos.tolist()``."""
        return self._shapes[finger](q)  # (_shape_function: the link angles' running sum, then the weights)

    def observe(self, q: list, v: list, tip0, tip1, c0: float, c1: float, k0: float, k1: float, forces,
                z0: float, hold: float) -> np.ndarray:
        """The observation from values already read (the environment's step).

        ``q``, ``v``: ``data.qpos.tolist()``, ``data.qvel.tolist()``; ``tip0``, ``tip1``: the tips'
        ``geom_xpos`` rows (views are fine); ``c0, c1``, ``k0, k1``: commanded and actual curvatures; the rest
        as :meth:`__call__`.
        """
        # everything is computed on Python floats and clipped to the bounds in Python, one np.array at the end:
        # right after the physics the caches are cold, and numpy calls cost more there than these few lines
        inv_l, pq, pd, bq, bd, fu, lo, span, th, ht = self._consts  # curvatures in action units: lo, span
        palm_z, palm_v = q[pq], v[pd]
        x0, _, z0_tip = tip0.tolist()
        bz = q[bq + 2]
        hold_obs = min(hold / ht, 1.0) if ht > 0 else 0.0
        if self._pick is None:  # per_finger: both fingers, the box's x, tilt and spin
            bx, qw, qx, qy, qz = q[bq], q[bq + 3], q[bq + 4], q[bq + 5], q[bq + 6]
            x1, _, z1_tip = tip1.tolist()
            tilt = math.atan2(2.0 * (qx * qz + qw * qy), 1.0 - 2.0 * (qx * qx + qy * qy))
            vals = [palm_z * inv_l, 2.0 * (c0 - lo) / span - 1.0, 2.0 * (c1 - lo) / span - 1.0,
                    2.0 * (k0 - lo) / span - 1.0, 2.0 * (k1 - lo) / span - 1.0, *self.finger_shape(q, 0),
                    *self.finger_shape(q, 1),
                    x0 * inv_l, (z0_tip - palm_z) * inv_l, x1 * inv_l, (z1_tip - palm_z) * inv_l,
                    bx * inv_l, (bz - palm_z) * inv_l, tilt, v[bd] * inv_l, (v[bd + 2] - palm_v) * inv_l,
                    v[bd + 4] * SPIN_TIME, (bz - z0) / th,
                    math.log1p(forces[0] / fu), math.log1p(forces[1] / fu), math.log1p(forces[2] / fu),
                    math.log1p(forces[3] / fu), hold_obs]
        else:  # finger 0 and the box's z
            mid = self._shapes[0](q)  # finger_shape(q, 0)
            mid += [x0 * inv_l, (z0_tip - palm_z) * inv_l, (bz - palm_z) * inv_l, (v[bd + 2] - palm_v) * inv_l,
                    (bz - z0) / th]
            p = palm_z * inv_l
            f0, f1 = math.log1p(forces[0] / fu), math.log1p(forces[1] / fu)
            # the usual case, clipped by comparisons only: the shape, tip, box and lift entries (bounds +-5 or
            # wider) within +-5, the palm height in [0, 10], the forces in [0, 20]; the curvatures (in [lo, hi],
            # so within [-1, 1] in action units; bounds [-2, 2] or wider) and the hold (in [0, 1]) are inside
            # their bounds by construction.  Else every entry is clipped, as always (_fast_clip False: always)
            if (self._fast_clip and -5.0 <= min(mid) and max(mid) <= 5.0 and 0.0 <= p <= 10.0
                    and 0.0 <= f0 <= 20.0 and 0.0 <= f1 <= 20.0):
                return np.array([p, 2.0 * (c0 - lo) / span - 1.0, 2.0 * (k0 - lo) / span - 1.0, *mid, f0, f1,
                                 hold_obs])
            vals = [p, 2.0 * (c0 - lo) / span - 1.0, 2.0 * (k0 - lo) / span - 1.0, *mid, f0, f1, hold_obs]
            # next the curled fingers' case (the cradle's shape samples beyond -5 rad: a sixth of its random steps):
            # the same test with the shape samples against their own bound, still identity inside the bounds
            S = self._n_shape
            shape, rest = mid[:S], mid[S:]
            if (self._fast_clip and self._shape_lo <= min(shape) and max(shape) <= self._shape_hi
                    and -5.0 <= min(rest) and max(rest) <= 5.0 and 0.0 <= p <= 10.0 and 0.0 <= f0 <= 20.0
                    and 0.0 <= f1 <= 20.0):
                return np.array(vals)
        return np.array([lo_ if x < lo_ else (hi_ if x > hi_ else x)
                         for x, lo_, hi_ in zip(vals, self._low, self._high)])
