"""The per-run CSV logs of ``examples/train_sb3.py``: the training episodes' curve and the sampled actions' windows.

Both files are written whole (:func:`simgrip.io.atomic_write`), so a checkpoint's copy is never half a file.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from simgrip.io import atomic_write

#: the columns of ``<algo>_curve.csv``, one row per finished training episode (seconds since the training began)
CURVE_COLUMNS = ("episode", "timesteps", "wall_s", "cpu_s", "episode_return", "length", "success")


def write_curve(path: Path, rows) -> None:
    """Write ``<algo>_curve.csv``: :data:`CURVE_COLUMNS`, then ``rows`` (tuples in that order)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(CURVE_COLUMNS)
    w.writerows(rows)
    with atomic_write(path) as fh:
        fh.write(buf.getvalue())


class ActionWindow:
    """Running sums of the sampled actions over one window of training steps (one ``<algo>_policy.csv`` row).

    :meth:`add` takes one step's actions, one row per environment of a vectorised env (``(n_envs, dims)``) or a
    single action (``(dims,)``); :attr:`n` counts the environment steps added since the window began."""

    def __init__(self):
        self.n, self.s, self.ss = 0, 0.0, 0.0

    def add(self, actions) -> None:
        a = np.asarray(actions, dtype=float).reshape(-1, np.shape(actions)[-1])
        self.n += a.shape[0]
        self.s = self.s + a.sum(axis=0)
        self.ss = self.ss + (a * a).sum(axis=0)

    def row(self, timesteps: int, cpu_s: float, log_std) -> tuple:
        """``(timesteps, cpu_s, means..., stds..., log_stds...)`` (``log_std`` None: empty cells); the window
        restarts."""
        mean = self.s / self.n
        std = np.sqrt(np.maximum(self.ss / self.n - mean * mean, 0.0))
        log_std = [""] * mean.size if log_std is None else [round(float(x), 6) for x in log_std]
        self.n, self.s, self.ss = 0, 0.0, 0.0
        return (timesteps, round(cpu_s, 3), *[round(float(x), 6) for x in mean], *[round(float(x), 6) for x in std],
                *log_std)


def write_policy(path: Path, rows) -> None:
    """Write ``<algo>_policy.csv``: ``timesteps, cpu_s``, then per action ``i`` ``action_mean_i``, ``action_std_i``
    and ``log_std_i``, then ``rows`` (from :meth:`ActionWindow.row`)."""
    buf = io.StringIO()
    w = csv.writer(buf)
    dims = (len(rows[0]) - 2) // 3 if rows else 0
    w.writerow(["timesteps", "cpu_s", *[f"action_mean_{i}" for i in range(dims)],
                *[f"action_std_{i}" for i in range(dims)], *[f"log_std_{i}" for i in range(dims)]])
    w.writerows(rows)
    with atomic_write(path) as fh:
        fh.write(buf.getvalue())
