"""simgrip sweep --contact point|surface|full [--box-depth D]: the contact recorded, refused on --resume if
different; a full-contact sweep has no per-point BVP (reference 'none')."""

from __future__ import annotations

import json

import pytest

from simgrip.cli import main
from simgrip.parallel.runner import RunnerOptions
from simgrip.sweep.grid import make_grid
from simgrip.sweep.store import PARTIAL, read_csv

ONE = RunnerOptions(jobs=1, progress=False)


def test_default_contact_is_the_methods_own():
    """No --contact: the spec and the points are those of a sweep before the option (old sweeps resume, the
    points settle exactly as before); an explicit method default is the same sweep."""
    g = make_grid("I", kappa=-5, links=8)
    assert g.contact == "point" and "contact" not in g.spec() and g.reference == "bvp"
    assert next(g.points()).settle_options() == {}
    assert make_grid("I", kappa=-5, links=8, contact="point").spec() == g.spec()
    d = make_grid("I", kappa=-5, links=8, method="dynamics")
    assert d.contact == "surface" and "contact" not in d.spec()
    s = make_grid("I", kappa=-5, links=8, contact="surface")
    assert s.spec()["contact"] == "surface" and s.point(0).settle_options() == {"contact": "surface"}


def test_full_contact_grid():
    g = make_grid("II", kappa=9, links=8, contact="full", box_depth=0.4, reference=None)
    assert g.reference == "none" and g.spec()["contact"] == "full" and g.spec()["box_depth"] == 0.4
    assert g.point(0).settle_options() == {"contact": "full", "box_depth": 0.4}
    for kw, name in [(dict(contact="line"), "contact"), (dict(contact="full", grip="III"), "contact"),
                     (dict(contact="full", reference="bvp"), "reference"),
                     (dict(contact="full", box_depth=1.5), "box_depth"), (dict(box_depth=0.4), "box_depth"),
                     (dict(contact="point", method="dynamics"), "contact")]:
        grip = kw.pop("grip", "I")
        kw.setdefault("reference", None)
        with pytest.raises(ValueError, match=name):
            make_grid(grip, kappa=-9, links=8, **kw)


@pytest.fixture(scope="module")
def full_sweep(tmp_path_factory):
    """Grip I past the onset (-8.27 at the standard case), 2 points at n = 8, every link touching."""
    out = tmp_path_factory.mktemp("full") / "s"
    rc = main(["sweep", "I", "--kappa", "-10", "-9.5", "2", "--links", "8", "--contact", "full", "--out",
               str(out), "--jobs", "1", "--no-map", "--no-progress"])
    assert rc == 0
    return out


def test_full_contact_sweep_rows_and_record(full_sweep):
    meta = json.loads((full_sweep / "sweep.json").read_text())
    assert meta["arguments"]["contact"] == "full" and meta["arguments"]["reference"] == "none"
    rows = read_csv(full_sweep / "sweep.csv")
    assert len(rows) == 2
    for r in rows:
        assert r["status"] == "settled" and r["valid"] is True
        assert r["penetration"] <= 1e-3  # the bound over l (the settle restarts above 1e-4 l)
        assert r["bvp_normal_force"] is None and r["agree"] is None  # no point-contact BVP beside full contact
        assert r["normal_force"] > 0


def test_resume_refuses_another_contact(full_sweep, capsys):
    base = ["sweep", "I", "--kappa", "-10", "-9.5", "2", "--links", "8", "--out", str(full_sweep), "--jobs", "1",
            "--no-map", "--no-progress", "--resume"]
    assert main(base + ["--contact", "full"]) == 0  # the same sweep: nothing computed
    capsys.readouterr()
    for extra in ([], ["--contact", "point"], ["--contact", "full", "--box-depth", "0.4"]):
        assert main(base + extra) == 2
        assert "different grid" in capsys.readouterr().err


def test_resume_of_a_partial_sweep_refuses_another_contact(tmp_path, capsys):
    out = tmp_path / "p"
    (out / PARTIAL).mkdir(parents=True)
    point = make_grid("I", kappa=-10, links=8)
    (out / PARTIAL / "spec.json").write_text(json.dumps(point.spec()))
    rc = main(["sweep", "I", "--kappa", "-10", "--links", "8", "--contact", "full", "--out", str(out), "--jobs",
               "1", "--no-map", "--no-progress", "--resume"])
    err = capsys.readouterr().err
    assert rc == 2 and "different sweep" in err and "Traceback" not in err, err


@pytest.mark.parametrize("args, words", [
    (["--contact", "line"], "--contact"),
    (["--contact", "full", "--box-depth", "0"], "--box-depth"),
    (["--box-depth", "0.4"], "--box-depth"),
    (["--contact", "full", "--reference", "bvp"], "--reference"),
])
def test_cli_bad_contact_exit_2(tmp_path, capsys, args, words):
    out = tmp_path / "o"
    rc = main(["sweep", "I", "--kappa", "-10", "--links", "8", *args, "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and words in err and "Traceback" not in err, err
    assert not (out / "sweep.csv").exists()
