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
