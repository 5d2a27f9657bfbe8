"""The training logs of ``examples/train_sb3.py`` (:mod:`simgrip.envs.training_logs`): the sampled actions' window
statistics against NumPy's on the same actions, one step's actions a row per env of a vectorised env or one
action, and the two CSV files read back whole."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from simgrip.envs.training_logs import CURVE_COLUMNS, ActionWindow, write_curve, write_policy


def test_the_window_gives_numpys_mean_and_std_whatever_the_steps_shape():
    rng = np.random.default_rng(4)
    steps = [rng.normal(0.3, 0.7, (4, 2)) for _ in range(5)] + [rng.normal(size=2), rng.normal(size=(1, 2))]
    w = ActionWindow()
    for a in steps:
        w.add(a)
    every = np.vstack([np.atleast_2d(a) for a in steps])
    assert w.n == every.shape[0] == 22
    row = w.row(22, 1.23456, np.array([-0.5, -0.25]))
    assert row[:2] == (22, 1.235)
    np.testing.assert_allclose(row[2:4], every.mean(axis=0), atol=1e-6)
    np.testing.assert_allclose(row[4:6], every.std(axis=0), atol=1e-6)  # population std, as a window's spread
    assert row[6:] == (-0.5, -0.25)
    assert w.n == 0  # the window restarted
    w.add([1.0, -1.0])
    assert w.row(23, 2.0, None)[2:] == (1.0, -1.0, 0.0, 0.0, "", "")  # SAC: no log std, empty cells


@pytest.mark.parametrize("rows", [[], [(0, 64, 0.5, 0.4, 1.5, 64, 1), (1, 128, 1.0, 0.9, -2.0, 64, 0)]])
def test_the_curve_reads_back_with_its_columns(rows, tmp_path):
    write_curve(tmp_path / "c.csv", rows)
    with open(tmp_path / "c.csv", newline="") as fh:
        got = list(csv.reader(fh))
    assert tuple(got[0]) == CURVE_COLUMNS
    assert [[float(x) for x in r] for r in got[1:]] == [[float(x) for x in r] for r in rows]


def test_the_policy_file_names_a_column_per_action_and_statistic(tmp_path):
    w = ActionWindow()
    w.add(np.array([[0.0, 1.0], [2.0, 3.0]]))
    write_policy(tmp_path / "p.csv", [w.row(2, 0.5, [0.0, 0.0])])
    with open(tmp_path / "p.csv", newline="") as fh:
        head, row = list(csv.reader(fh))
    assert head == ["timesteps", "cpu_s", "action_mean_0", "action_mean_1", "action_std_0", "action_std_1",
                    "log_std_0", "log_std_1"]
    assert [float(x) for x in row] == [2, 0.5, 1.0, 2.0, 1.0, 1.0, 0.0, 0.0]
