"""The installed package finds its MJCF parts and environments without the source tree."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """Build a wheel from the source tree and unpack it into an isolated target dir."""
    tmp = tmp_path_factory.mktemp("wheel")
    wheel_dir, site, src = tmp / "dist", tmp / "site", tmp / "src"
    # from a copy without build outputs: setuptools reuses a checkout's build/lib, whose stale files would ship
    # (and hide a package missing from pyproject's list, as a clean clone would not)
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns("build", "dist", "*.egg-info", "__pycache__", ".git",
                                                             ".hypothesis", ".pytest_cache"))
    pip = [sys.executable, "-m", "pip", "-q", "--disable-pip-version-check"]
    subprocess.run(pip + ["wheel", "--no-deps", "--no-build-isolation", "-w", str(wheel_dir), str(src)], check=True)
    (wheel,) = wheel_dir.glob("simgrip-*.whl")
    subprocess.run(pip + ["install", "--no-deps", "--target", str(site), str(wheel)], check=True)
    return site


def test_wheel_ships_models_and_envs(installed, tmp_path):
    code = textwrap.dedent(
        """
        import simgrip, simgrip.models, simgrip.envs, mujoco
        from pathlib import Path
        site = Path(r"%s").resolve()
        assert Path(simgrip.__file__).resolve().is_relative_to(site), simgrip.__file__
        names = simgrip.models.available()
        assert names, "no MJCF parts shipped"
        for name in names:
            path = simgrip.models.model_path(name)
            assert path.resolve().is_relative_to(site), path
            mujoco.MjSpec.from_file(str(path))
        print(len(names))
        """
        % installed
    )
    env = dict(os.environ, PYTHONPATH=str(installed))
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout.strip()) >= 1


def test_wheel_ships_every_module_of_the_source_tree(installed):
    """Every .py file of simgrip/, envs/ and models/ is in the wheel (a subpackage missing from pyproject's
    ``packages`` list installs without error and fails only at import, on the user's machine)."""
    site = Path(installed)
    trees = {"simgrip": ROOT / "simgrip", "simgrip/envs": ROOT / "envs", "simgrip/models": ROOT / "models"}
    missing = []
    for dest, src in trees.items():
        for f in src.rglob("*.py"):
            rel = f.relative_to(src)
            if "__pycache__" in rel.parts or (dest == "simgrip" and rel.parts[0] in ("envs", "models")):
                continue
            if not (site / dest / rel).is_file():
                missing.append(f"{dest}/{rel}")
    assert not missing, f"not in the wheel (add the package to pyproject's [tool.setuptools] packages): {missing}"
