"""The statics of a one- or two-finger scene in the chains' own coordinates, with exact derivatives.

Unknowns: the link angles ``phi_0 .. phi_{n-1}`` of each finger, finger after
finger (MuJoCo's hinge angles are ``q_j = phi_j - phi_{j-1}``), and the
workpiece's dofs ``y``: its height ``w`` when it slides in ``z`` (one finger,
the symmetric reduction) or ``(x, z, ry)`` (two fingers: slides over ``l``, the
turn in radians).  Everything is dimensionless (lengths over ``l``, forces over
``rho g l``, moments over ``rho g l^2``) and read from the compiled model, so it
is the MuJoCo chain itself, not a copy of the theory:

* springs ``V_s = sum_j k_j/2 (q_j - r_j)^2`` (``jnt_stiffness``,
  ``qpos_spring``): force ``-dV_s/dphi_i = s_{i+1} - s_i`` with hinge moments
  ``s_j = k_j (q_j - r_j)``; Hessian tridiagonal (``k_i + k_{i+1}`` on the
  diagonal, ``-k_{i+1}`` beside it), with no coupling between two fingers;
* gravity ``V_g = sum_k c_k sin(phi_k)`` with ``c_k = g (m_k a_k + ds sum_{i>k}
  m_i)`` (``a_k`` the centre of mass along link ``k``): diagonal Hessian;
* a generalised force ``Q_q`` on the hinges is ``Q_q_j = sum_{i >= j} F_i`` of the
  link-angle force ``F`` (``phi = cumsum(q)`` per finger); the residual is reported in ``q``.

Each finger works in its own frame: finger 1 is finger 0 mirrored in ``x``, so
its links read exactly like finger 0's.  In finger ``f``'s frame (mirror
``m = +-1``) a workpiece point at body-local ``(a, c)`` sits at ``O + R(alpha)
(m a, c)`` with ``O = (m (x0 + y_x), z0 + y_z)`` and ``alpha = m y_ry`` (the
``ry`` hinge turns about ``-y``); ``R`` the rotation, ``perp(u) = (-u_z, u_x)``.

Contact and stick terms are all of one form, ``f = v . (p - c)`` with ``p`` a
point fixed on link ``i`` (``node_i + a_x t_i + a_z n_i``, ``t_i = (cos, sin)``,
``n_i = (-sin, cos)``), ``c = O + R(alpha) c_loc`` on the workpiece
(``dc/dy = dO/dy + dalpha/dy perp(R c_loc)``, ``d2c/dy2 = -dalpha dalpha' R c_loc``)
and ``v`` turning with link ``i`` (``R(phi_i) v_loc``) or with the workpiece
(``R(alpha) v_loc``: the box's face normal, a stick's tangent on the box).
With ``dp/dphi_k = ds n_k`` (``k < i``), ``dp/dphi_i = perp(p - node_i)``::

    df/dphi_k = v . ds n_k                (k < i)
    df/dphi_i = v . perp(p - node_i) [link v: + perp(v) . (p - c)]
    df/dy     = -v . dc/dy               [workpiece v: + dalpha/dy perp(v) . (p - c)]
    d2f/dphi_k^2  = -v . ds t_k           (k < i)
    d2f/dphi_i^2  = -v . (p - node_i)     [link v: + 2 v.(p - node_i) - v.(p - c)]

The rest of the Hessian is low rank (``U S U'``, rank <= 3).  Link ``v``: an
"arrow" on index ``i`` (``d2f/dphi_k dphi_i = perp(v) . ds n_k``, ``d2f/dphi_i dy
= -perp(v) . dc/dy``) plus ``d2f/dy2 = (v . R c_loc) dalpha dalpha'``:
``U = [e_i, h, dalpha]``.  Workpiece ``v``: ``d2f/dphi_k dy = dalpha_y perp(v) .
dp/dphi_k``, ``d2f/dy2 = -(v . (p - O)) dalpha dalpha' - (dalpha w' + w dalpha')``
(``w = perp(v) . dO/dy``): ``U = [g, dalpha]`` with ``g = (perp(v) . dp/dphi, -w)``.
A capsule end cap (Grip III corner beyond a node) is ``f = |c - p|``: gradient
``e . de/dx``, Hessian ``(1/|e|) u u' + diag(e . d2e) - (e . R c_loc) dalpha dalpha'``
with ``u = e_perp . de/dx``.  These are the sphere--face (Grips I/II) and
capsule--capsule (Grip III) distances of MuJoCo's collision functions, and the
sticking constraints of :class:`~simgrip.settle.statics.Stick`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.settle.banded import _F64, _MAX, solve_tridiagonal
from simgrip.sim.scene import Scene

__all__ = ["ChainModel", "Term", "eligible", "gravity_factor", "model_gravity"]

def _perp(v):
    return np.array([-v[1], v[0]])


def _rot(a) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def model_gravity(m) -> float:
    """Downward gravity [m/s^2] as MuJoCo applies it: ``-opt.gravity[2]``, or 0 under ``mjDSBL_GRAVITY``."""
    if int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY):
        return 0.0
    return -float(m.opt.gravity[2])


def gravity_factor(scene: Scene) -> float:
    """The scene's gravity over the physical ``g`` it was built with (1 physical, 0 gravity free).

    Read from the compiled model as MuJoCo applies it (:func:`model_gravity`):
    both a zeroed ``opt.gravity`` and the ``mjDSBL_GRAVITY`` flag switch it off.
    This is the ``gravity`` factor of :func:`simgrip.reference.solve_chain`.
    """
    return model_gravity(scene.model) / scene.physical.g


def eligible(scene: Scene) -> bool:
    """The chain-coordinate solve covers one- and two-finger scenes (workpiece fixed, in ``z``, or ``x, z, ry``)."""
    return tuple(scene.workpiece_joints) in ((), ("z",), ("x", "z", "ry")) and scene.mirror[0] == 1.0


def _structure(scene: Scene) -> dict:
    """What the chain model reads from the compiled model's topology alone, computed once per model.

    The contact pairs' geoms, each pair's finger, link and kind (tip sphere or capsule) and the link
    bodies' index: none of it changes with the parameters a compiled scene is set to in place
    (:mod:`simgrip.sim.reuse` keys its scenes on the structure), so it is kept on the scene with the
    model and finger index it was read from and read again only when either is another object.
    Nothing in it is written after it is built (callers read it only).
    """
    m = scene.model
    memo = scene.__dict__.get("_chain_structure")
    if memo is not None and memo[0] is m and memo[1] is scene.index:
        return memo[2]
    nf, nl = scene.fingers, scene.n
    n = nf * nl
    bodies = np.asarray(scene.link_body, int).reshape(nf, nl)
    link_index = {int(b): (f, i) for f in range(nf) for i, b in enumerate(bodies[f])}
    pairs = [(int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in range(m.npair)]
    sphere = int(mujoco.mjtGeom.mjGEOM_SPHERE)
    pair_link = [(*link_index[int(m.geom_bodyid[g1])], int(m.geom_type[g1]) == sphere) for g1, _ in pairs]
    jd = np.asarray(scene.joint_dof, int).reshape(-1)
    first = np.zeros(n, bool)  # a finger's first link, and its last
    first[::nl] = True
    last = np.zeros(n, bool)
    last[nl - 1::nl] = True
    out = {"link_index": link_index, "pairs": pairs, "pair_link": pair_link, "bodies": bodies,
           "jq": np.asarray(scene.joint_qpos, int).reshape(-1), "jd": jd, "jnt": m.dof_jntid[jd],
           "mir": np.asarray(scene.mirror, float), "first": first, "last": last, "first_at": np.flatnonzero(first),
           "last_at": np.flatnonzero(last),
           "wnames": tuple(scene.workpiece_joints), "wq": np.asarray(scene.workpiece_qpos, int),
           "wd": np.asarray(scene.workpiece_dof, int)}
    for v in out.values():
        if isinstance(v, np.ndarray):
            v.setflags(write=False)  # shared by every settle of the model: read only
    scene.__dict__["_chain_structure"] = (m, scene.index, out)
    return out


_GRAVITY_OFF = int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)


def _parameters(scene: Scene, st: dict) -> dict:
    """:class:`ChainModel`'s parameters of the scene's model in the chain's units, computed once per set of values.

    Stiffness ``k``, link length ``ds``, gravity moments ``c``, the springs' diagonal, the workpiece's weight,
    dof scales and rest position, the pairs' radii and the per-pair arrays of
    :meth:`ChainModel.pair_distances`: everything here is a function of the model fields and scene
    scalars in the key (``jnt_stiffness``, ``body_mass``, ``body_ipos``, ``body_pos``, ``geom_size``,
    ``geom_pos``, gravity as MuJoCo applies it, ``l``, ``rho g l``, the workpiece's mass), so the arrays
    are the ones a fresh computation gives, bit for bit.  A settle of a scene whose parameters did not
    change since the last one (a curvature sweep sets only ``qpos_spring``, which
    :meth:`ChainModel.internal` reads live) finds them in the one-entry memo kept on the scene with the
    model it was read from.  The arrays are read only (shared by every settle until a value changes).
    """
    m = scene.model
    opt = m.opt
    L, W = scene.length, scene.force_scale
    key = (L, W, float(scene.workpiece_mass), int(opt.disableflags) & _GRAVITY_OFF, opt.gravity.tobytes(),
           m.jnt_stiffness.tobytes(), m.body_mass.tobytes(), m.body_ipos.tobytes(), m.body_pos.tobytes(),
           m.geom_size.tobytes(), m.geom_pos.tobytes())
    memo = scene.__dict__.get("_chain_parameters")
    if memo is not None and memo[0] is m and memo[1] is scene.index and memo[2] == key:
        return memo[3]
    nf, nl = scene.fingers, scene.n
    n = nf * nl
    bodies = st["bodies"]
    out = {"L": L, "W": W}
    out["k"] = k = m.jnt_stiffness[st["jnt"]] / (W * L)
    out["ds"] = ds = float(m.body_pos[bodies[0, 1]][0]) / L
    g = model_gravity(m)
    # every finger at once (rows: the per-finger sums of the same terms in the same order)
    mass = m.body_mass[bodies]
    arm = m.body_ipos[bodies, 0] / L
    beyond = np.zeros((nf, nl))  # the mass beyond each link: suffix sums, the last link's 0
    beyond[:, :-1] = np.cumsum(mass[:, ::-1], axis=1)[:, ::-1][:, 1:]
    out["c"] = (g * (mass * arm + ds * beyond) / W).reshape(-1)
    # the next hinge's stiffness (0 beyond a finger's last link) and the springs' diagonal
    k_next = np.zeros(n)
    k_next[:-1] = k[1:]
    k_next[nl - 1::nl] = 0.0
    out["_k_next"] = k_next
    out["_k_diag"] = -(k + k_next)
    # the true weight (body_mass may be a floored inertia, its extra weight relieved: sim.workpiece.inertial_mass)
    out["weight"] = float(scene.workpiece_mass) * g / W if scene.has_workpiece else 0.0
    #: the workpiece dofs' scale: slides over l, the hinge in radians
    out["wscale"] = np.array([1.0 if nm == "ry" else L for nm in st["wnames"]])
    if scene.has_workpiece:
        p = m.body_pos[scene.workpiece_body] / L
        out["w0"] = np.array([p[0], p[2]])
    pairs, pair_link = st["pairs"], st["pair_link"]
    #: the radii each pair's distance subtracts (geom sizes: parameters)
    out["radius"] = [(m.geom_size[g1][0] + (0.0 if sphere else m.geom_size[g2][0])) / L
                     for (g1, g2), (_, _, sphere) in zip(pairs, pair_link)]
    if pairs:  # pair_distances' arrays (the same values ChainModel._geom_local and the sizes give)
        mir = st["mir"]
        pf = np.array([f for f, _, _ in pair_link])
        sph = np.array([sp for _, _, sp in pair_link])
        out.update(_pf=pf, _pl=np.array([i for _, i, _ in pair_link]), _sph=sph,
                   _gl=np.array([np.array([mir[f] * (m.geom_pos[g] / L)[0], (m.geom_pos[g] / L)[2]])
                                 for (f, _, _), (_, g) in zip(pair_link, pairs)]),
                   _hx=np.array([m.geom_size[g][0] / L for _, g in pairs]), _rad=np.array(out["radius"]),
                   _pidx=[np.flatnonzero(pf == f) for f in range(nf)],
                   _branch="face" if sph.all() else ("caps" if not sph.any() else "both"))
        out["_face_at"] = [(float(gl[0]) + float(m.geom_size[g][0]) / L, float(gl[1]) + 0.0) if sp else None
                           for gl, (_, g), (_, _, sp) in zip(out["_gl"], pairs, pair_link)]  # (pair_term's face points)
        if out["_branch"] == "face" and "ry" not in st["wnames"]:
            # tip spheres on a face that does not turn (alpha = 0): pair_distances' arithmetic on Python floats
            out["_face_rows"] = tuple((int(f), int(i) + 1, float(out["_gl"][j, 0]), float(out["_gl"][j, 1]),
                                       float(out["_hx"][j]), float(out["_rad"][j]))
                                      for j, (f, i, _) in enumerate(pair_link))
    out.setdefault("_face_rows", None)
    for v in list(out.values()) + out.get("_pidx", []):
        if isinstance(v, np.ndarray):
            v.setflags(write=False)
    scene.__dict__["_chain_parameters"] = (m, scene.index, key, out)
    return out


@dataclass
class Term:
    """A scalar function of ``x = (phi, y)``: value, gradient, diagonal + low-rank Hessian."""

    value: float
    grad: np.ndarray  # (n + nw,)
    diag: np.ndarray  # (n,)  phi-phi diagonal
    U: np.ndarray  # (n + nw, r)
    S: np.ndarray  # (r, r)


_SWAP = np.array([[0.0, 1.0], [1.0, 0.0]])


class ChainModel:
    """Analytic statics of a one- or two-finger scene (see the module docstring)."""

    def __init__(self, scene: Scene):
        m = scene.model
        self.scene, self.m = scene, m
        self.fingers = nf = scene.fingers
        self.nl = nl = scene.n
        self.n = nf * nl  #: all link angles, finger after finger
        st = self._struct = _structure(scene)  # (the index arrays: read once per compiled model)
        self.jq, self.jd = st["jq"], st["jd"]
        self._bodies = st["bodies"]
        self.mir = st["mir"]
        self.first, self.last, self._first_at, self._last_at = st["first"], st["last"], st["first_at"], st["last_at"]
        self.wnames = st["wnames"]
        self.nw = len(self.wnames)
        #: the workpiece turns (``ry``): else every ``dalpha`` is 0, a term's Hessian its diagonal (:meth:`dot_term`)
        self._turns = any(nm not in ("x", "z") for nm in st["wnames"])
        self._no_rank = (np.zeros((self.n + self.nw, 0)), np.zeros((0, 0)))  # (empty: nothing to write into)
        self.wq, self.wd = st["wq"], st["wd"]
        #: the contact pairs (geom1, geom2) and, for each, (finger, link index of geom1, is the tip sphere)
        self.pairs, self.pair_link = st["pairs"], st["pair_link"]
        # the model's parameters in the chain's units (stiffness, gravity, radii, ...): read again on a change
        self.__dict__.update(_parameters(scene, st))
        #: one-entry memos of :meth:`pose` and :meth:`_link` (keyed on their arguments' values; read-only results)
        self._pose_memo = self._link_memo = None

    @property
    def link_index(self) -> dict:
        """``{link body id: (finger, link)}`` (read-only: shared by every settle of the scene's model)."""
        return self._struct["link_index"]

    # -- kinematics -------------------------------------------------------------
    def split(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Link angles (finger after finger) and the workpiece dofs (slides over l, hinge in rad) from ``qpos``."""
        phi = np.asarray(q)[self.jq].reshape(self.fingers, self.nl).cumsum(axis=1).reshape(-1)
        return phi, np.asarray(q)[self.wq] / self.wscale

    def join(self, q, phi, y) -> np.ndarray:
        """``q`` with the link angles ``phi`` and the workpiece dofs ``y`` written in."""
        qq = np.array(q, dtype=float)
        ph = np.asarray(phi, dtype=float).reshape(self.fingers, self.nl)
        dq = ph.copy()  # np.diff(ph, prepend=0) without its concatenation: phi_0 - 0 is phi_0
        dq[:, 1:] -= ph[:, :-1]
        qq[self.jq] = dq.reshape(-1)
        if self.nw:  # (split's y, a 1-D array, as it is: np.atleast_1d would hand it back unchanged)
            qq[self.wq] = (y if type(y) is np.ndarray and y.ndim == 1 else np.atleast_1d(y)) * self.wscale
        return qq

    def nodes(self, phi) -> np.ndarray:
        """Nodes (x, z) over l of every finger in its own frame (finger 1 mirrored in x): (fingers, nl + 1, 2)."""
        ph = np.asarray(phi).reshape(self.fingers, self.nl)
        out = np.zeros((self.fingers, self.nl + 1, 2))  # (the same sums as cumsum of stacked segments)
        (self.ds * np.cos(ph)).cumsum(axis=1, out=out[:, 1:, 0])
        (self.ds * np.sin(ph)).cumsum(axis=1, out=out[:, 1:, 1])
        return out

    def pose(self, f, y):
        """Workpiece origin ``O`` and angle ``alpha`` in finger ``f``'s frame, and their derivatives in ``y``.

        Returns ``O (2,)``, ``alpha``, ``dO (nw, 2)``, ``dalpha (nw,)``.  A body point
        at local ``(a, c)`` sits at ``O + R(alpha) (m a, c)`` (``m`` the finger's mirror).
        """
        memo = self._pose_memo
        if memo is not None and memo[2] is y and memo[0][0] == f and memo[0][1] == y.tobytes():
            return memo[1]  # (the array asked for last, its value unchanged: no conversion needed to tell)
        y_in = y
        mf = self.mir[f]
        if not (type(y) is np.ndarray and y.ndim == 1 and y.dtype is _F64):  # (else it is that array itself)
            y = np.atleast_1d(np.asarray(y, float))
        key = (f, y.tobytes())
        if memo is not None and memo[0] == key:
            self._pose_memo = (key, memo[1], y_in if y_in is y else None)
            return memo[1]  # (one Newton iteration asks for the same pose several times)
        O = np.array([mf * self.w0[0], self.w0[1]])
        alpha = 0.0
        dO = np.zeros((self.nw, 2))
        da = np.zeros(self.nw)
        for j, nm in enumerate(self.wnames):
            if nm == "x":
                O[0] += mf * y[j]
                dO[j, 0] = mf
            elif nm == "z":
                O[1] += y[j]
                dO[j, 1] = 1.0
            else:  # hinge about -y: turns (x, z) counter-clockwise by y in the world, mirrored in the finger's frame
                alpha = mf * y[j]
                da[j] = mf
        for a in (O, dO, da):
            a.setflags(write=False)  # shared by the memo: callers build new arrays from them
        # (the caller's array when it is the float64 vector keyed on: the shortcut above compares its bytes)
        self._pose_memo = (key, (O, alpha, dO, da), y_in if y_in is y else None)
        return O, alpha, dO, da

    def local(self, f, v3) -> np.ndarray:
        """A workpiece-local 3-vector (x, y, z) as the finger frame's unturned (x, z) over 1."""
        return np.array([self.mir[f] * v3[0], v3[2]])

    # -- internal forces --------------------------------------------------------
    def internal(self, phi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Spring and gravity force on the link angles, and its tridiagonal Jacobian (diag, off; 0 between fingers)."""
        F, diag = self._force_diag(np.asarray(phi, dtype=float), self.m.qpos_spring[self.jq])  # (rest: read each time)
        return F, diag, self._k_next[:-1].copy()

    def _force_diag(self, phi, rest) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`internal`'s force and Jacobian diagonal at float64 ``phi``, hinge rest angles ``rest`` (rad)."""
        q = phi.copy()  # joint angles: phi_i - phi_(i-1) within a finger, phi_i at its first link
        q[1:] -= phi[:-1]
        q[self._first_at] = phi[self._first_at]  # (the mask's positions: the same elements, no mask scan)
        s = self.k * (q - rest)
        sn = np.empty_like(s)  # the next hinge's moment, 0 beyond a finger's last link
        sn[:-1] = s[1:]
        sn[self._last_at] = 0.0  # (every finger's last link, the array's last element among them)
        return sn - s - self.c * np.cos(phi), self._k_diag + self.c * np.sin(phi)

    def free_equilibrium(self, phi0, tol: float = 1e-12, max_iter: int = 50):
        """The fingers alone (no contact) at equilibrium, by Newton from ``phi0``; None if it fails.

        The tridiagonal Jacobian of :meth:`internal` is exact, so a start near the
        equilibrium (e.g. the grip's shape) converges in a few ``O(n)`` steps; a
        backtracking line search on ``|F|`` guards the rest.  Not checked for
        stability: callers use it near a known stable branch.
        """
        rest, off = self.m.qpos_spring[self.jq], self._k_next[:-1].copy()  # (internal's: fixed through this solve)
        phi = np.array(phi0, dtype=float)
        F, diag = self._force_diag(phi, rest)
        res = float(_MAX(np.abs(self.to_q(F))))  # (ndarray.max's reduction, without its wrapper)
        for _ in range(max_iter):
            if res < tol:
                return phi
            try:
                d = solve_tridiagonal(diag, off, -F)
            except (np.linalg.LinAlgError, ValueError):
                return None
            step = 1.0
            for _ls in range(30):
                trial = phi + step * d
                Fn, dn = self._force_diag(trial, rest)
                rn = float(_MAX(np.abs(self.to_q(Fn))))
                if rn < res or rn < tol:
                    break
                step *= 0.5
            else:
                return None
            phi, F, diag, res = trial, Fn, dn, rn  # (the accepted trial: phi + step d)
        return phi if res < tol else None

    def workpiece_force(self) -> np.ndarray:
        """Weight plus applied force (moment for ``ry``) on each workpiece dof (over rho g l, rho g l^2)."""
        out = np.zeros(self.nw)
        qa = self.scene.data.qfrc_applied
        for j, nm in enumerate(self.wnames):
            out[j] = float(qa[self.wd[j]]) / (self.W * (self.L if nm == "ry" else 1.0))
            if nm == "z":
                out[j] -= self.weight
        return out

    def to_q(self, F) -> np.ndarray:
        """Link-angle force -> hinge force (suffix sums within each finger)."""
        if self.fingers == 1 and type(F) is np.ndarray and F.ndim == 1:
            return F[::-1].cumsum()[::-1]  # (the same sequential sums along one axis)
        return np.asarray(F).reshape(self.fingers, self.nl)[:, ::-1].cumsum(axis=1)[:, ::-1].reshape(-1)

    # -- terms ------------------------------------------------------------------
    def _link(self, phi, f, i):
        """Global index of link ``i`` of finger ``f`` and its predecessors' normals and tangents."""
        g0 = f * self.nl
        ph = np.asarray(phi, dtype=float)[g0:g0 + i]
        key = (f, i, ph.tobytes())
        if self._link_memo is not None and self._link_memo[0] == key:
            return self._link_memo[1]  # (a contact and its stick sit on the same link)
        cs, sn = np.cos(ph), np.sin(ph)
        nk, tk = np.empty((ph.size, 2)), np.empty((ph.size, 2))
        nk[:, 0], nk[:, 1] = -sn, cs
        tk[:, 0], tk[:, 1] = cs, sn
        nk.setflags(write=False)
        tk.setflags(write=False)
        self._link_memo = (key, (g0, nk, tk))
        return g0, nk, tk

    def dot_term(self, phi, nodes, f, i, p, c_loc, y, v_loc, kind: str) -> Term:
        """``f = v . (p - c)``: ``p`` on link ``i`` of finger ``f``, ``c = O + R(alpha) c_loc`` on the workpiece.

        ``kind``: ``"link"`` (``v = R(phi_i) v_loc`` turns with the link) or
        ``"work"`` (``v = R(alpha) v_loc`` turns with the workpiece).  The plane's 2-vectors are worked on as
        Python floats (each a handful of products: numpy's per-call cost is most of a 2-vector operation's);
        only the ``O(n)`` and workpiece rows are arrays.
        """
        n, nw, ds = self.n, self.nw, self.ds
        O, alpha, dO, da = self.pose(f, y)
        ca, sa = math.cos(alpha), math.sin(alpha)
        cl0, cl1 = float(c_loc[0]), float(c_loc[1])
        rc0, rc1 = ca * cl0 - sa * cl1, sa * cl0 + ca * cl1  # R(alpha) c_loc
        o0, o1 = float(O[0]), float(O[1])
        pc0, pc1 = float(p[0]) - (o0 + rc0), float(p[1]) - (o1 + rc1)  # p - c
        g0, nk, tk = self._link(phi, f, i)
        gi = g0 + i
        nd = nodes[f, i]
        rel0, rel1 = float(p[0]) - float(nd[0]), float(p[1]) - float(nd[1])  # p - node_i
        vl0, vl1 = float(v_loc[0]), float(v_loc[1])
        if kind == "link":
            cv, sv = math.cos(float(phi[gi])), math.sin(float(phi[gi]))
        else:
            cv, sv = ca, sa
        v0, v1 = cv * vl0 - sv * vl1, sv * vl0 + cv * vl1
        v = np.array([v0, v1])
        v_rel = v0 * rel0 + v1 * rel1
        v_pc = v0 * pc0 + v1 * pc1
        # d c / d y = dO + dalpha perp(R c_loc): its product with v
        dc_v = dO @ v + da * (v1 * rc0 - v0 * rc1)
        grad = np.zeros(n + nw)
        grad[g0:gi] = ds * (nk @ v)
        grad[gi] = v1 * rel0 - v0 * rel1  # v . perp(rel)
        grad[n:] = -dc_v
        diag = np.zeros(n)
        diag[g0:gi] = -ds * (tk @ v)
        diag[gi] = -v_rel
        pv_pc = v0 * pc1 - v1 * pc0  # perp(v) . (p - c)
        pv = np.array([-v1, v0]) if kind == "link" or self._turns else None  # perp(v) (the low-rank parts')
        if kind == "link":
            grad[gi] += pv_pc
            diag[gi] += 2.0 * v_rel - v_pc
            U = np.zeros((n + nw, 3))
            U[gi, 0] = 1.0
            U[g0:gi, 1] = ds * (nk @ pv)
            U[n:, 1] = -(dO @ pv + da * (v0 * rc0 + v1 * rc1))  # -(dc . perp(v))
            U[n:, 2] = da
            S = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, v0 * rc0 + v1 * rc1]])
            return Term(v_pc, grad, diag, U, S)
        if not self._turns:  # (da is all zero: pose's dalpha has an entry only for an ry dof)
            return Term(v_pc, grad, diag, *self._no_rank)
        grad[n:] += da * pv_pc
        U = np.zeros((n + nw, 2))
        U[g0:gi, 0] = ds * (nk @ pv)
        U[gi, 0] = -v1 * -rel1 + v0 * rel0  # perp(v) . perp(rel) = v . rel
        U[n:, 0] = -(dO @ pv)
        U[n:, 1] = da
        po0, po1 = float(p[0]) - o0, float(p[1]) - o1
        S = np.array([[0.0, 1.0], [1.0, -(v0 * po0 + v1 * po1)]])
        return Term(v_pc, grad, diag, U, S)

    def norm_term(self, phi, nodes, f, i, p, c_loc, y) -> Term:
        """``f = |c - p|``: ``p`` on link ``i`` of finger ``f``, ``c = O + R(alpha) c_loc`` on the workpiece."""
        n, nw, ds = self.n, self.nw, self.ds
        O, alpha, dO, da = self.pose(f, y)
        Rc = _rot(alpha) @ c_loc
        e = O + Rc - p
        rho = float(np.hypot(*e))
        eh = e / rho
        ep = _perp(eh)
        g0, nk, tk = self._link(phi, f, i)
        gi = g0 + i
        rel = p - nodes[f, i]
        de = np.zeros((n + nw, 2))  # d e / d x
        de[g0:gi] = -ds * nk
        de[gi] = -_perp(rel)
        de[n:] = dO + da[:, None] * _perp(Rc)[None, :]
        diag = np.zeros(n)
        diag[g0:gi] = ds * (tk @ eh)
        diag[gi] = float(eh @ rel)
        U = np.zeros((n + nw, 2))
        U[:, 0] = de @ ep
        U[n:, 1] = da
        return Term(rho, de @ eh, diag, U, np.array([[1.0 / rho, 0.0], [0.0, -float(eh @ Rc)]]))

    # -- contacts ---------------------------------------------------------------
    def _geom_local(self, f, g) -> np.ndarray:
        return self.local(f, self.m.geom_pos[g] / self.L)

    def pair_term(self, p, phi, nodes, y) -> Term:
        """Signed distance of contact pair ``p`` (MuJoCo's geometry) as a :class:`Term`."""
        f, i, sphere = self.pair_link[p]
        g1, g2 = self.pairs[p]
        R = self.radius[p]
        if sphere:  # tip sphere on the box's outer face (turning with the workpiece): the face's point, _parameters'
            t = self.dot_term(phi, nodes, f, i, nodes[f, i + 1], self._face_at[p], y, (1.0, 0.0), "work")
            t.value -= R
            return t
        c_loc = self._geom_local(f, g2)
        O, alpha, _, _ = self.pose(f, y)  # corner capsule axis (along y)
        c = O + _rot(alpha) @ c_loc
        a, b = nodes[f, i], nodes[f, i + 1]
        gi = f * self.nl + i
        tvec = np.array([math.cos(phi[gi]), math.sin(phi[gi])])
        u = float((c - a) @ tvec)
        if u <= 0.0 or u >= self.ds:
            t = self.norm_term(phi, nodes, f, i, a if u <= 0.0 else b, c_loc, y)
        else:
            sigma = 1.0 if float((c - a) @ _perp(tvec)) >= 0.0 else -1.0
            t = self.dot_term(phi, nodes, f, i, a, c_loc, y, np.array([0.0, -sigma]), "link")
        t.value -= R
        return t

    def pair_distances(self, phi, nodes, y) -> np.ndarray:
        """All pairs' signed distances (vectorised; same geometry as :meth:`pair_term`).

        The row dot products are written out as ``einsum("ij,ij->i")`` sums them, ``(0 + x0 y0) + x1 y1``
        (bit for bit, signed zeros too), and only the branch the pairs use is evaluated (tip spheres on a
        face, or capsules): the same values as both branches and ``np.where``, at a third of the cost.
        """
        if not self.pairs:
            return np.zeros(0)
        if self._face_rows is not None:
            return self._face_distances(nodes, y)
        O = np.empty((len(self.pairs), 2))
        A = np.empty(len(self.pairs))
        for f, mine in enumerate(self._pidx):
            if mine.size:
                Of, af, _, _ = self.pose(f, y)
                O[mine], A[mine] = Of, af
        ca, sa = np.cos(A), np.sin(A)
        gl = self._gl
        rgl = np.empty_like(gl)  # R(alpha) c_loc
        rgl[:, 0] = ca * gl[:, 0] - sa * gl[:, 1]
        rgl[:, 1] = sa * gl[:, 0] + ca * gl[:, 1]
        b = nodes[self._pf, self._pl + 1]
        face = caps = None
        if self._branch != "caps":  # the face normal (ca, sa), turned with the workpiece
            bo = b - O
            face = (((0.0 + ca * bo[:, 0]) + sa * bo[:, 1])
                    - (((0.0 + ca * rgl[:, 0]) + sa * rgl[:, 1]) + self._hx) - self._rad)
        if self._branch != "face":
            c = O + rgl
            a = nodes[self._pf, self._pl]
            seg = b - a
            ac = c - a
            u = np.clip(((0.0 + ac[:, 0] * seg[:, 0]) + ac[:, 1] * seg[:, 1])
                        / ((0.0 + seg[:, 0] * seg[:, 0]) + seg[:, 1] * seg[:, 1]), 0.0, 1.0)
            caps = np.hypot(*(c - a - u[:, None] * seg).T) - self._rad
        if face is None:
            return caps
        if caps is None:
            return face
        return np.where(self._sph, face, caps)

    def _face_distances(self, nodes, y) -> np.ndarray:
        """:meth:`pair_distances` of tip spheres on faces that do not turn, on Python floats, bit for bit.

        The workpiece has no ``ry`` dof, so every ``alpha`` is ``0.0`` and its cosine and sine are ``1.0`` and
        ``0.0`` exactly; each element of the vectorised formula is then the same sequence of IEEE
        operations on one pair's numbers (products, sums and differences in the same order, the written-out
        row sums included), done here on floats: no array temporaries for one or two pairs.
        """
        ca, sa = 1.0, 0.0  # cos and sin of alpha = 0.0
        out = []
        for f, k, gl0, gl1, hx, rad in self._face_rows:
            o0, o1 = self.pose(f, y)[0].tolist()
            rgl0 = ca * gl0 - sa * gl1
            rgl1 = sa * gl0 + ca * gl1
            nd0, nd1 = nodes[f, k].tolist()
            bo0, bo1 = nd0 - o0, nd1 - o1
            out.append(((0.0 + ca * bo0) + sa * bo1) - (((0.0 + ca * rgl0) + sa * rgl1) + hx) - rad)
        return np.array(out)

    def stick_term(self, s, phi, nodes, y) -> Term:
        """Sticking constraint ``t . (p_f - p_w) + offset`` (over l) of a :class:`Stick`."""
        f, i = self.link_index[s.body_f]
        L = self.L
        gi = f * self.nl + i
        ct, st = math.cos(float(phi[gi])), math.sin(float(phi[gi]))  # the link's tangent
        lf0, lf2 = float(s.local_f[0]), float(s.local_f[2])
        nd = nodes[f, i]
        pf = (float(nd[0]) + (lf0 * ct - lf2 * st) / L, float(nd[1]) + (lf0 * st + lf2 * ct) / L)
        mf = float(self.mir[f])
        pw_loc = (mf * (float(s.local_w[0]) / L), float(s.local_w[2]) / L)
        if s.t_body == s.body_f:
            t = self.dot_term(phi, nodes, f, i, pf, pw_loc, y, (float(s.t_local[0]), float(s.t_local[2])), "link")
        else:
            t = self.dot_term(phi, nodes, f, i, pf, pw_loc, y, (mf * float(s.t_local[0]), float(s.t_local[2])),
                              "work")
        t.value += s.offset / L
        return t
