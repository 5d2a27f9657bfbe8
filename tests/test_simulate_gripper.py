"""simgrip.gripper (simulate_gripper, gripper_record) and ``simgrip simulate --fingers K --workpiece SHAPE``."""

from __future__ import annotations

import json
import math

import pytest

from simgrip import STANDARD, Uniform
from simgrip.cli import main
from simgrip.gripper import gripper_record, simulate_gripper


@pytest.mark.parametrize("options, method, contact", [
    ([], "symmetric", "point"),  # the default, auto: the symmetry skip where the scene is exactly symmetric
    (["--method", "auto", "--contact", "surface"], "symmetric", "surface"),
    (["--method", "dynamics"], "dynamics", "surface"),
])
def test_record_has_the_planar_fields_and_one_record_per_finger(capsys, options, method, contact):
    assert main(["simulate", "I", "--kappa", "-6", "--links", "12", "--json", "--fingers", "3",
                 "--workpiece", "cylinder"] + options) == 0
    rec = json.loads(capsys.readouterr().out)
    planar = {"source", "grip", "links", "tip", "normal_force", "friction_force", "required_mu", "feasible",
              "min_eigenvalue", "N1", "N2", "held", "wall_time_s", "steps", "penetration", "residual", "converged",
              "method", "params"}
    assert planar <= set(rec)
    assert rec["held"] and rec["feasible"] and rec["workpiece"] == "cylinder"
    assert rec["method"] == method and rec["contact"] == contact
    assert len(rec["fingers"]) == 3
    first = rec["fingers"][0]
    # the top level is finger 0
    for key in ("normal_force", "friction_force", "N1", "N2", "tip", "required_mu"):
        assert rec[key] == first[key]
    for f in rec["fingers"]:
        assert set(f) >= {"normal_force", "friction_force", "tip", "contact"}
        assert f["normal_force"] == pytest.approx(first["normal_force"], abs=1e-9)  # symmetric grip
    # the weight K M is carried: the friction forces on the rods sum to -K M
    # (within the settle's residual, which bounds that balance's error, and the round-off of a sum of forces ~15: the
    # error can equal the residual to the last bits)
    assert sum(f["friction_force"] for f in rec["fingers"]) == pytest.approx(-3 * STANDARD.M,
                                                                             abs=rec["residual"] + 1e-12)
    assert rec["min_eigenvalue"] > 0


@pytest.mark.parametrize("method", [None, "dynamics"])
def test_the_python_path_is_the_cli_path(method):
    st = simulate_gripper("II", STANDARD, Uniform(5.0), 12, fingers=4, workpiece="box",
                          **({} if method is None else {"method": method}))
    rec = gripper_record(st, STANDARD)
    assert rec["min_eigenvalue"] is None and len(rec["fingers"]) == 4 and rec["held"]
    assert rec["N1"] == st.records[0].N1 and rec["fingers"][3]["N1"] == st.records[3].N1
    assert rec["method"] == (method or "symmetric")


@pytest.mark.parametrize("method", ["auto", "dynamics"])
def test_dropped_workpiece_keeps_one_record_per_finger(method):
    st = simulate_gripper("I", STANDARD.replace(mu_s=0.3), Uniform(-6.0), 12, fingers=3, workpiece="cylinder",
                          method=method)
    rec = gripper_record(st, STANDARD.replace(mu_s=0.3), Uniform(-6.0))
    assert not rec["held"] and not rec["feasible"] and len(rec["fingers"]) == 3
    assert all(f["normal_force"] == 0.0 and f["contact"] is None for f in rec["fingers"])
    assert rec["min_eigenvalue"] > 0  # the free finger's


@pytest.mark.parametrize("args, name", [
    (["--fingers", "3", "--workpiece", "box"], "fingers"),
    (["--fingers", "1"], "fingers"),
    (["--fingers", "3", "--workpiece", "cone"], "workpiece"),
    (["--workpiece", "sphere"], "fingers"),
    (["--contact-angle", "0.1"], "fingers"),
    (["--fingers", "3", "--method", "newton"], "method"),
    (["--fingers", "3", "--method", "fast"], "method"),
    (["--fingers", "3", "--offset", "0.01", "0", "--method", "symmetric"], "method"),  # not exactly symmetric
    (["--fingers", "3", "--target-error", "1e-3"], "method"),
    (["--fingers", "3", "--method", "dynamics", "--contact", "point"], "contact"),  # MuJoCo's surface contact only
    (["--fingers", "3", "--offset", "0.01", "0", "--contact", "point"], "contact"),  # auto falls to the dynamics
    (["--fingers", "3", "--contact", "centre"], "contact"),
    (["--fingers", "3", "--workpiece", "sphere", "--contact", "surface"], "contact"),  # the sphere's skip: point
    (["--fingers", "3", "--contact-angle", "10"], "contact_angle"),  # a cylinder's surface is vertical
    (["--fingers", "3", "--workpiece", "sphere", "--contact-angle", "90"], "contact_angle"),  # degrees
    (["--fingers", "3", "--workpiece", "sphere", "--contact-angle", "nan"], "contact_angle"),
])
def test_bad_gripper_options_exit_2_naming_them(capsys, args, name):
    assert main(["simulate", "I", "--kappa", "-6", "--links", "8"] + args) == 2
    err = capsys.readouterr().err
    assert name in err and "Traceback" not in err


def test_grip_iii_with_fingers_is_refused(capsys):  # but for a box with K = 4 (the cradle: tests/test_gripper_cradle)
    assert main(["simulate", "III", "--kappa", "-6", "--links", "8", "--fingers", "3", "--workpiece", "cylinder"]) == 2
    assert "workpiece" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["auto", "dynamics"])
def test_sphere_contact_angle_from_the_command_line(capsys, method):
    # --contact-angle in degrees, as --workpiece-yaw; the record's angles in radians (as the library's)
    assert main(["simulate", "I", "--kappa", "-6", "--links", "12", "--json", "--fingers", "3",
                 "--workpiece", "sphere", "--contact-angle", "-11.5", "--method", method]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["held"] and len(rec["fingers"]) == 3
    assert rec["method"] == ("symmetric" if method == "auto" else "dynamics")
    assert all(abs(f["contact_angle"] - math.radians(-11.5)) < 1e-3 for f in rec["fingers"])
