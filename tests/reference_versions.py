"""The MuJoCo versions a bit-for-bit reference file holds for (``tests/data/env_*_reference.npz``).

A reference's digests are MuJoCo's physics to the last bit, so each file stores (``mujoco_version``) the
versions under which its replay was seen to give every recorded digest: the one it was recorded with, and each
later one added by ``python tests/test_env_*_reference.py --add-version`` (which replays the whole file under
the installed MuJoCo and adds its version only when nothing differs).  Under any other version the tests skip,
saying so.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def recorded_versions(ref) -> list[str]:
    """The MuJoCo versions ``ref`` (an open ``.npz``) holds for, oldest first."""
    return [str(v) for v in np.atleast_1d(ref["mujoco_version"])]


def skip_unless_recorded(ref) -> None:
    """``pytest.skip`` unless the installed MuJoCo is one of ``ref``'s versions."""
    import mujoco
    import pytest

    versions = recorded_versions(ref)
    if mujoco.__version__ not in versions:
        pytest.skip(f"reference holds for MuJoCo {', '.join(versions)}; this is {mujoco.__version__} "
                    "(python tests/test_env_*_reference.py --add-version checks it and adds it)")


def add_installed_version(path: Path, mismatches: list[str]) -> None:  # pragma: no cover - maintenance command
    """Add the installed MuJoCo's version to the reference at ``path`` when its replay under it gave
    ``mismatches == []``; otherwise exit naming the first ones (the file untouched)."""
    import mujoco

    if mismatches:
        raise SystemExit(f"MuJoCo {mujoco.__version__} does not reproduce {path.name}: " + "; ".join(mismatches[:5]))
    with np.load(path) as ref:
        arrays = {k: ref[k] for k in ref.files}
        versions = recorded_versions(ref)
    if mujoco.__version__ not in versions:
        versions.append(mujoco.__version__)
    arrays["mujoco_version"] = np.array(versions)
    tmp = path.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(path)
    print(f"{path.name}: holds for MuJoCo {', '.join(versions)}")
