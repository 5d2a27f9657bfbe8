"""simgrip.sim.checks: where MuJoCo's warnings go for a block (the errors themselves: test_models)."""

import mujoco

from helpers import nan_position_step as _warn
from simgrip.sim.checks import stderr_printer, warnings_to, warnings_to_stderr


def test_warnings_go_to_the_handler_and_the_previous_one_comes_back(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    outer, inner = [], []
    previous = mujoco.get_mju_user_warning()
    try:
        mujoco.set_mju_user_warning(outer.append)
        with warnings_to(inner.append):
            count = _warn()
        assert len(inner) == 1 and "Nan, Inf or huge value in QPOS" in inner[0] and outer == []
        assert count == 1  # still counted for the checks
        _warn()
        assert len(outer) == 1 and len(inner) == 1  # restored on leaving
    finally:
        mujoco.set_mju_user_warning(previous)
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT


def test_warnings_to_stderr_is_one_line_under_the_prefix(capsys):
    with warnings_to_stderr("simgrip worker 7"):
        _warn()
    err = capsys.readouterr().err
    assert err.startswith("simgrip worker 7: MuJoCo: Nan, Inf or huge value in QPOS") and err.count("\n") == 1


def test_the_stderr_printer_is_the_one_line_the_cli_installs(capsys):
    stderr_printer("simgrip simulate")("a message")
    assert capsys.readouterr().err == "simgrip simulate: MuJoCo: a message\n"
