"""simgrip.envs.baselines: one member of a grid run alone (``--member``), as it runs in the grid."""

import json
import subprocess
import sys

import pytest

from simgrip.envs.baselines import evaluate

PINCH = "simgrip/PickFragile-v7"
SEEDS = [7300, 7301]


def test_a_member_alone_is_its_row_of_the_grid():
    grid = evaluate(PINCH, "openloop", SEEDS, grid="coarse")
    assert len(grid["members"]) > 1
    for row in (grid["members"][0], grid["members"][-1]):
        params = {k: v for k, v in row.items() if k not in ("success_rate", "outcomes")}
        alone = evaluate(PINCH, "openloop", SEEDS, grid="coarse", member=params)
        assert alone["member"] == params and "members" not in alone
        assert (alone["success_rate"], alone["outcomes"]) == (row["success_rate"], row["outcomes"])


@pytest.mark.parametrize("member, needle", [
    ({"kappa": 0.3}, "must name this grid's parameters"),
    ({"kappa": 0.35, "ramp_steps": 50, "palm": 0.5}, "is not a member"),
    ({"kappa": 0.3, "ramp_steps": 50, "palm": 0.5, "speed": 1}, "must name this grid's parameters"),
])
def test_a_member_not_in_the_grid_is_refused(member, needle):
    with pytest.raises(ValueError, match=needle):
        evaluate(PINCH, "openloop", SEEDS, member=member)


def test_cli_refuses_a_bad_member_in_one_line():
    r = subprocess.run([sys.executable, "-m", "simgrip.envs.baselines", "--env", PINCH, "--policy", "openloop",
                        "--seeds", "7300-7301", "--member", json.dumps({"kappa": 0.35, "ramp_steps": 50, "palm": 0.5})],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "--member" in r.stderr and "Traceback" not in r.stderr and r.stdout == ""
