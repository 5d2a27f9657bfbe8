"""The command line: JSON fields, and exit code 2 with the parameter named for bad input."""

import json
import subprocess
import sys

import pytest

from simgrip.cli import main


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "simgrip.cli", *args], capture_output=True, text=True)


def test_solve_json_fields(capsys):
    assert main(["solve", "I", "--kappa", "-5", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    for key in ("tip", "normal_force", "friction_force", "required_mu", "feasible", "min_eigenvalue"):
        assert key in rec
    assert rec["tip"][0] == pytest.approx(0.3, abs=1e-9)  # the width constraint X(l) = b/2
    assert rec["friction_force"] == pytest.approx(-5.0)  # F_f = -M
    assert rec["required_mu"] == pytest.approx(5.0 / rec["normal_force"])


def test_solve_grip_iii_json_has_contact(capsys):
    assert main(["solve", "III", "--kappa", "-4", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    for key in ("contact", "N1", "N2"):
        assert key in rec
    assert rec["contact"][0] == pytest.approx(0.3, abs=1e-9)
    assert rec["N2"] == pytest.approx(-5.0)


def test_solve_concentrated_profile_table(capsys):
    assert main(["solve", "II", "--profile", "concentrated", "--kappa-max", "6", "--alpha", "2"]) == 0
    out = capsys.readouterr().out
    assert "normal_force" in out and "Concentrated(kappa_max=6.0, alpha=2.0, p=1)" in out


@pytest.mark.parametrize(
    "args, name",
    [
        (["solve", "I", "--kappa", "nan"], "kappa"),
        (["solve", "IV", "--kappa", "-3"], "grip"),
        (["solve", "I", "--kappa", "-3", "--D", "-1"], "D"),
        (["solve", "I", "--kappa", "-3", "--M", "-2"], "M"),
        (["solve", "I", "--kappa", "-3", "--b", "2.4"], "b"),
        (["solve", "I", "--kappa", "-3", "--mu", "-0.1"], "mu_s"),
        (["solve", "III", "--kappa", "-3", "--gamma", "1.2"], "gamma"),
        (["solve", "I", "--profile", "spiral", "--kappa", "-3"], "profile"),
        (["solve", "I"], "kappa"),
        (["solve", "II", "--profile", "concentrated", "--alpha", "-1"], "alpha"),
        (["figures", "--which", "99"], "figure"),
        (["figures", "--jobs", "0"], "jobs"),
    ],
)
def test_bad_input_exits_2_naming_the_parameter(args, name):
    out = run_cli(*args)
    assert out.returncode == 2, out.stderr
    assert name in out.stderr
    assert "Traceback" not in out.stderr


def test_argparse_errors_exit_2():
    out = run_cli("solve", "I", "--kappa", "abc")
    assert out.returncode == 2 and "--kappa" in out.stderr


def test_figures_command_writes_pngs(tmp_path, capsys):
    assert main(["figures", "--out", str(tmp_path), "--which", "6", "--jobs", "1", "--no-progress"]) == 0
    assert (tmp_path / "fig06.png").stat().st_size > 10_000
    assert capsys.readouterr().out.strip().endswith("fig06.png")


def test_simulate_json_fields(capsys):
    assert main(["simulate", "I", "--kappa", "-5.5", "--links", "16", "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    for key in ("tip", "normal_force", "friction_force", "required_mu", "feasible", "min_eigenvalue",
                "wall_time_s", "steps", "held", "penetration", "residual"):
        assert key in rec
    assert rec["held"] is True and rec["penetration"] < 1e-4
    assert rec["friction_force"] == pytest.approx(-5.0, rel=1e-6)  # the workpiece's weight M per finger


@pytest.mark.parametrize("method", ["newton", "dynamics"])
def test_compare_json_differences_are_small(capsys, method):
    assert main(["compare", "II", "--kappa", "5", "--links", "32", "--json", "--method", method]) == 0
    out = json.loads(capsys.readouterr().out)
    sim, ref, diff = out["simulation"], out["reference"], out["difference"]
    assert sim["source"] == "simulation" and ref["source"] == "elastica"
    # second-order chain: ~1e-3 relative at n = 32 (tests/test_settle.py checks the order itself)
    assert abs(diff["normal_force"]) < 5e-3 * abs(ref["normal_force"])
    assert abs(diff["tip"][1]) < 1e-3


@pytest.mark.parametrize(
    "args, name",
    [
        (["simulate", "I", "--kappa", "-5", "--links", "1"], "links"),
        (["simulate", "III", "--kappa", "inf", "--links", "8"], "kappa"),
        (["compare", "I", "--kappa", "-5", "--b", "-0.2"], "b"),
        (["compare", "X", "--kappa", "-5"], "grip"),
        (["simulate", "I", "--kappa", "-5", "--method", "rk4"], "method"),
    ],
)
def test_simulate_and_compare_bad_input(args, name):
    out = run_cli(*args)
    assert out.returncode == 2 and name in out.stderr


def test_render_command_writes_png_and_gif(tmp_path):
    out = run_cli("render", "--png", str(tmp_path / "g.png"), "--gif", str(tmp_path / "p.gif"))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "g.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "p.gif").read_bytes()[:6] in (b"GIF89a", b"GIF87a")


@pytest.mark.parametrize(
    "args, name",
    [
        (["solve", "I", "--kappa", "-1e6"], "kappa"),  # argparse used to read -1e6 as an option
        (["solve", "I", "--kappa", "-inf"], "kappa"),
        (["solve", "I", "--kappa", "-nan"], "kappa"),
        (["solve", "I", "--kappa", "-4", "--D", "-1e-3"], "D"),
        (["solve", "I", "--profile", "concentrated", "--alpha", "520"], "alpha"),  # was an OverflowError
        (["simulate", "I", "--profile", "concentrated", "--alpha", "520"], "alpha"),
        (["simulate", "I", "--kappa", "-5.5", "--M", "1e300"], "M"),  # was exit 0 with an overflow warning
        (["simulate", "I", "--kappa", "-5.5", "--links", "100000"], "links"),  # used to hang in the builder
        (["solve", "I", "--kappa", "-4", "--K", "100000000"], "K"),
        (["stress", "--seed", "-1"], "seed"),
        (["render", "--seed", "-1"], "seed"),  # was a Gymnasium traceback
        (["figures", "--which"], "--which"),  # did nothing and exited 0
    ],
)
def test_hostile_values_are_named_in_process(capsys, args, name):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert name in err and "Traceback" not in err


@pytest.mark.parametrize(
    "command",
    [["bench", "--quick"], ["stress", "--cases", "3"], ["figures", "--which", "6"], ["render"]],
)
def test_output_paths_are_checked_before_any_work(tmp_path, capsys, monkeypatch, command):
    """An existing file as the output is refused at once, naming the option; the command never runs."""
    import simgrip.cli as cli

    blocker = tmp_path / "file"
    blocker.write_text("x")
    option = ["--png", str(blocker / "g.png")] if command[0] == "render" else ["--out", str(blocker)]
    ran = []
    monkeypatch.setitem(cli.COMMANDS, command[0], lambda args: ran.append(args))
    assert main([*command, *option]) == 2
    assert ran == []
    assert option[0] in capsys.readouterr().err


def test_interrupt_is_one_line_exit_130_and_no_partial_file(tmp_path, capsys, monkeypatch):
    import simgrip.cli as cli
    from simgrip.io import atomic_write

    out = tmp_path / "new" / "out"

    def interrupted(args):
        (out / "sub").mkdir(parents=True)
        with atomic_write(out / "done.json") as fh:
            fh.write("{}")
        # a worker killed mid-write leaves its temporary file behind; the CLI removes it
        cm = atomic_write(out / "sub" / "half.json")
        cm.__enter__().write("{")
        raise KeyboardInterrupt

    monkeypatch.setitem(cli.COMMANDS, "stress", interrupted)
    assert main(["stress", "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "simgrip stress: interrupted"
    assert sorted(p.name for p in out.rglob("*")) == ["done.json", "sub"]


def test_interrupt_removes_an_output_folder_it_created_and_left_empty(tmp_path, monkeypatch, capsys):
    import simgrip.cli as cli

    out = tmp_path / "fresh"

    def interrupted(args):
        out.mkdir()
        raise KeyboardInterrupt

    monkeypatch.setitem(cli.COMMANDS, "figures", interrupted)
    assert main(["figures", "--out", str(out)]) == 130
    assert not out.exists()


def test_sigterm_is_an_interrupt():
    import os
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-c", "import time, simgrip.cli as c; "
                             "c.COMMANDS['solve'] = lambda a: time.sleep(60); "
                             "raise SystemExit(c.main(['solve', 'I', '--kappa', '-4']))"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.5)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 130, err
    assert err.strip() == "simgrip solve: interrupted"
    assert not os.path.exists("grip.png")


def test_closed_stdout_is_quiet():
    """simgrip ... | true: the reader is gone before we print; no BrokenPipeError."""
    import os

    r, w = os.pipe()
    os.close(r)
    proc = subprocess.run([sys.executable, "-m", "simgrip.cli", "solve", "I", "--kappa", "-5"],
                          stdout=w, stderr=subprocess.PIPE, text=True)
    os.close(w)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr


def test_closed_stdout_is_quiet_for_a_command_that_prints_as_it_goes(tmp_path):
    """sweep prints its files' paths itself (not through the CLI's printer): it printed BrokenPipeError's
    traceback and exited 1 when piped into ``true``."""
    import os

    r, w = os.pipe()
    os.close(r)
    proc = subprocess.run([sys.executable, "-m", "simgrip.cli", "sweep", "I", "--kappa", "-5", "--links", "8",
                           "--reference", "none", "--no-map", "--jobs", "1", "--no-progress", "--out",
                           str(tmp_path / "o")], stdout=w, stderr=subprocess.PIPE, text=True)
    os.close(w)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    assert (tmp_path / "o" / "sweep.csv").is_file()


def test_help_returns_0(capsys):
    assert main(["--help"]) == 0
    assert "simgrip" in capsys.readouterr().out


def test_negative_values_reach_every_numeric_option():
    import math

    from simgrip.cli import build_parser

    args = build_parser().parse_args(["simulate", "I", "--kappa", "-1e6", "--D", "-inf", "--links", "-3", "--json"])
    assert args.kappa == -1e6 and args.D == -math.inf and args.links == -3 and args.json
    sweep = build_parser().parse_args(["sweep", "I", "--kappa", "-1e6", "-3", "5", "--links", "8", "--out", "x"])
    assert sweep.kappa == ["-1e6", "-3", "5"]


@pytest.mark.parametrize(
    "extra, name",
    [(["--contact", "edge"], "contact"),
     (["--target-error", "1e-5", "--contact", "surface"], "contact"),
     (["--target-error", "1e-5", "--method", "dynamics"], "method")],
)
def test_contact_option_and_target_error_combinations_are_named(extra, name):
    out = run_cli("simulate", "I", "--kappa", "-5.5", "--links", "8", *extra)
    assert out.returncode == 2 and name in out.stderr


def test_surface_contact_reference_carries_the_couple():
    """--contact surface: the reference is solved with the simulation's own tip couple, so the
    two agree to the same discretisation error as the point contact does with its reference."""
    point = json.loads(run_cli("compare", "I", "--kappa", "-5.5", "--links", "16", "--json").stdout)
    surf = json.loads(run_cli("compare", "I", "--kappa", "-5.5", "--links", "16", "--contact", "surface", "--json").stdout)
    assert abs(point["simulation"]["contact_moment"]) < 1e-12
    assert abs(surf["simulation"]["contact_moment"]) > 1e-4
    for rec in (point, surf):
        n_rel = abs(rec["difference"]["normal_force"]) / rec["reference"]["normal_force"]
        assert n_rel < 4e-3  # second-order chain error at n = 16 (0.07 % at n = 32, x4)


@pytest.mark.parametrize("argv, prefix, needle", [
    (["solve", "I", "--kappa", "abc"], "simgrip solve", "--kappa"),
    (["simulate", "I", "--kappa", "-5", "--links", "2.5"], "simgrip simulate", "--links"),
    (["sweep", "I", "--kappa", "-5", "--links", "8", "--out", "x", "--jobs", "two"], "simgrip sweep", "--jobs"),
    (["solve", "--kappa", "-5"], "simgrip solve", "grip"),
])
def test_a_value_argparse_cannot_read_is_one_line_naming_it(argv, prefix, needle, capsys):
    """argparse's own refusals (a wrong type, a missing argument) printed the usage block, 5-10 lines, under the
    prefix ``simgrip:``; now one line under the command's name, as the values the commands check themselves."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith(f"{prefix}: error: ") and needle in err, err


def _refused_in_one_line(argv, needle, capsys, tmp_path, monkeypatch):
    """``main(argv)`` run in an empty folder: status 2, one line of stderr holding ``needle``, nothing written."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and needle in err, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv, needle", [
    (["bench", "--quick", "--repeats", "99999999999999999999", "--out", "b"], "repeats must be an integer in [1, 100]"),
    (["simulate", "I", "--kappa", "-5", "--fingers", "999999999999999999999"], "fingers must be an integer in [2, 32]"),
])
def test_work_it_cannot_finish_is_refused_by_name(argv, needle, capsys, tmp_path, monkeypatch):
    """Found by an audit: ``bench --repeats 10^20`` ran for ever, ``--fingers 10^21`` raised OverflowError."""
    _refused_in_one_line(argv, needle, capsys, tmp_path, monkeypatch)


@pytest.mark.parametrize("argv, needle", [
    (["solve", "I", "--kappa", "-5", "--profile", "concentrated"], "kappa: the concentrated profile"),
    (["solve", "I", "--kappa", "-5", "--sign", "1"], "--sign: only with --profile concentrated"),
    (["solve", "I", "--kappa", "-5", "--alpha", "3"], "--alpha: only with --profile concentrated"),
    (["simulate", "I", "--kappa", "-5", "--links", "8", "--fingers", "2", "--contact", "full", "--box-depth", "0.2"],
     "--box-depth: the planar finger's --contact full only"),
    (["sweep", "I", "--kappa", "-5", "--links", "8", "--throughput", "--resume", "--out", "o"],
     "--resume: not with --throughput"),
    (["sweep", "I", "--kappa", "-5", "--links", "8", "--throughput", "--no-map", "--out", "o"],
     "--no-map: not with --throughput"),
])
def test_an_option_the_command_would_ignore_is_refused(argv, needle, capsys, tmp_path, monkeypatch):
    """Found by an audit: each of these ran and silently ignored the option (the same output as without it)."""
    _refused_in_one_line(argv, needle, capsys, tmp_path, monkeypatch)


def test_a_scheduler_not_reached_leaves_no_folder_and_no_timing_first(capsys, tmp_path):
    """``sweep --throughput --scheduler`` once ran ~5 s of local timing before trying the address, and a failed
    command left its new, empty ``--out`` behind."""
    import time

    out = tmp_path / "o"
    t0 = time.perf_counter()
    assert main(["sweep", "I", "--kappa", "-5", "--links", "8", "--throughput", "--scheduler", "tcp://127.0.0.1:1",
                 "--connect-timeout", "1", "--out", str(out)]) == 2
    assert time.perf_counter() - t0 < 8
    assert "cannot be reached" in capsys.readouterr().err and not out.exists()


def test_mujoco_warnings_go_to_stderr_not_a_log_file(tmp_path):
    """A diverged settle's MuJoCo warning wrote ``MUJOCO_LOG.TXT`` into the working folder (an audit); now one
    line on stderr under the command's name, beside the command's own error."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "simgrip.cli", "simulate", "I", "--kappa", "-5", "--links", "8",
                        "--contact", "full", "--box-depth", "0.9"], capture_output=True, text=True, cwd=tmp_path,
                       timeout=300)
    if "settle diverged" not in r.stderr:  # (a divergence 317 s into the settle: another machine's floats may not)
        pytest.skip("the settle did not diverge on this machine")
    assert r.returncode == 1
    assert "simgrip simulate: MuJoCo: Nan, Inf or huge value" in r.stderr and "Traceback" not in r.stderr
    assert not list(tmp_path.iterdir())
