"""Results files are written whole or not at all."""

import json

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


def test_check_output_dir_refuses_a_read_only_folder(tmp_path):
    import os

    from simgrip.io import check_output_dir

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if os.access(ro, os.W_OK) and os.geteuid() == 0:
            pytest.skip("root writes into read-only folders")
        with pytest.raises(ValueError, match="--out.*not writable"):
            check_output_dir(ro / "sub")
    finally:
        ro.chmod(0o700)


def test_check_output_file_names_the_option(tmp_path):
    from simgrip.io import check_output_file

    assert check_output_file(tmp_path / "x" / "g.png", "--png") == tmp_path / "x" / "g.png"
    with pytest.raises(ValueError, match="--png.*folder"):
        check_output_file(tmp_path, "--png")
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="--gif"):
        check_output_file(tmp_path / "f" / "p.gif", "--gif")
