"""Natural frequencies and mode shapes of a settled finger: MuJoCo's chain beside the linearised rod.

:func:`modes` builds the scene of a grip, settles it (:func:`simgrip.settle.settle`),
linearises MuJoCo's own forces about the equilibrium with the held workpiece as
a sticking constraint (:mod:`.linear`) and solves the eigenproblem; beside it
(``reference_frequencies``) the small vibrations of the inextensible elastica
about the BVP's equilibrium (:mod:`.rod`), solved independently of the chain.
Frequencies are dimensionless, ``omega sqrt(l/g)`` (so a cantilever's
Euler-Bernoulli frequencies are ``(beta l)^2 sqrt(D)``: ``omega^2 = EI beta^4 /
rho`` and ``D = EI / (rho g l^3)``).

The chain's mass (:mod:`simgrip.sim.fingers`): each link is a rigid body of mass
``rho ds`` at its midpoint with inertia ``rho ds (ds^2/12 + r_link^2/4)`` about
its centre; the tip sphere and the capsules carry no mass, the hinges no
armature.  A link's ``ds^2/12`` is the inertia of its own mass spread along it:
the chain's kinetic energy is exactly that of the rod whose centreline is the
piecewise-linear interpolant of the nodes, an ``O(ds^2)`` approximation of the
continuous (Euler-Bernoulli) kinetic energy; equivalently an apparent rotary
inertia ``rho ds^2/12`` per length, which shifts mode ``k`` by ``O((beta_k ds)^2)``.
The capsule's ``rho r_link^2/4`` (``r_link = 2e-3 l``) is a true rotary inertia that
does not vanish with ``ds``: by Rayleigh's quotient it shifts mode ``k`` by ``-(r_link^2 / 8) int w_k'^2 / int w_k^2``,
``-(beta_k r_link)^2 c_k / 8`` with ``c_k = 1.32, 1.47, 1.25`` for a cantilever's first three modes: -2.3e-6,
-1.6e-5, -3.9e-5.
With the springs' and gravity's second-order discretisation (:mod:`simgrip.chain`),
the chain's frequencies converge to the rod's at second order in ``ds``.

Grip III: the workpiece's corner sticks to the rod's centreline point at the simulation's own ``gamma``; the
reference is the BVP at that ``gamma`` and ``X(gamma)`` (as :mod:`simgrip.compare`), and the contact falling
inside a link makes the chain's error first order there, like the statics'.

Which motions the modes cover: one finger (the symmetric reduction) with the
workpiece sliding vertically, so its symmetric modes; the workpiece neither
sways nor rocks in them.  ``fingers=2`` builds both mirrored fingers with the
workpiece free in the plane (``x, z, ry``): its modes include the antisymmetric
ones, which the rod reference (symmetric) does not cover.  The K-finger gripper
(workpiece free in 3-D) is :func:`simgrip.modes.gripper.gripper_modes`.

For other code (e.g. the damping of a built scene): :func:`linearise` gives
``M``, ``K`` and the constraints' null space of any built scene at a given
``qpos``, :func:`eigen` the eigenpairs, :func:`chain_modes` both for a settled
state (model units: ``omega^2`` in 1/s^2).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from simgrip.modes.linear import Linearisation, Stick, eigen, linearise, sticks_of

__all__ = ["ModeResult", "ModesError", "Stick", "Linearisation", "chain_modes", "eigen", "linearise", "mac", "modes",
           "node_displacements", "reference_modes", "sticks_of"]


class ModesError(RuntimeError):
    """No modes: the grip's equilibrium does not exist (the workpiece fell)."""


@dataclass
class ModeResult:
    """Natural frequencies and mode shapes of a settled scene (dimensionless unless said).

    Attributes
    ----------
    grip, links, fingers, count
    frequencies : ndarray (count,)
        The chain's ``omega sqrt(l/g)``, lowest first (NaN for a negative ``omega^2``: unstable).
    omega2 : ndarray (count,)
        The chain's ``omega^2 l/g``.
    shapes : ndarray (count, fingers, n + 1, 2)
        Node displacements ``(dx, dz)`` over ``l`` of each mode (finger frame), scaled to
        ``sum |u|^2 / n = 1`` (a discrete ``int |u|^2 ds = 1``), largest component positive.
    joint_shapes : ndarray (count, nv)
        The same modes in MuJoCo's generalised coordinates (mass-normalised).
    reference_frequencies : ndarray (count,) or None
        The linearised elastica's (:mod:`.rod`; Grip III at the simulation's own ``gamma`` and ``X(gamma)``), or
        None where it does not apply (two fingers, a Grip III contact at the tip).
    relative_difference : ndarray (count,) or None
        ``frequencies / reference_frequencies - 1``.
    mac : ndarray (count,) or None
        Modal assurance criterion of each chain mode against the reference mode of the same rank.
    dofs : int
        Degrees of freedom after the constraints (the most modes there are).
    settled : dict
        The settled state's key numbers: ``tip``, ``N1``, ``N2``, ``residual``, ``held``, ``workpiece_mass``
        (inertial, per finger), ``misfit`` (the linearisation's equilibrium misfit), ``asymmetry``.
    reference_error : float or None
        The rod solver's own error estimate (relative, :attr:`simgrip.modes.rod.RodModes.error_estimate`).
    wall_time_s : dict
        ``settle``, ``linearise`` (stiffness and mass matrix), ``eigen``, ``reference`` seconds.
    """

    grip: str
    links: int
    fingers: int
    count: int
    frequencies: np.ndarray
    omega2: np.ndarray
    shapes: np.ndarray
    joint_shapes: np.ndarray
    reference_frequencies: np.ndarray | None
    relative_difference: np.ndarray | None
    mac: np.ndarray | None
    dofs: int
    settled: dict
    reference_error: float | None = None
    wall_time_s: dict = field(default_factory=dict)

    def record(self) -> dict:
        """A flat JSON-able record (lists, no arrays of shapes) for the command line."""
        def lst(a):
            return None if a is None else [None if not math.isfinite(float(x)) else float(x) for x in a]

        return {
            "grip": self.grip, "links": self.links, "fingers": self.fingers, "count": self.count,
            "dofs": self.dofs, "frequencies": lst(self.frequencies),
            "reference_frequencies": lst(self.reference_frequencies),
            "relative_difference": lst(self.relative_difference), "mac": lst(self.mac),
            "reference_error": self.reference_error, "settled": self.settled,
            "wall_time_s": self.wall_time_s,
        }


def node_displacements(scene, q0, dq) -> np.ndarray:
    """Node displacements ``(fingers, n + 1, 2)`` over ``l`` (finger frames) of a small joint motion ``dq``
    (in MuJoCo's dofs, model units) about ``q0``: ``du_j = sum_{i<j} ds (-sin phi_i, cos phi_i) dphi_i``."""
    n = scene.n
    out = np.zeros((scene.fingers, n + 1, 2))
    for f in range(scene.fingers):
        phi = np.cumsum(np.asarray(q0)[scene.joint_qpos[f]])
        dphi = np.cumsum(np.asarray(dq)[scene.joint_dof[f]])
        steps = (1.0 / n) * np.stack([-np.sin(phi) * dphi, np.cos(phi) * dphi], axis=-1)
        out[f, 1:] = np.cumsum(steps, axis=0)
    return out


def mac(a, b) -> float:
    """Modal assurance criterion ``|a.b|^2 / (|a|^2 |b|^2)`` of two shapes (any equal shape), in [0, 1]."""
    a = np.ravel(a)
    b = np.ravel(b)
    den = float(a @ a) * float(b @ b)
    return float((a @ b) ** 2 / den) if den > 0 else 0.0


def _scaled(u) -> np.ndarray:
    """Scale node displacements to a discrete ``int |u|^2 = 1`` (mean over links), largest component positive."""
    n = u.shape[-2] - 1
    norm = math.sqrt(float(np.sum(u[..., 1:, :] ** 2)) / n)
    u = u / norm if norm > 0 else u
    big = np.unravel_index(np.argmax(np.abs(u)), u.shape)
    return -u if u[big] < 0 else u


def chain_modes(scene, state, count: int | None = None):
    """``(linearisation, omega2, joint_shapes, node_shapes, times)`` of a settled scene, model units.

    ``state`` is the :class:`~simgrip.settle.SettledState` of ``scene`` (its ``qpos`` is the equilibrium;
    a held workpiece sticks, :func:`sticks_of`).  ``omega2`` [1/s^2 of the model].
    """
    import mujoco

    d = mujoco.MjData(scene.model)
    d.qpos[:] = state.qpos
    mujoco.mj_kinematics(scene.model, d)
    t0 = time.perf_counter()
    lin = linearise(scene, d, sticks=sticks_of(scene, state, d))
    t1 = time.perf_counter()
    w, v = eigen(lin.M, lin.K, lin.basis, count)
    t2 = time.perf_counter()
    shapes = np.stack([_scaled(node_displacements(scene, state.qpos, v[:, k])) for k in range(v.shape[1])])
    return lin, w, v, shapes, {"linearise": t1 - t0, "eigen": t2 - t1}


def reference_modes(grip, params, profile, count: int, *, tip_mass: float | None = None, fixed: bool = False,
                    nodes: int | None = None):
    """The linearised elastica's modes (:class:`simgrip.modes.rod.RodModes`) about the BVP's equilibrium.

    ``tip_mass``: the workpiece's inertial mass per finger over ``rho l`` (default ``params.M``).
    """
    from simgrip.modes.rod import DEFAULT_NODES, problem_of, rod_modes
    from simgrip.reference import elastica

    sol = elastica.solve(grip, params, profile)
    return rod_modes(problem_of(sol, tip_mass=tip_mass, fixed=fixed), count,
                     DEFAULT_NODES if nodes is None else nodes)


def _check_count(count, dofs: int) -> int:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 1 <= count <= dofs:
        raise ValueError(f"count must be an integer in [1, {dofs}] (the degrees of freedom), got {count!r}")
    return int(count)


def modes(grip, params, profile, links, *, count: int = 3, fingers: int = 1, method: str | None = None,
          contact: str | None = None, reference: bool = True, progress=None, **settle_kw) -> ModeResult:
    """Natural frequencies and mode shapes of the settled finger(s) of ``grip``, beside the rod's.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams or PhysicalParams
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)``.
    links : int
        Links per finger.
    count : int
        How many of the lowest modes, ``1 <= count <=`` the degrees of freedom left by the constraints
        (``links`` for the free rod, ``links - 1`` for a held workpiece in the symmetric reduction).
    fingers : {1, 2}
        The symmetric reduction (1) or both mirrored fingers (2; no reference).
    method, contact, settle_kw
        Passed to :func:`simgrip.settle.settle` (default Newton, point contact).
    progress : callable, optional
        Told the build's and the settle's phases (:mod:`simgrip.progress`; None: silent).
    reference : bool
        Also solve the linearised elastica (free rod, Grips I/II with one finger).

    Returns
    -------
    ModeResult
        Frequencies ``omega sqrt(l/g)``.

    Raises
    ------
    ValueError
        Bad arguments (named).
    SettleError, ElasticaError, ModesError
        The settle or the BVP failed, the workpiece fell; RuntimeError when the rod's eigenproblem is not
        resolved.
    """
    from simgrip.chain import check_link_count
    from simgrip.params import check_grip
    from simgrip.profiles import as_profile
    from simgrip.settle import settle
    from simgrip.sim.scene import build_scene, check_params

    grip = check_grip(grip)
    dimless, phys = check_params(params)
    prof = as_profile(profile)
    links = check_link_count(links)  # [2, MAX_LINKS], as the CLI's --links
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError(f"count must be a positive integer, got {count!r}")
    if not isinstance(reference, (bool, np.bool_)):  # "no" is truthy: reference="no" solved the reference
        raise ValueError(f"reference must be True or False, got {reference!r}")
    if contact not in (None, "point", "surface"):
        # the linearisation sticks the tip (Grips I/II) or the corner (III) and nothing else: a full-contact
        # state's contact set (links on faces, self-contact) is not a constraint it knows
        raise ValueError(f"contact must be 'point' or 'surface' for the modes (the sticking tip or corner is their "
                         f"only constraint; contact='full' is not linearised), got {contact!r}")
    from simgrip.progress import phase

    with phase(progress, f"building the model ({links} links per finger)"):
        scene = build_scene(grip, params, prof, links, fingers=fingers)
    t0 = time.perf_counter()
    kw = dict(settle_kw)
    if method is not None:
        kw["method"] = method
    if contact is not None:
        kw["contact"] = contact
    with phase(progress, "settling"):
        state = settle(scene, **kw)
    t_settle = time.perf_counter() - t0
    import mujoco

    d = mujoco.MjData(scene.model)
    d.qpos[:] = state.qpos
    mujoco.mj_kinematics(scene.model, d)
    if scene.has_workpiece and not state.held:
        raise ModesError(f"grip {grip}: the settled finger does not hold the workpiece (it fell): there is no "
                         f"equilibrium of the grip to vibrate about")
    sticks = sticks_of(scene, state, d)
    dofs = scene.model.nv - 2 * len(sticks)
    count = _check_count(count, dofs)
    lin, w, v, shapes, times = chain_modes(scene, state, count)
    tscale = phys.length / phys.g  # omega^2 [1/s^2] times l/g: dimensionless
    w_bar = w * tscale
    freq = np.sqrt(np.where(w_bar >= 0, w_bar, np.nan))
    ref = rel = macs = None
    ref_err = None
    times["settle"] = t_settle
    wp_mass = scene.workpiece_inertial_mass / fingers / (phys.rho * phys.length) if scene.has_workpiece else 0.0
    c = state.contact
    if reference and fingers == 1 and (grip == "free" or (c is not None and (grip != "III" or c.gamma < 1.0))):
        t1 = time.perf_counter()
        if grip == "III":  # the BVP at the simulation's own gamma and X(gamma) (simgrip.compare)
            from simgrip.compare import chain_reference
            from simgrip.modes.rod import DEFAULT_NODES, problem_of, rod_modes

            sol = chain_reference("III", dimless.replace(b=2.0 * float(c.point[0])), prof, state.link_angles[0],
                                  float(c.N1), state.nodes[0], gamma=float(c.gamma))
            rm = rod_modes(problem_of(sol, tip_mass=wp_mass), count, DEFAULT_NODES)
        else:
            rm = reference_modes(grip, dimless, prof, count, tip_mass=wp_mass)
        times["reference"] = time.perf_counter() - t1
        ref = rm.omega
        ref_err = rm.error_estimate
        rel = freq / ref - 1.0
        s_nodes = np.arange(scene.n + 1) / scene.n
        macs = np.array([mac(shapes[k, 0, 1:], rm.displacement(k, s_nodes)[1:]) for k in range(count)])
    settled = {
        "tip": [float(x) for x in state.tip[0]], "held": bool(state.held), "residual": float(state.residual),
        "N1": float(c.N1) if c else 0.0, "N2": float(c.N2) if c else 0.0, "workpiece_mass": float(wp_mass),
        "misfit": lin.misfit, "asymmetry": lin.asymmetry, "method": state.method,
    }
    return ModeResult(grip=grip, links=scene.n, fingers=fingers, count=count, frequencies=freq, omega2=w_bar,
                      shapes=shapes, joint_shapes=v, reference_frequencies=ref, relative_difference=rel,
                      mac=macs, dofs=dofs, settled=settled, reference_error=ref_err, wall_time_s=times)


class _CallableModule(__import__("types").ModuleType):
    """``simgrip.modes(...)`` is :func:`modes`: the package's module object calls it (issue 20 names the
    command ``simgrip.modes(...)``; the package and the function share the name)."""

    def __call__(self, *args, **kwargs) -> ModeResult:
        return modes(*args, **kwargs)


__import__("sys").modules[__name__].__class__ = _CallableModule
