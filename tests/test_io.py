"""Results files are written whole or not at all."""

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from simgrip.io import atomic_write, to_jsonable, write_json


def test_write_json_round_trip(tmp_path):
    path = tmp_path / "sub" / "r.json"
    write_json(path, {"tip": np.array([0.3, -0.2]), "n": np.int64(3), "bad": float("nan"), "ok": np.bool_(True)})
    assert json.loads(path.read_text()) == {"tip": [0.3, -0.2], "n": 3, "bad": None, "ok": True}
    assert [p.name for p in path.parent.iterdir()] == ["r.json"]


def test_interrupted_write_leaves_old_file_untouched(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_write(path) as fh:
            fh.write("half a result")
            raise RuntimeError("crash mid-write")
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["r.txt"]


def test_to_jsonable_nested():
    assert to_jsonable({"a": (np.float32(1.5), [np.inf])}) == {"a": [1.5, [None]]}


def test_results_files_get_ordinary_permissions(tmp_path):
    import os

    path = tmp_path / "r.json"
    write_json(path, {"a": 1})
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_check_output_dir(tmp_path):
    from simgrip.io import check_output_dir

    assert check_output_dir(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert (tmp_path / "a" / "b").is_dir() and list((tmp_path / "a" / "b").iterdir()) == []
    (tmp_path / "f").write_text("x")
    for bad in (tmp_path / "f", tmp_path / "f" / "sub"):
        with pytest.raises(ValueError, match="--out"):
            check_output_dir(bad)
    with pytest.raises(ValueError, match="out_dir"):
        check_output_dir(tmp_path / "f", option="out_dir")


def test_check_output_dir_leaves_no_probe_file(tmp_path):
    from simgrip.io import check_output_dir

    assert check_output_dir(tmp_path) == tmp_path
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("make", ["file", "under_file", "empty"])
def test_check_output_dir_names_the_option(tmp_path, make):
    from simgrip.io import check_output_dir

    f = tmp_path / "f"
    f.write_text("x")
    path = {"file": f, "under_file": f / "sub", "empty": ""}[make]
    with pytest.raises(ValueError, match="--where"):
        check_output_dir(path, "--where")


def _refusal_in_a_read_only_folder(folder):
    """The message of ``check_output_dir(folder / "sub")`` with ``folder`` read-only (mode 0o555), or None if it
    passes.  As root (CI) it runs in a forked child that drops to the ``nobody`` user (65534), so the
    file system's own refusal is tested there too (root writes into read-only folders)."""
    import os

    from simgrip.io import check_output_dir

    folder.chmod(0o555)
    if os.geteuid() != 0:
        try:
            check_output_dir(folder / "sub")
        except ValueError as exc:
            return str(exc)
        return None
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: no pytest machinery, only os._exit
        code = 0
        try:
            os.close(r)
            os.setgid(65534)
            os.setuid(65534)
            try:
                check_output_dir(folder / "sub")
                msg = ""
            except ValueError as exc:
                msg = str(exc)
            os.write(w, msg.encode())
        except BaseException:
            code = 1
        os._exit(code)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        msg = f.read().decode()
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    return msg or None


def test_check_output_dir_refuses_a_read_only_folder(tmp_path):
    import os
    import tempfile

    # a folder the nobody user can reach (pytest's tmp_path is 0700 for its owner)
    base = Path(tempfile.mkdtemp(prefix="simgrip-ro-"))
    try:
        base.chmod(0o755)
        ro = base / "ro"
        ro.mkdir()
        msg = _refusal_in_a_read_only_folder(ro)
        assert msg is not None and re.match(r"--out: cannot write results to .*ro/sub.*\(Permission denied\)", msg), msg
        assert not (ro / "sub").exists()
    finally:
        os.chmod(base / "ro", 0o700)
        shutil.rmtree(base)


def test_check_output_file_names_the_option(tmp_path):
    from simgrip.io import check_output_file

    assert check_output_file(tmp_path / "x" / "g.png", "--png") == tmp_path / "x" / "g.png"
    with pytest.raises(ValueError, match="--png.*folder"):
        check_output_file(tmp_path, "--png")
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="--gif"):
        check_output_file(tmp_path / "f" / "p.gif", "--gif")
