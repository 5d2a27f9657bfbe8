"""Messages name what the user gave (issue 16, section 8): the parameter typed, its value as typed, never an
internal quantity or a NumPy repr; compare takes simulate's K-finger options; the stress map counts as stress.json."""

from __future__ import annotations

import json
import math
import re

import pytest

from simgrip import STANDARD, Uniform
from simgrip.cli import main


def _error(capsys, argv) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_grip_iii_gamma_inside_half_the_box_names_gamma(capsys):
    """``simulate III --gamma 0.001`` named ``b``; the rule is gamma > b/2, as the BVP's solve says."""
    for cmd in ("simulate", "compare", "solve"):
        line = _error(capsys, [cmd, "III", "--kappa", "-6", "--gamma", "0.001"])
        assert line.startswith(f"simgrip {cmd}: error: gamma = 0.001 must exceed b/2 = 0.3 for Grip III"), line
    from simgrip.compare import simulate

    with pytest.raises(ValueError, match=r"^gamma = 0\.3 must exceed b/2"):
        simulate("III", STANDARD.replace(gamma=0.3), Uniform(-6.0), 8)


def test_a_contact_angle_beyond_the_tip_names_contact_angle(capsys):
    """``--contact-angle -89.9`` said "got b = 0.0010472", a width the user never set."""
    line = _error(capsys, ["simulate", "I", "--kappa", "-6", "--fingers", "3", "--workpiece", "sphere",
                           "--contact-angle", "-89.9"])
    assert "error: contact_angle: at -1.56905 rad (-89.9 deg)" in line and "got b" not in line
    limit = math.degrees(math.acos(2 * 0.002 / 0.6))  # (b/2) cos(beta) must exceed r_tip = 0.002
    assert f"({limit:.6g} deg)" in line


def test_the_box_offset_error_prints_plain_numbers(capsys):
    line = _error(capsys, ["simulate", "I", "--kappa", "-6", "--fingers", "4", "--workpiece", "box",
                           "--offset", "0.298", "0"])
    assert "np.float64" not in line and "half sizes (0.298, 0.298) l" in line and "got (0.298, 0)" in line


def test_compare_takes_the_k_finger_options_of_simulate(capsys):
    """The README says compare takes simulate's options: ``--fingers 3`` was "unrecognized arguments"."""
    argv = ["I", "--kappa", "-6", "--fingers", "3", "--links", "8", "--json"]
    assert main(["compare", *argv]) == 0
    cmp = json.loads(capsys.readouterr().out)
    assert main(["simulate", *argv]) == 0
    sim = json.loads(capsys.readouterr().out)
    assert cmp["simulation"]["normal_force"] == sim["normal_force"]
    from simgrip.reference import elastica

    n_ref = elastica.solve("I", STANDARD, Uniform(-6.0), contact_moment=sim["fingers"][0]["contact_moment"]).normal_force
    assert cmp["reference"]["normal_force"] == pytest.approx(n_ref, rel=1e-12)
    assert len(cmp["fingers"]) == 3
    for f, rec in zip(cmp["fingers"], sim["fingers"]):
        assert f["relative_difference"] == pytest.approx((rec["normal_force"] - n_ref) / n_ref, rel=1e-12)
    assert main(["compare", *argv[:-1]]) == 0  # the table: one line per finger
    out = capsys.readouterr().out
    assert len(re.findall(r"^finger \d: N ", out, flags=re.M)) == 3


@pytest.mark.parametrize("extra, name", [
    (["--offset", "0.1", "0"], "offset"), (["--workpiece-yaw", "10"], "offset"),
    (["--kappa-per-finger", "-6", "-5", "-6"], "kappa_per_finger"),
    (["--workpiece", "sphere", "--contact-angle", "20"], "contact_angle"),
])
def test_compare_refuses_k_finger_scenes_without_one_planar_reference(capsys, extra, name):
    argv = ["compare", "I", "--fingers", "3", "--links", "8", *extra]
    if name != "kappa_per_finger":
        argv += ["--kappa", "-6"]
    line = _error(capsys, argv)
    assert line.startswith(f"simgrip compare: error: {name}:"), line


def test_the_stability_map_counts_flagged_states_as_stress_json_does():
    """The map said "flagged (1)" where stress.json counted 4: a dropped, flagged state was drawn as dropped."""
    from simgrip.harness.stress import _category, _counts

    base = {"outcome": "settled", "grip": "I", "steps": 3}
    cases = [
        {**base, "held": False, "flags": {"self_intersection": True}},
        {**base, "held": True, "flags": {"self_intersection": True, "beyond_full_turn": True}},
        {**base, "held": False, "flags": {"self_intersection": False}},
        {**base, "held": True, "flags": {}},
        {**base, "grip": "free", "held": None, "flags": {"beyond_full_turn": True}},
    ]
    assert sum(_category(c) == "flagged" for c in cases) == _counts(cases)["flagged"] == 3
    assert [_category(c) for c in cases] == ["flagged", "flagged", "dropped", "easy", "flagged"]


def test_sweeps_timing_run_is_throughput_not_profile(capsys, tmp_path):
    """``--profile`` was a curvature profile in solve and a timing run in sweep: the sweep's is ``--throughput``."""
    assert main(["sweep", "I", "--kappa", "-7", "-3", "3", "--links", "8", "--out", str(tmp_path / "o"),
                 "--profile"]) == 2
    assert "sweep has no --profile: the points/s measurement is --throughput" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    from simgrip.cli import build_parser

    args = build_parser().parse_args(["sweep", "I", "--kappa", "-7", "--links", "8", "--out", "o", "--throughput"])
    assert args.throughput is True
