"""Tests of the human-readable tables of simgrip.report (format_comparison, format_table).

The records are literal copies of ``simgrip compare ... --json`` output (their
shape is what is under test, not the physics).
"""

from __future__ import annotations

import copy
import re

from simgrip.report import format_comparison, format_table

_PARAMS = {"D": 1.0, "M": 5.0, "b": 0.6, "mu_s": 1.0, "gamma": 0.8}
GRIP_I = {
    "simulation": {
        "source": "simulation", "grip": "I", "links": 32, "tip": [0.29999899946739245, -0.6754937473757363],
        "normal_force": 6.651604374018464, "friction_force": -5.0, "required_mu": 0.7516983450684886,
        "feasible": True, "min_eigenvalue": 23.9791820488417, "N1": 6.651604374018464, "N2": -5.0, "held": True,
        "wall_time_s": 0.8184316750002836, "steps": 2, "penetration": 1.0005326074851578e-06,
        "residual": 1.1708873870475145e-09, "converged": True, "method": "newton", "warnings": [],
        "extrapolated": False, "error_estimate": None, "params": _PARAMS, "contact_moment": 8.881784197001252e-16,
        "profile": "Uniform(kappa=-5.5)",
    },
    "reference": {
        "source": "elastica", "grip": "I", "tip": [0.3, -0.6749248604397347], "normal_force": 6.655968266443494,
        "friction_force": -5.0, "required_mu": 0.7512055045706622, "feasible": True, "min_eigenvalue": None,
        "N1": 6.655968266443494, "N2": -5.0, "residual": 9.99433258909144e-09, "success": True, "params": _PARAMS,
        "profile": "Uniform(kappa=-5.5)",
    },
    "difference": {"tip": [-1.0005326075424037e-06, -0.0005688869360016557]},
}


def _grip_iii():
    r = copy.deepcopy(GRIP_I)
    for side in ("simulation", "reference"):
        r[side].update(grip="III", contact=[0.3, -0.5627], gamma=0.8, n=7.9, f=-1.66, N1=6.3379, N2=-5.0)
    r["reference"]["tip_clear"] = True
    return r


def _rows(text):
    return {line.split("  ")[0].strip(): line for line in text.splitlines()[2:]}


def test_comparison_reads_well():
    text = format_comparison(GRIP_I)
    lines = text.splitlines()
    assert lines[0].startswith("Grip I, Uniform(kappa=-5.5), D=1, M=5, b=0.6, mu_s=1") and "32 links" in lines[0]
    assert "None" not in text and "[]" not in text
    rows = _rows(text)
    # physical quantities first, in this order; diagnostics on the footer lines only
    labels = [line.split("  ")[0].strip() for line in lines[2:] if ":" not in line.split("  ")[0]]
    assert labels == ["tip x", "tip y", "normal force", "friction force", "required mu", "feasible", "held",
                      "min eigenvalue"]
    assert "N1" not in rows and "N2" not in rows  # Grips I/II: they are the normal and friction forces
    assert re.search(r"normal force\s+6\.6516\s+6\.6560\s+-0\.0044 \(-0\.066 %\)", text)
    assert re.search(r"min eigenvalue\s+23\.979\s+-$", text, re.M)
    footer = [line for line in lines if line.startswith("simulation:")]
    assert len(footer) == 1
    for word in ("steps 2", "method newton", "time 0.82 s", "contact moment 8.9e-16", "warnings none"):
        assert word in footer[0]
    assert "error estimate" not in text  # a None diagnostic is left out, not printed as a cell
    for key in ("steps", "method", "penetration", "converged", "extrapolated"):
        assert not any(line.startswith(key) for line in lines)


def test_comparison_of_grip_iii_has_contact_and_components():
    rows = _rows(format_comparison(_grip_iii()))
    for label in ("contact x", "contact y", "gamma", "N1", "N2", "tip clear"):
        assert label in rows
    assert re.search(r"tip clear\s+-\s+yes", rows["tip clear"])


def test_comparison_shows_warnings_and_unbounded_mu():
    r = copy.deepcopy(GRIP_I)
    r["simulation"]["warnings"] = ["settled as Grip II"]
    r["reference"]["required_mu"] = float("inf")
    text = format_comparison(r)
    assert "WARNING: settled as Grip II" in text and "warnings 1" in text
    assert re.search(r"required mu\s+0\.75170\s+unbounded\s*$", text, re.M)


def test_table_has_five_digits_and_dashes():
    rec = dict(GRIP_I["reference"])
    text = format_table(rec)
    assert "normal_force    6.656\n" in text and "None" not in text
    assert re.search(r"min_eigenvalue\s+-$", text, re.M)
    assert "params          D=1, M=5, b=0.6, mu_s=1, gamma=0.8" in text


def test_table_prints_warnings_as_lines_after_it():
    rec = {"source": "simulation", "grip": "I", "feasible": False, "warnings": ["one thing", "another"]}
    lines = format_table(rec).splitlines()
    assert lines[-2:] == ["WARNING: one thing", "WARNING: another"]
    assert not any(line.startswith("warnings") for line in lines)


def test_solve_reports_a_rod_through_itself_as_no_grip():
    """``simgrip solve``'s record gets the reference's validity as ``compare`` gives it: this BVP branch
    (kappa_bar -6.5, D 3, M 12, b 0.3, mu 2; found by an audit with its own shooting solver) crosses itself and
    enters the box, and was printed ``feasible: True`` with no ``valid``."""
    from simgrip.params import DimensionlessParams
    from simgrip.profiles import Uniform
    from simgrip.report import solve_record

    bad = solve_record("I", DimensionlessParams(D=3.0, M=12.0, b=0.3, mu_s=2.0, gamma=0.8), Uniform(-6.5), K=32)
    assert bad["valid"] is False and bad["feasible"] is False
    assert any("crosses itself" in w for w in bad["warnings"])
    good = solve_record("I", DimensionlessParams(D=1.0, M=5.0, b=0.6, mu_s=1.0, gamma=0.8), Uniform(-5.5), K=32)
    assert good["valid"] is True and good["feasible"] is True and "warnings" not in good
