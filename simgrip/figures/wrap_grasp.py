"""A rendered wrap grasp (issue 17 s.5): three fingers curled around a sphere with ``contact="full"``.

The K-finger gripper of :mod:`simgrip.gripper.scene` (Grip I, palm down, fingers clamped on the palm axis)
with every link free to touch the workpiece, itself and the other fingers
(:func:`~simgrip.gripper.full.settle_gripper_full`).  Why these numbers (:data:`WRAP`): a free finger
of uniform ``kappa_bar0 < 0`` curls into a circle of radius ``1/|kappa_bar0|`` centred on the palm axis, as
is a sphere hanging below the palm; a sphere a little larger than that circle (``b/2 = 0.35`` against
``1/3.6 = 0.28``), its top ``0.02 l`` under the palm, lies inside the finger's rest shape, so the settled
finger is pushed out along its middle and closes under the sphere with its tip: it wraps the sphere (contact
at mid-length and at the tip, every finger).  Less curvature (``|kappa_bar0| <= 3``) leaves only the tips
touching, more (``>= 8``, 1/kappa under the finger's half length past the bottom) brings the three fingers
together under the sphere, which then drops; the standard case's weight ``M = 5`` per finger.

:func:`wrap_grasp_picture` builds, settles, checks and draws it (:func:`~simgrip.figures.gripper.render_gripper`,
headless: EGL, then OSMesa); the check (:func:`wrap_violations`): the sphere held, the settle converged, the
state valid by :func:`~simgrip.validity_shapes.check_gripper_valid`, no contact deeper than
:data:`MAX_PENETRATION` (the issue's ``1e-3 l``), and, recomputed here from the settled link angles, no
finger crossing itself and no link centreline closer to the sphere's centre than its radius plus the link's
minus that depth.  ``simgrip figures --which wrap_grasp`` writes ``wrap_grasp.png`` (800 x 600, n = 32).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["WRAP", "MAX_PENETRATION", "wrap_scene", "wrap_grasp_picture", "wrap_violations",
           "make_wrap_grasp_figure"]

#: The wrap grasp: three fingers, a sphere of diameter ``b`` (through the tip centres) whose top lies
#: ``box_gap`` under the palm, uniform ``kappa``, the standard case's D, M, mu_s (module docstring).
WRAP = dict(fingers=3, workpiece="sphere", kappa=-3.6, b=0.7, box_gap=0.02, D=1.0, M=5.0, mu_s=1.0)
#: Deepest contact a drawn state may have, over ``l`` (issue 17).
MAX_PENETRATION = 1e-3
#: Links per finger of the figure.
LINKS = 32


def wrap_scene(links: int):
    """The unsettled :class:`~simgrip.gripper.scene.GripperScene` of :data:`WRAP` at ``links`` links per finger."""
    from simgrip.params import DimensionlessParams
    from simgrip.profiles import Uniform
    from simgrip.gripper.scene import build_gripper

    w = WRAP
    params = DimensionlessParams(D=w["D"], M=w["M"], mu_s=w["mu_s"], b=w["b"])
    return build_gripper("I", params, Uniform(w["kappa"]), links, fingers=w["fingers"], workpiece=w["workpiece"],
                         contact="full", box_gap=w["box_gap"])


def wrap_violations(scene, state) -> list[str]:
    """What keeps a settled wrap grasp from being drawn as one (empty: it is a valid wrap).

    The sphere held and the settle converged; the state valid (its own check) and no deeper than
    :data:`MAX_PENETRATION`; recomputed from the link angles: no finger crossing itself (in its plane), every
    link at least ``R + r_link - MAX_PENETRATION`` from the sphere's centre (``R`` its radius, lengths over
    ``l``); and every finger touching the sphere at a link besides its last (the wrap, not a pinch).
    """
    from simgrip.gripper.simulate import gripper_nodes
    from simgrip.intersection import crossing_pairs

    bad = []
    if not state.held:
        bad.append("the sphere was dropped")
    if not state.converged:
        bad.append("the settle did not converge")
    if not getattr(state, "valid", True):
        bad.append(f"the state is invalid: {state.warnings}")
    if state.penetration > MAX_PENETRATION:
        bad.append(f"a contact {state.penetration:.3g} l deep (at most {MAX_PENETRATION:g})")
    nodes = gripper_nodes(scene, state.link_angles)
    L = scene.length
    centre = np.asarray(scene.data.xpos[scene.workpiece_body], dtype=float) / L
    radius = float(scene.size[0]) / L
    for k, P in enumerate(nodes):
        e = np.array([np.cos(scene.azimuths[k]), np.sin(scene.azimuths[k])])  # the finger's plane: (E1, z)
        planar = np.stack([P[:, :2] @ e, P[:, 2]], axis=1)
        if len(crossing_pairs(planar)[0]):
            bad.append(f"finger {k} crosses itself")
        a, b = P[:-1], P[1:]
        t = np.clip(np.einsum("ij,ij->i", centre - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0.0, 1.0)
        gap = np.linalg.norm(a + t[:, None] * (b - a) - centre, axis=1) - radius - float(scene.r_link)
        if gap.min() < -MAX_PENETRATION:
            bad.append(f"finger {k} enters the sphere by {-gap.min():.3g} l (link {int(np.argmin(gap))})")
    n = scene.n
    touch = {(c["finger"], c["link"]) for c in (state.contact_set or []) if c["with"] == "workpiece"}
    for k in range(len(nodes)):
        if not any(f == k and i < n - 1 for f, i in touch):
            bad.append(f"finger {k} touches the sphere with its tip only (no wrap)")
    return bad


def wrap_grasp_picture(links: int = LINKS, **render):
    """Build, settle and draw the wrap grasp of :data:`WRAP`: ``(image, scene, state)``.

    ``render`` goes to :func:`~simgrip.figures.gripper.render_gripper` (``width``, ``height``, ...).

    Raises
    ------
    RuntimeError
        The settled state is not a valid wrap (:func:`wrap_violations`, named): nothing is drawn.
    simgrip.settle.state.SettleError
        The settle failed.
    simgrip.sim.gl.RenderingUnavailable
        No OpenGL backend renders offscreen here.
    """
    from simgrip.figures.gripper import render_gripper
    from simgrip.gripper.settle import settle_gripper

    scene = wrap_scene(links)
    state = settle_gripper(scene, contact="full")
    bad = wrap_violations(scene, state)
    if bad:
        raise RuntimeError(f"wrap_grasp: not a valid wrap at n = {links}: {'; '.join(bad)}")
    return render_gripper(scene, state, **render), scene, state


def make_wrap_grasp_figure(out_dir) -> Path:
    """``out_dir/wrap_grasp.png``: the wrap grasp at :data:`LINKS` links, 800 x 600, seen from a little below
    the palm's plane so that the fingers' curl around the sphere shows (used by ``simgrip figures``)."""
    from simgrip.figures.gripper import write_png

    image, _, _ = wrap_grasp_picture(LINKS, width=800, height=600, elevation=-15.0)
    return write_png(image, Path(out_dir) / "wrap_grasp.png")
