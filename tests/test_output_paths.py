"""Issue 16 section 1: output paths never destroy anything (simgrip.io's output-path policy, every command).

An existing target that is not a regular file (FIFO, device, socket, folder) is refused before any work, naming
the option; a symbolic link is followed to the regular file it points to (the link kept) or refused; two outputs of
one command at one file are refused; ``render`` writes only what was asked for.

Safety of the tests themselves (they run as root on some machines): nothing here lets code under test write near
``/dev/null``.  Targets that must be refused are FIFOs, sockets and (as root only) character devices made with
``os.mknod`` inside ``tmp_path``; ``/dev/null`` itself is only handed to the pure checks, which never write, or to
the command line with every writer replaced by a recorder, so that even broken code could not replace it.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import load_example

from simgrip import io as sio
from simgrip.cli import main


# targets ---------------------------------------------------------------------------------------------------------

def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


@pytest.fixture
def unix_socket(tmp_path, monkeypatch):
    """A listening-capable Unix socket file ``tmp_path/sock`` (bound by a relative name: AF_UNIX paths are short)."""
    monkeypatch.chdir(tmp_path)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind("sock")
    yield tmp_path / "sock"
    s.close()


def _char_device(path: Path) -> Path:
    """A character device like /dev/null (major 1, minor 3) at ``path``: root only (skips otherwise)."""
    if os.geteuid() != 0:
        pytest.skip("making a device node needs root")
    try:
        os.mknod(path, stat.S_IFCHR | 0o600, os.makedev(1, 3))
    except OSError as exc:  # e.g. a container without CAP_MKNOD
        pytest.skip(f"cannot make a device node here: {exc}")
    return path


def _kind(path: Path):
    return stat.S_IFMT(os.lstat(path).st_mode)


def _no_temp_files(folder: Path) -> bool:
    return not any(p.name.startswith(sio.TEMP_PREFIX) for p in folder.iterdir())


def _assert_refused_unchanged(path: Path, write_target=None):
    """``atomic_write`` to ``write_target`` (default ``path``) is refused and ``path`` keeps its kind."""
    before = _kind(path)
    with pytest.raises(sio.OutputPathError, match="--png"):
        with sio.atomic_write(write_target or path, "wb", option="--png") as fh:
            fh.write(b"\x89PNG must never land here")
    assert _kind(path) == before
    assert _no_temp_files(path.parent)


# the policy in simgrip.io ----------------------------------------------------------------------------------------

def test_atomic_write_refuses_a_fifo_a_folder_and_a_socket(tmp_path, unix_socket):
    _assert_refused_unchanged(_fifo(tmp_path / "f"))
    (tmp_path / "d").mkdir()
    _assert_refused_unchanged(tmp_path / "d")
    _assert_refused_unchanged(unix_socket)
    assert stat.S_ISSOCK(os.lstat(unix_socket).st_mode)


def test_atomic_write_refuses_a_character_device(tmp_path):
    dev = _char_device(tmp_path / "c")
    _assert_refused_unchanged(dev)
    assert stat.S_ISCHR(os.lstat(dev).st_mode)


@pytest.mark.parametrize("kind", ["fifo", "device", "folder", "link elsewhere"])
def test_atomic_write_rechecks_right_before_the_rename(tmp_path, kind):
    """A target that turns into a FIFO/device/folder/other link while the result is written is not replaced."""
    target = tmp_path / "r.json"
    target.write_text("old")
    elsewhere = tmp_path / "elsewhere.json"
    elsewhere.write_text("keep")
    with pytest.raises(sio.OutputPathError, match="path"):
        with sio.atomic_write(target) as fh:
            fh.write("new")
            target.unlink()
            if kind == "fifo":
                os.mkfifo(target)
            elif kind == "device":
                _char_device(target)
            elif kind == "folder":
                target.mkdir()
            else:
                target.symlink_to(elsewhere)
    expected = {"fifo": stat.S_IFIFO, "device": stat.S_IFCHR, "folder": stat.S_IFDIR, "link elsewhere": stat.S_IFLNK}
    assert _kind(target) == expected[kind]
    assert elsewhere.read_text() == "keep"
    assert _no_temp_files(tmp_path)


def test_a_symlink_is_followed_and_kept(tmp_path):
    real = tmp_path / "data" / "real.json"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(Path("data") / "real.json")  # relative, as `ln -s` makes them
    chain = tmp_path / "chain.json"
    chain.symlink_to(link)
    sio.write_json(chain, {"a": 1})
    assert link.is_symlink() and chain.is_symlink()
    assert real.read_text() == '{\n  "a": 1\n}\n'
    assert sio.resolve_output_file(chain) == real.resolve()
    assert _no_temp_files(tmp_path) and _no_temp_files(real.parent)


def test_a_symlink_to_a_fifo_or_a_device_is_refused(tmp_path):
    fifo = _fifo(tmp_path / "f")
    link = tmp_path / "to_fifo.png"
    link.symlink_to(fifo)
    _assert_refused_unchanged(fifo, write_target=link)
    assert link.is_symlink()
    # /dev/null only through the pure check: it never writes, so this is safe even if the check were broken
    devnull = tmp_path / "to_devnull.png"
    devnull.symlink_to(os.devnull)
    with pytest.raises(sio.OutputPathError, match="--png.*character device"):
        sio.check_output_file(devnull, "--png")
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode) and devnull.is_symlink()


@pytest.mark.parametrize("kind", ["dangling", "loop"])
def test_a_dangling_or_looping_symlink_is_refused(tmp_path, kind):
    link = tmp_path / "l.png"
    if kind == "dangling":
        link.symlink_to(tmp_path / "nowhere" / "x.png")
    else:
        link.symlink_to(tmp_path / "l2.png")
        (tmp_path / "l2.png").symlink_to(link)
    with pytest.raises(sio.OutputPathError, match="--png.*symbolic link"):
        sio.check_output_file(link, "--png")
    with pytest.raises(sio.OutputPathError):
        with sio.atomic_write(link) as fh:
            fh.write("x")
    assert link.is_symlink() and not (tmp_path / "nowhere").exists()


def test_check_output_file_names_the_kind_and_the_option(tmp_path, unix_socket):
    fifo = _fifo(tmp_path / "f")
    with pytest.raises(ValueError, match=r"--gif: .*'.*f' is a FIFO \(named pipe\), not a regular file"):
        sio.check_output_file(fifo, "--gif")
    with pytest.raises(ValueError, match="--gif: .* is a socket"):
        sio.check_output_file(unix_socket, "--gif")
    with pytest.raises(ValueError, match="--gif: .* is a folder"):
        sio.check_output_file(tmp_path, "--gif")
    with pytest.raises(ValueError, match="--gif.*below"):
        sio.check_output_file(fifo / "x.gif", "--gif")
    assert sio.check_output_file(tmp_path / "new.gif", "--gif") == tmp_path / "new.gif"


def test_check_output_dir_refuses_what_is_not_a_folder(tmp_path, unix_socket):
    with pytest.raises(ValueError, match="--out: .* is a FIFO"):
        sio.check_output_dir(_fifo(tmp_path / "f"), "--out", create=False)
    with pytest.raises(ValueError, match="--out: .* is a socket"):
        sio.check_output_dir(unix_socket, "--out")
    with pytest.raises(ValueError, match="--out: .* is a character device"):
        sio.check_output_dir(os.devnull, "--out", create=False)  # a pure check: nothing is written anywhere
    linked = tmp_path / "linked"
    linked.symlink_to(tmp_path / "real", target_is_directory=True)
    (tmp_path / "real").mkdir()
    assert sio.check_output_dir(linked) == linked  # a link to a folder is a folder; the files go inside it


def test_check_output_files_in_refuses_a_folder_or_fifo_at_a_result_name(tmp_path):
    out = tmp_path / "out"
    assert sio.check_output_files_in(out, ["sweep.csv"], "--out") == [out / "sweep.csv"]  # missing folder: fine
    (out / "sweep.csv").mkdir(parents=True)
    with pytest.raises(ValueError, match=r"--out: .*sweep\.csv' is a folder, not a regular file"):
        sio.check_output_files_in(out, ["sweep.json", "sweep.csv"], "--out")
    _fifo(out / "map.png")
    with pytest.raises(ValueError, match=r"out_dir: .*map\.png' is a FIFO"):
        sio.check_output_files_in(out, ["map.png"], "out_dir")
    (out / "sweep.json").write_text("{}")
    assert sio.check_output_files_in(out, ["sweep.json"]) == [out / "sweep.json"]


def test_check_distinct_outputs_sees_through_spellings_and_links(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sio.check_distinct_outputs({"--png": "g.png", "--gif": "p.gif"})
    for other in ("g.png", "./g.png", str(tmp_path / "g.png"), "sub/../g.png"):
        with pytest.raises(ValueError, match="--gif: .* is the same file as --png"):
            sio.check_distinct_outputs({"--png": "g.png", "--gif": other})
    Path("g.png").write_bytes(b"x")
    Path("link.png").symlink_to("g.png")
    os.link("g.png", "hard.png")
    for other in ("link.png", "hard.png"):
        with pytest.raises(ValueError, match="same file"):
            sio.check_distinct_outputs({"--png": "g.png", "--gif": other})


def test_remove_partial_files_leaves_a_fifo_with_a_temporary_name(tmp_path):
    fifo = _fifo(tmp_path / f"{sio.TEMP_PREFIX}x.tmp")
    assert sio.remove_partial_files(tmp_path) == []
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


# the library's writers -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("function", ["render_grip_png", "render_pick_gif"])
def test_rendering_refuses_a_fifo_before_rendering(tmp_path, monkeypatch, function):
    import simgrip.envs.rendering as rendering

    def no_work(*args, **kwargs):
        raise AssertionError("rendered before checking the path")

    monkeypatch.setattr(rendering, "scripted_frames", no_work)
    fifo = _fifo(tmp_path / "f")
    with pytest.raises(ValueError, match="path: .* is a FIFO"):
        getattr(rendering, function)(fifo)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


# the command line ------------------------------------------------------------------------------------------------

@pytest.fixture
def fake_render(monkeypatch):
    """Replace the GL-rendering writers by recorders that write small files through atomic_write (no GL)."""
    import simgrip.envs.rendering as rendering
    import simgrip.sim.gl as gl

    calls = []

    def writer(kind):
        def write(path, **kwargs):
            calls.append((kind, str(path)))
            with sio.atomic_write(path, "wb") as fh:
                fh.write(kind.encode())
            return {}
        return write

    monkeypatch.setattr(rendering, "render_grip_png", writer("png"))
    monkeypatch.setattr(rendering, "render_pick_gif", writer("gif"))
    monkeypatch.setattr(gl, "choose_backend", lambda *a, **k: "fake")
    return calls


def _one_line_exit_2(capsys, argv, option):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and option in err and "Traceback" not in err, err
    return err


def test_render_to_a_fifo_and_a_device_is_refused_before_rendering(tmp_path, capsys, fake_render):
    """The issue's reproduction: mkfifo f; mknod c c 1 3; simgrip render --png f --gif c (both became files)."""
    fifo = _fifo(tmp_path / "f")
    err = _one_line_exit_2(capsys, ["render", "--png", str(fifo), "--gif", str(tmp_path / "p.gif")], "--png")
    assert "FIFO" in err
    if os.geteuid() == 0:
        dev = _char_device(tmp_path / "c")
        err = _one_line_exit_2(capsys, ["render", "--png", str(tmp_path / "g.png"), "--gif", str(dev)], "--gif")
        assert "character device" in err and stat.S_ISCHR(os.lstat(dev).st_mode)
    assert fake_render == [] and stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) in (["f"], ["c", "f"])


def test_render_to_a_socket_or_a_folder_is_refused(tmp_path, capsys, fake_render, unix_socket):
    _one_line_exit_2(capsys, ["render", "--gif", str(unix_socket)], "--gif")
    _one_line_exit_2(capsys, ["render", "--png", str(tmp_path)], "--png")
    assert fake_render == [] and stat.S_ISSOCK(os.lstat(unix_socket).st_mode)


def test_render_to_a_link_to_dev_null_is_refused(tmp_path, capsys, monkeypatch, fake_render):
    """As root this replaced /dev/null.  Every writer is a recorder here, so no code path can touch /dev/null."""
    import simgrip.cli as cli

    ran = []
    monkeypatch.setitem(cli.COMMANDS, "render", lambda args: ran.append(args))
    link = tmp_path / "null.png"
    link.symlink_to(os.devnull)
    err = _one_line_exit_2(capsys, ["render", "--png", str(link)], "--png")
    assert "character device" in err and ran == [] and fake_render == []
    err = _one_line_exit_2(capsys, ["render", "--png", os.devnull, "--gif", os.devnull], "--png")
    assert ran == [] and stat.S_ISCHR(os.stat(os.devnull).st_mode) and link.is_symlink()


@pytest.mark.parametrize("png, gif", [("P.png", "P.png"), ("./P.png", "P.png"), ("link.png", "P.png"),
                                      ("sub/../P.png", "P.png")])
def test_render_one_path_for_both_outputs_is_refused(tmp_path, capsys, monkeypatch, fake_render, png, gif):
    monkeypatch.chdir(tmp_path)
    Path("sub").mkdir()
    Path("P.png").write_bytes(b"mine")
    Path("link.png").symlink_to("P.png")
    err = _one_line_exit_2(capsys, ["render", "--png", png, "--gif", gif], "--gif")
    assert "same file as --png" in err
    assert fake_render == [] and Path("P.png").read_bytes() == b"mine"


@pytest.mark.parametrize("argv, written", [
    (["--png", "x.png"], ["x.png"]),
    (["--gif", "y.gif"], ["y.gif"]),
    ([], ["grip.png", "pick.gif"]),  # neither given: today's defaults, both
    (["--png", "x.png", "--gif", "y.gif"], ["x.png", "y.gif"]),
])
def test_render_writes_only_what_was_asked_for(tmp_path, capsys, monkeypatch, fake_render, argv, written):
    monkeypatch.chdir(tmp_path)
    assert main(["render", *argv]) == 0
    assert capsys.readouterr().out.split() == written
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(written)
    assert [path for _, path in fake_render] == written


def test_render_help_documents_the_defaults():
    from simgrip.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices["render"]
    text = " ".join(sub.format_help().split())
    assert "--png alone writes only the PNG" in text and "grip.png and pick.gif" in text


def _no_work(monkeypatch):
    """Make the parallel runner fail loudly: a refusal must come before any task starts."""
    import simgrip.parallel.runner as runner

    def work(*args, **kwargs):
        raise RuntimeError("work started before the output paths were checked")

    monkeypatch.setattr(runner, "run_tasks", work)
    import simgrip.sweep.run as sweep_run

    monkeypatch.setattr(sweep_run, "run_tasks", work, raising=False)


@pytest.mark.parametrize("command", [
    ["sweep", "I", "--kappa", "-5", "--links", "4"], ["stress", "--cases", "1"], ["figures", "--which", "6"],
    ["bench", "--quick"],
])
def test_an_out_folder_that_is_a_fifo_is_refused(tmp_path, capsys, monkeypatch, command):
    _no_work(monkeypatch)
    fifo = _fifo(tmp_path / "f")
    err = _one_line_exit_2(capsys, [*command, "--out", str(fifo), "--jobs", "1"], "--out")
    assert "FIFO" in err and stat.S_ISFIFO(os.lstat(fifo).st_mode)


@pytest.mark.parametrize("command, name, option", [
    (["sweep", "I", "--kappa", "-5", "--links", "4"], "sweep.csv", "--out"),  # was IsADirectoryError after the work
    (["sweep", "I", "--kappa", "-5", "--links", "4"], "map.png", "--out"),
    (["stress", "--cases", "1"], "stress.json", "--out"),
    (["stress", "--cases", "1"], "stability_map.png", "--out"),
    (["figures", "--which", "6"], "fig06.png", "--out"),
    (["bench", "--quick"], "bench.csv", "--out"),
    (["bench", "--quick"], "gripper.md", "--out"),
])
@pytest.mark.parametrize("blocker", ["folder", "fifo"])
def test_a_result_name_inside_out_that_is_not_a_file_is_refused_before_work(tmp_path, capsys, monkeypatch,
                                                                           command, name, option, blocker):
    _no_work(monkeypatch)
    out = tmp_path / "out"
    out.mkdir()
    if blocker == "folder":
        (out / name).mkdir()
    else:
        _fifo(out / name)
    err = _one_line_exit_2(capsys, [*command, "--out", str(out), "--jobs", "1"], option)
    assert name in err
    assert sorted(p.name for p in out.iterdir()) == [name]  # nothing started: no .partial, no other file


@pytest.mark.parametrize("function, name", [("stress", "stress.json"), ("figures", "fig06.png"),
                                            ("bench", "settle_targets.md")])
def test_library_writers_check_their_files_before_work(tmp_path, monkeypatch, function, name):
    """run_stress, make_figures and run_bench refuse a folder at one of their result names, naming out_dir."""
    from simgrip.figures import make_figures
    from simgrip.harness.bench import run_bench
    from simgrip.harness.stress import run_stress

    _no_work(monkeypatch)
    (tmp_path / name).mkdir()
    call = {"stress": lambda: run_stress(tmp_path, cases=1, jobs=1, progress=False),
            "figures": lambda: make_figures(tmp_path, which=[6], jobs=1, progress=False),
            "bench": lambda: run_bench(tmp_path, quick=True, jobs=1, progress=False)}[function]
    with pytest.raises(ValueError, match=f"out_dir: .*{name}' is a folder"):
        call()
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_sweep_no_map_does_not_check_map_png(tmp_path, monkeypatch):
    """Only files the command will write are checked: with --no-map a folder named map.png is not in the way."""
    from simgrip.sweep.grid import make_grid
    from simgrip.sweep.run import run_sweep

    _no_work(monkeypatch)
    out = tmp_path / "out"
    (out / "map.png").mkdir(parents=True)
    with pytest.raises(RuntimeError, match="work started"):  # past the checks, into the (disabled) work
        run_sweep(make_grid("I", kappa=["-5"], links=4), out=out, write_map=False)


def test_cli_refusal_is_one_line_exit_2_in_a_fresh_process(tmp_path):
    fifo = _fifo(tmp_path / "f")
    out = subprocess.run([sys.executable, "-m", "simgrip.cli", "render", "--png", str(fifo)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr.strip().splitlines() == [f"simgrip render: error: --png: {str(fifo)!r} is a FIFO (named pipe), "
                                               f"not a regular file; refusing to replace it"]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


# the examples ----------------------------------------------------------------------------------------------------

def _example(name):
    return load_example(name, "_paths")


def test_scripted_pick_refuses_a_fifo_gif_before_the_episodes(tmp_path, capsys, monkeypatch):
    module = _example("scripted_pick")

    def no_work(*args, **kwargs):
        raise AssertionError("episodes ran before the --gif path was checked")

    monkeypatch.setattr(module, "run_episodes", no_work)
    fifo = _fifo(tmp_path / "f")
    with pytest.raises(SystemExit) as exc:
        module.main(["--episodes", "1", "--gif", str(fifo)])
    assert exc.value.code == 2 and "--gif" in capsys.readouterr().err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_train_sb3_refuses_a_folder_at_a_result_name(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    (tmp_path / "sac_curve.csv").mkdir()
    with pytest.raises(SystemExit) as exc:
        module.main(["--algo", "sac", "--steps", "10", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--out" in err and "sac_curve.csv" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sac_curve.csv"]


def test_render_png_alone_writes_only_the_png(tmp_path, render_backend):
    """The issue's ``render --png X`` also dropped pick.gif into the current folder; now only X (real rendering;
    skipped only where conftest's ``render_backend`` finds no GL library at all)."""
    out = subprocess.run([sys.executable, "-m", "simgrip.cli", "render", "--png", "x.png"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["x.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.png"]
    assert (tmp_path / "x.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
