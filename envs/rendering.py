"""Pictures of the pick environment for ``simgrip render``: a PNG of a settled grip, a GIF of a pick.

Both run the scripted elastica controller (:class:`simgrip.envs.scripted.ScriptedPickPolicy`)
in :class:`simgrip.envs.pick.PickEnv` and write through :func:`simgrip.io.atomic_write`, under
:mod:`simgrip.io`'s output-path policy: ``path`` is checked before anything is rendered (a
folder, FIFO, device or socket there, or a dangling link, raises ``ValueError`` naming ``path``;
a link to a regular file is followed and kept).
Rendering is offscreen; on a machine without a display the backend is chosen by
:func:`simgrip.sim.gl.choose_backend` (``MUJOCO_GL`` if set, else EGL, then OSMesa).
"""

from __future__ import annotations

import io
import os

import numpy as np

from simgrip.io import atomic_write, check_output_file

__all__ = ["render_grip_png", "render_pick_gif", "scripted_frames"]


def scripted_frames(*, grip: str = "I", seed: int = 0, every: int = 2, max_steps: int = 200,
                    width: int = 480, height: int = 360, camera: str = "front", env_kwargs=None,
                    until: str = "end") -> tuple[list[np.ndarray], dict]:
    """Run one scripted pick and return ``(frames, info)``.

    ``every`` keeps one frame in that many steps; ``until="settled"`` stops when the
    grip has settled (right before the lift), ``"end"`` at the episode's end.
    ``info`` has the box parameters, the chosen ``kappa`` and whether the pick succeeded.
    """
    from simgrip.envs.pick import PickEnv
    from simgrip.envs.scripted import ScriptedPickPolicy

    if until not in ("end", "settled"):
        raise ValueError(f"until must be 'end' or 'settled', got {until!r}")
    if int(every) < 1:
        raise ValueError(f"every must be a positive integer, got {every!r}")
    env = PickEnv(grip=grip, render_mode="rgb_array", width=width, height=height, camera=camera,
                  **dict(env_kwargs or {}))
    frames: list[np.ndarray] = []
    try:
        obs, info = env.reset(seed=seed)
        policy = ScriptedPickPolicy()
        policy.reset(env, info)
        frames.append(env.render())
        step_info = {}
        for k in range(int(max_steps)):
            action = policy(obs)
            if until == "settled" and action[-1] > 0:  # the lift starts: the grip has settled
                frames.append(env.render())
                break
            obs, _, term, trunc, step_info = env.step(action)
            if k % int(every) == 0 or term:
                frames.append(env.render())
            if term or trunc:
                break
        out = {
            "box_width": env.box.width, "box_mass": env.box.mass, "box_friction": env.box.friction,
            "kappa": policy.kappa, "is_success": bool(step_info.get("is_success", False)),
            "normal_force": np.asarray(step_info.get("normal_force", [np.nan, np.nan])).tolist(),
            "dimensionless": env.dimensionless(), "dt": env.dt,
        }
    finally:
        env.close()
    return frames, out


def render_grip_png(path: str | os.PathLike, *, grip: str = "I", seed: int = 0, width: int = 640,
                    height: int = 480, camera: str = "front", env_kwargs=None) -> dict:
    """Write a PNG of the scripted controller's settled grip (before the lift); returns the episode info.

    ``path`` is checked first (``ValueError`` naming it; see the module docstring).
    """
    from PIL import Image

    check_output_file(path, "path")
    frames, info = scripted_frames(grip=grip, seed=seed, width=width, height=height, camera=camera,
                                   env_kwargs=env_kwargs, until="settled")
    buf = io.BytesIO()
    Image.fromarray(frames[-1]).save(buf, format="PNG")
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())
    return info


def render_pick_gif(path: str | os.PathLike, *, grip: str = "I", seed: int = 0, width: int = 320,
                    height: int = 240, every: int = 2, camera: str = "front", env_kwargs=None) -> dict:
    """Write an animated GIF of one scripted pick (every ``every``-th control step); returns the episode info.

    ``path`` is checked first (``ValueError`` naming it; see the module docstring).
    """
    from PIL import Image

    check_output_file(path, "path")
    frames, info = scripted_frames(grip=grip, seed=seed, every=every, width=width, height=height,
                                   camera=camera, env_kwargs=env_kwargs, until="end")
    ms = int(round(1000.0 * int(every) * info["dt"]))
    images = [Image.fromarray(f) for f in frames]
    buf = io.BytesIO()
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:], duration=ms, loop=0)
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())
    info["frames"] = len(frames)
    return info
