"""Pictures of K-finger grippers: a rendered settled grasp, and the normal force per finger against ``kappa_bar0``.

* :func:`render_gripper` draws a :class:`~simgrip.gripper.scene.GripperScene`
  (its current state, or a :class:`~simgrip.gripper.settle.GripperState`'s)
  offscreen with :class:`mujoco.Renderer` on the backend of
  :func:`simgrip.sim.gl.make_renderer` (``MUJOCO_GL``, else EGL, then OSMesa on
  a headless machine).  It draws a copy of the model, never the simulated one:
  the simulation's contact geoms are thin (radius ``2e-3 l``), so the copy
  draws the links and tips with radius ``draw_radius`` and shrinks the
  workpiece by the same amount, so that each tip still touches it where the
  simulated tip does; box and cylinder (``2 l`` tall in the simulation, so
  that a tip meets a vertical face) are drawn ``draw_height`` tall around
  their centre.  A palm disc, a floor, a light and a free camera that frames
  every finger and the workpiece are added.  The settled joint angles and
  workpiece pose are the simulation's, unchanged.
* :func:`grasp_picture` builds, settles (:func:`simgrip.gripper.settle.settle_gripper`)
  and draws one of :data:`GRASPS` (Grip I at the paper's standard case);
  :func:`write_png` writes an image through :func:`simgrip.io.atomic_write`.
* :func:`gripper_force_data` and :func:`plot_gripper_forces`: a cylinder held
  by ``K`` = 3 and 4 fingers puts every finger in the paper's planar Grip I
  problem, so the normal force ``N`` (along ``E1``, over ``rho g l``) that each
  finger of the settled gripper (``n`` = 32 links) carries lies on the BVP's
  curve ``N(kappa_bar0)``.  The curve is the point-contact BVP (the paper's);
  each simulated point is also compared with the BVP solved with the tip
  couple the settle measured (the contact force acts on the tip sphere's
  surface, radius ``2e-3 l``: a couple that moves ``N`` by about 0.4 % in
  Grip I), whose only remaining difference is the chain's second-order error,
  documented at ``n = 32`` as 0.5 % of ``N``.  Where ``mu_s N < M`` the
  cylinder is dropped and the point is drawn as such.

:func:`make_gripper_figure` makes one of :data:`GRIPPER_FIGURES` for
``simgrip figures`` (:mod:`simgrip.figures.make`).  matplotlib is imported
only by :func:`plot_gripper_forces`.
"""

from __future__ import annotations

import io
import math
import os
from pathlib import Path

import numpy as np

from simgrip.figures.catalog import GRIPPER_FIGURES
from simgrip.io import atomic_write
from simgrip.params import STANDARD, DimensionlessParams

__all__ = ["GRASPS", "GRIPPER_FIGURES", "render_gripper", "grasp_picture", "write_png", "gripper_force_data",
           "plot_gripper_forces", "make_gripper_figure"]

#: The rendered grasps: figure name -> (fingers, workpiece).
GRASPS = {"grasp3": (3, "cylinder"), "grasp4": (4, "box")}
#: Grip and curvature of the rendered grasps: Grip I's standard case (``harness.methods.STANDARD_CASES``).
GRASP_GRIP, GRASP_KAPPA = "I", -6.0
#: Links per finger of the figures' simulations.
LINKS = 32
#: ``kappa_bar0`` of the simulated points of the force plot (Grip I's feasible window is [-6, -4.74]).
SIM_KAPPAS = (-3.0, -4.0, -4.5, -5.0, -5.25, -5.5, -5.75, -6.0)
#: Fingers around the cylinder in the force plot.
FORCE_FINGERS = (3, 4)
#: The BVP curve of the force plot: ``kappa_bar0`` from 0 to -6 (the paper's Fig. 7) in 49 points.
CURVE_KAPPAS = np.linspace(0.0, -6.0, 49)
#: The chain's documented error in ``N`` against the BVP at ``n = 32`` (second order; ``tests/test_settle.py``).
N_REL_32 = 5e-3
#: Drawn radius of links and tips, and drawn height of a box or cylinder (over ``l``).
DRAW_RADIUS, DRAW_HEIGHT = 0.012, 0.3

_BVP_TOL = 1e-8
_MAX_PIXELS = 4096


# ---------------------------------------------------------------------------
# rendering


def _check_size(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 16 <= value <= _MAX_PIXELS:
        raise ValueError(f"{name} must be an integer number of pixels in [16, {_MAX_PIXELS}], got {value!r}")
    return int(value)


def _check_angle(name: str, value, lo: float, hi: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number (degrees), got {value!r}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}] degrees, got {value!r}")
    return v


def _drawn_spec(scene, width: int, height: int, r_draw: float, h_draw: float, floor_z: float):
    """A copy of the scene's spec dressed for drawing (see the module docstring); lengths over ``l``."""
    import mujoco

    from simgrip.models import model_path

    L = scene.length
    spec = scene.spec.copy()
    grow = max(r_draw - scene.r_tip, 0.0) * L
    for g in spec.geoms:
        name = g.name or ""
        if name.startswith("f") and ("_geom" in name or name.endswith("_tip")):
            g.size = [r_draw * L, g.size[1], g.size[2]]
        elif name == "workpiece_geom":
            s = np.array(g.size, dtype=float)
            if scene.workpiece == "box":
                s[0] -= grow
                s[1] -= grow if scene.fingers == 4 else 0.0
                s[2] = 0.5 * h_draw * L
            elif scene.workpiece == "cylinder":
                s[0] -= grow
                s[1] = 0.5 * h_draw * L
            else:
                s[0] -= grow
            g.size = s.tolist()
    up = -1.0 if scene.grip == "II" else 1.0
    spec.worldbody.add_geom(name="draw_palm", type=mujoco.mjtGeom.mjGEOM_CYLINDER, contype=0, conaffinity=0,
                            size=[0.1 * L, 0.01 * L, 0.0], pos=[0.0, 0.0, up * (r_draw + 0.01) * L],
                            rgba=[0.6, 0.6, 0.6, 1.0])
    spec.attach(mujoco.MjSpec.from_file(str(model_path("dressing.xml"))), prefix="dress_",
                frame=spec.worldbody.add_frame())
    floor = spec.geom("dress_floor")
    floor.pos = [0.0, 0.0, floor_z * L]
    floor.size = [3.0 * L, 3.0 * L, 0.1 * L]
    light = spec.light("dress_key")
    light.pos = [0.0, -2.0 * L, 2.0 * L]
    spec.worldbody.add_light(name="draw_top", pos=[0.0, 0.0, 3.0 * L], dir=[0.0, 0.0, -1.0],
                             diffuse=[0.6, 0.6, 0.6], castshadow=False,
                             type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    spec.add_texture(name="draw_sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.92, 0.94, 0.97], rgb2=[0.55, 0.6, 0.68],
                     width=256, height=1536)
    spec.visual.headlight.ambient = [0.4, 0.4, 0.4]  # dressing.xml's (attach carries no <visual>)
    spec.visual.headlight.diffuse = [0.6, 0.6, 0.6]
    spec.visual.global_.offwidth = max(width, 640)
    spec.visual.global_.offheight = max(height, 480)
    return spec


def _points(scene) -> np.ndarray:
    """World positions over ``l`` of every finger's bodies and tip, and the workpiece's centre."""
    d = scene.data
    pts = [np.asarray(d.xpos[scene.index.link_body.ravel()]), np.asarray(d.geom_xpos[scene.tip_geom]),
           np.asarray(d.xpos[scene.workpiece_body])[None, :], np.zeros((1, 3))]
    return np.vstack(pts) / scene.length


def render_gripper(scene, state=None, *, width: int = 640, height: int = 480, azimuth=None,
                   elevation: float = -30.0, draw_radius: float = DRAW_RADIUS,
                   draw_height: float = DRAW_HEIGHT) -> np.ndarray:
    """Draw a K-finger gripper offscreen; returns an RGB image, ``(height, width, 3)`` ``uint8``.

    Parameters
    ----------
    scene : simgrip.gripper.scene.GripperScene
        Drawn in its current state (after :func:`~simgrip.gripper.settle.settle_gripper`: the settled one).
    state : simgrip.gripper.settle.GripperState, optional
        A settled state of ``scene`` to draw instead (its ``qpos`` is set on ``scene.data``).
    width, height : int
        Pixels, 16 to 4096.
    azimuth : float, optional
        Camera azimuth [deg] (MuJoCo's free camera: the direction it looks along,
        about the palm axis).  Default: the camera sits midway between fingers
        0 and 1 (odd ``K``: the finger opposite shows above the workpiece).
    elevation : float
        Camera elevation [deg], -89 to 89 (negative: looking down).
    draw_radius, draw_height : float
        Drawn radius of links and tips, and height of a box or cylinder, over ``l``
        (see the module docstring; the simulation is not changed).

    Raises
    ------
    ValueError
        A bad argument (named).
    simgrip.sim.gl.RenderingUnavailable
        No OpenGL backend renders offscreen on this machine.
    """
    import mujoco

    from simgrip.sim.gl import make_renderer
    from simgrip.gripper.scene import GripperScene

    if not isinstance(scene, GripperScene):
        raise ValueError(f"scene must be a simgrip.gripper.scene.GripperScene, got {type(scene).__name__}")
    width, height = _check_size("width", width), _check_size("height", height)
    elevation = _check_angle("elevation", elevation, -89.0, 89.0)
    if azimuth is not None:
        azimuth = _check_angle("azimuth", azimuth, -360.0, 360.0)
    for name, v in (("draw_radius", draw_radius), ("draw_height", draw_height)):
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and 0.0 < v <= 1.0):
            raise ValueError(f"{name} must lie in (0, 1] (over l), got {v!r}")
    if state is not None:
        qpos = np.asarray(getattr(state, "qpos", None), dtype=float)
        if qpos.shape != (scene.model.nq,):
            raise ValueError(f"state must be a settled state of this scene (qpos of size {scene.model.nq}), "
                             f"got {type(state).__name__}")
        scene.data.qpos[:] = qpos
        scene.data.qvel[:] = 0.0
    mujoco.mj_kinematics(scene.model, scene.data)
    pts = _points(scene)
    centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    reach = float(np.max(np.linalg.norm(pts - centre, axis=1))) + 0.5 * float(scene.params.b) + draw_radius
    low = min(float(pts[:, 2].min()), float(pts[-2, 2]) - 0.5 * draw_height) - 0.15
    spec = _drawn_spec(scene, width, height, float(draw_radius), float(draw_height), low)
    model = spec.compile()
    if model.nq != scene.model.nq:  # the dressing adds no joints
        raise RuntimeError("the drawn copy of the scene has another qpos layout")
    data = mujoco.MjData(model)
    data.qpos[:] = scene.data.qpos
    mujoco.mj_kinematics(model, data)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = centre * scene.length
    fovy = math.radians(float(model.vis.global_.fovy))
    cam.distance = 1.1 * reach * scene.length / math.sin(0.5 * fovy)
    if azimuth is None:  # MuJoCo's azimuth is the viewing direction; the camera sits opposite it
        side = float(scene.azimuths[0]) + math.pi / scene.fingers
        azimuth = (math.degrees(side) + 180.0) % 360.0
    cam.azimuth = azimuth
    cam.elevation = elevation
    renderer = make_renderer(model, height, width)
    try:
        renderer.update_scene(data, camera=cam)
        image = np.array(renderer.render())
    finally:
        renderer.close()
    return image


def write_png(image, path) -> Path:
    """Write an RGB image (``(h, w, 3)`` ``uint8``) as a PNG, whole or not at all (:func:`simgrip.io.atomic_write`)."""
    from PIL import Image

    arr = np.asarray(image)
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.dtype != np.uint8:
        raise ValueError(f"image must be an (h, w, 3) uint8 array, got shape {arr.shape} {arr.dtype}")
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="PNG")
    path = Path(os.fspath(path))
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def grasp_picture(fingers: int, workpiece: str, *, grip: str = GRASP_GRIP, kappa: float = GRASP_KAPPA,
                  links: int = LINKS, params: DimensionlessParams | None = None, **render):
    """Build, settle and draw a K-finger grasp: ``(image, state)``.

    ``fingers``, ``workpiece``, ``grip`` as :func:`simgrip.gripper.scene.build_gripper`;
    ``kappa`` the uniform ``kappa_bar0`` of every finger; ``params`` default the
    paper's standard case; ``render`` goes to :func:`render_gripper`.
    """
    from simgrip.profiles import Uniform
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper.scene import build_gripper

    scene = build_gripper(grip, STANDARD if params is None else params, Uniform(kappa), links, fingers=fingers,
                          workpiece=workpiece)
    state = settle_gripper(scene)
    return render_gripper(scene, **render), state


# ---------------------------------------------------------------------------
# normal force per finger against kappa_bar0


def gripper_force_data(*, fingers=FORCE_FINGERS, kappas=SIM_KAPPAS, links: int = LINKS,
                       params: DimensionlessParams | None = None, simulate: bool = True) -> dict:
    """The numbers of the force plot: Grip I, a cylinder held by ``K`` fingers, against ``kappa_bar0``.

    Returns a ``dict`` (forces on the rod over ``rho g l``):

    * ``kappa``, ``N``, ``feasible``: the BVP curve on :data:`CURVE_KAPPAS` (point
      contact, the paper's; NaN where a solve fails) and the paper's feasibility;
    * ``sim_kappa``: ``kappas``; per ``K`` in ``fingers``: ``held_K`` (bool),
      ``N_K`` (``len(kappas) x K``, every finger's ``N1``; NaN when dropped),
      ``couple_K`` (the tip couple the settle measured, over ``rho g l^2``, averaged
      over the fingers), ``ref_K`` (the BVP's ``N1`` with that couple) and
      ``rel_K`` (largest ``|N1 / ref - 1|`` over the fingers); NaN when dropped;
    * ``M``, ``mu_s``, ``b``, ``D``, ``links``, ``fingers``.

    ``simulate=False`` leaves the simulated entries out (the curve only).
    """
    from simgrip.chain import check_links
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper import reuse  # one compile per K, set in place for each kappa

    p = STANDARD if params is None else params
    fingers = tuple(int(k) for k in fingers)
    sim_kappas = np.array([float(k) for k in kappas], dtype=float)
    if not np.all(np.isfinite(sim_kappas)):
        raise ValueError(f"kappas must be finite, got {kappas!r}")
    links = check_links(links)
    sols = elastica.sweep("I", p, [Uniform(float(k)) for k in CURVE_KAPPAS], tol=_BVP_TOL, failures="skip")
    ok = [s is not None and bool(getattr(s, "success", True)) for s in sols]
    data = {"kappa": CURVE_KAPPAS.copy(), "N": np.array([s.N1 if o else np.nan for s, o in zip(sols, ok)]),
            "feasible": np.array([o and bool(s.feasible) for s, o in zip(sols, ok)]),
            "M": p.M, "mu_s": p.mu_s, "b": p.b, "D": p.D, "links": links, "fingers": fingers,
            "sim_kappa": sim_kappas}
    if not simulate:
        return data
    for K in fingers:
        held = np.zeros(len(sim_kappas), dtype=bool)
        forces = np.full((len(sim_kappas), K), np.nan)
        ref, rel, couple = (np.full(len(sim_kappas), np.nan) for _ in range(3))
        for i, k in enumerate(sim_kappas):
            st = settle_gripper(reuse.build_gripper("I", p, Uniform(float(k)), links, fingers=K, workpiece="cylinder"))
            if not (st.held and len(st.records) == K):
                continue
            held[i] = True
            forces[i] = [r.N1 for r in st.records]
            couple[i] = float(np.mean([r.moment for r in st.records]))
            ref[i] = elastica.solve("I", p, Uniform(float(k)), contact_moment=couple[i], tol=_BVP_TOL).N1
            rel[i] = float(np.max(np.abs(forces[i] / ref[i] - 1.0)))
        data.update({f"held_{K}": held, f"N_{K}": forces, f"ref_{K}": ref, f"rel_{K}": rel, f"couple_{K}": couple})
    return data


def plot_gripper_forces(data: dict):
    """Draw :func:`gripper_force_data`'s numbers; returns a :class:`matplotlib.figure.Figure` (Agg, no pyplot).

    (a) ``N`` per finger against ``-kappa_bar0``: the BVP curve, the friction
    limit ``N = M / mu_s`` (held above it; feasible region shaded) and every
    finger of the settled gripper; a dropped cylinder is a hollow marker on the
    axis.  (b) The simulated ``N`` against the BVP with the settle's own tip
    couple, with the ``n = 32`` bound :data:`N_REL_32`.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.6, 3.9), layout="constrained")
    FigureCanvasAgg(fig)
    a, b = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    x = -np.asarray(data["kappa"])
    feas = np.asarray(data["feasible"], dtype=bool)
    if feas.any():
        a.fill_between(x, 0, 1, where=feas, transform=a.get_xaxis_transform(), color="tab:green", alpha=0.18,
                       linewidth=0, label=r"feasible ($\mu_s N \geq M$)")
    a.plot(x, data["N"], color="k", lw=1.5, label="BVP (planar Grip I, point contact)")
    a.axhline(data["M"] / data["mu_s"], color="tab:red", lw=0.9, ls="--", label=r"$N = M/\mu_s$")
    styles = {3: ("o", "tab:blue"), 4: ("s", "tab:orange")}
    b.axhspan(-100 * N_REL_32, 100 * N_REL_32, color="0.85", label=rf"$n = {data['links']}$ bound ($\pm${100 * N_REL_32:g} %)")
    for j, K in enumerate(k for k in data["fingers"] if f"held_{k}" in data):
        marker, color = styles.get(K, ("^", f"C{j + 2}"))
        xs = -np.asarray(data["sim_kappa"])
        held = np.asarray(data[f"held_{K}"], dtype=bool)
        N = np.asarray(data[f"N_{K}"])
        size = 9.0 - 4.0 * min(j, 1)
        a.plot(np.repeat(xs[held], N.shape[1]), N[held].ravel(), marker, ms=size, mfc=color, mec="k", mew=0.6,
               ls="none", label=f"MuJoCo, {K} fingers, $n = {data['links']}$ (every finger)", zorder=5)
        if (~held).any():
            a.plot(xs[~held], np.zeros((~held).sum()), marker, ms=size, mfc="none", mec=color, mew=1.0, ls="none",
                   label=f"{K} fingers: dropped", zorder=5, clip_on=False)
        with np.errstate(invalid="ignore"):
            dev = 100 * (N[held] / np.asarray(data[f"ref_{K}"])[held, None] - 1.0)
        b.plot(np.repeat(xs[held], N.shape[1]), dev.ravel(), marker, ms=size, mfc=color, mec="k", mew=0.6,
               ls="none", label=f"{K} fingers")
    a.set_xlabel(r"$-\bar{\kappa}_0$")
    a.set_ylabel(r"normal force per finger $N/\rho g\ell$")
    a.set_ylim(bottom=0.0)
    a.set_title("(a) cylinder, Grip I: N per finger", fontsize=10)
    a.legend(fontsize=7, loc="upper left")
    b.axhline(0.0, color="0.5", lw=0.6)
    b.set_xlabel(r"$-\bar{\kappa}_0$")
    b.set_ylabel(r"$N_{sim}/N_{BVP} - 1$ [%]")
    held_x = [-np.asarray(data["sim_kappa"])[np.asarray(data[f"held_{k}"], dtype=bool)]
              for k in data["fingers"] if f"held_{k}" in data]
    held_x = np.concatenate(held_x) if held_x else np.zeros(0)
    if held_x.size:
        b.set_xlim(held_x.min() - 0.25, held_x.max() + 0.25)
    b.set_title("(b) against the BVP with the settle's tip couple", fontsize=10)
    b.legend(fontsize=7, loc="lower left")
    fig.suptitle(rf"K fingers around a cylinder: $D = {data['D']:g}$, $M = {data['M']:g}$ per finger, "
                 rf"$\mu_s = {data['mu_s']:g}$, $b/\ell = {data['b']:g}$")
    return fig


def make_gripper_figure(name: str, out_dir, *, simulate: bool = True) -> Path:
    """Make one of :data:`GRIPPER_FIGURES` as ``out_dir/<name>.png`` (used by :func:`simgrip.figures.make_figures`).

    The grasps are drawn 800 x 600 at :data:`LINKS` links; ``simulate=False``
    draws the force plot's BVP curve without the simulated points (the grasps
    are always simulated: the picture is the settled state).
    """
    path = Path(out_dir) / f"{name}.png"
    if name in GRASPS:
        K, shape = GRASPS[name]
        image, state = grasp_picture(K, shape, width=800, height=600)
        if not state.held:
            raise RuntimeError(f"{name}: the settled gripper dropped the {shape}")
        return write_png(image, path)
    if name == "grip_forces":
        from simgrip.figures.plot import save_figure

        return save_figure(plot_gripper_forces(gripper_force_data(simulate=simulate)), path)
    raise ValueError(f"unknown gripper figure {name!r}; known: {', '.join(GRIPPER_FIGURES)}")
