"""The MuJoCo versions a bit-for-bit reference file holds for (``tests/data/env_*_reference.npz``).

A reference's digests are MuJoCo's physics to the last bit, so each file stores (``mujoco_version``) the
versions under which its replay was seen to give every recorded digest: the one it was recorded with, and each
later one added by ``python tests/test_env_*_reference.py --add-version`` (which replays the whole file under
the installed MuJoCo and adds its version only when nothing differs).  Under any other version the tests skip,
saying so.  A host whose arithmetic gives other last bits for the same actions adds its own digest set beside the
file (``tests/data/<reference>.host<i>.npz``, written by ``python tests/test_env_*_reference.py --add-host`` from
the file's own actions, :func:`add_host`); a replay must equal one set whole, so a change of any env's output fails
on every host.  ``--which-host`` prints the set this host reproduces (:func:`which_host`; the reference itself is
the set of the host it was recorded on).  ``--regenerate`` leaves those sets behind: delete them and add each host
again.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def recorded_versions(ref) -> list[str]:
    """The MuJoCo versions ``ref`` (an open ``.npz``) holds for, oldest first."""
    return [str(v) for v in np.atleast_1d(ref["mujoco_version"])]


def host_sets(path: Path) -> list[Path]:
    """The reference at ``path`` and its other hosts' digest sets beside it (``<stem>.host<i>.npz``), in order."""
    return [path] + sorted(path.parent.glob(f"{path.stem}.host*.npz"))


def host_digests(path: Path) -> list[tuple[list[str], dict]]:
    """Each digest set of the reference at ``path`` (:func:`host_sets`): its MuJoCo versions and its digests
    (``d...`` arrays).  The same recorded actions replayed on another host can give other last bits (its CPU's
    vector instructions, the MuJoCo build's), so a reference may hold one set a host that reproduced it; a replay
    passes when it equals one set whole, so any change of an env's output still fails everywhere."""
    out = []
    for p in host_sets(path):
        with np.load(p) as ref:
            out.append((recorded_versions(ref), {k: ref[k] for k in ref.files if k.startswith("d")}))
    return out


def which_host(path: Path, got: dict) -> Path | None:
    """The digest set of the reference at ``path`` (:func:`host_sets`) that equals this host's digests ``got``
    (replayed from the reference's own actions) whole, or None.  Two hosts that reproduce one set give the same env
    outputs on its actions to the last bit, so a training replayed on one at a record's steps (``--replay``,
    :mod:`simgrip.envs.budget_replay`) can be the record made on the other (the learner's own arithmetic aside)."""
    for p, (_, digests) in zip(host_sets(path), host_digests(path)):
        if digests.keys() == got.keys() and all(np.array_equal(digests[k], got[k]) for k in got):
            return p
    return None


def add_host(path: Path, got: dict) -> Path:  # pragma: no cover - maintenance command
    """Write this host's digests ``got`` (replayed from the reference's own actions) as the next digest set beside
    ``path``, for the installed MuJoCo; unless one set equals them already (then nothing is written)."""
    import mujoco

    if which_host(path, got) is not None:
        raise SystemExit(f"{path.name}: this host reproduces a recorded set already")
    with np.load(path) as ref:
        ids = ref["ids"]
    target = path.with_name(f"{path.stem}.host{len(host_sets(path))}.npz")
    np.savez_compressed(target, mujoco_version=np.array([mujoco.__version__]), ids=ids, **got)
    return target


def installed_sets(path: Path) -> list[dict]:
    """The digest sets of the reference at ``path`` that hold for the installed MuJoCo (:func:`host_digests`);
    ``pytest.skip`` naming the versions recorded when none does."""
    import mujoco

    sets = [digests for versions, digests in host_digests(path) if mujoco.__version__ in versions]
    if not sets:
        with np.load(path) as ref:
            skip_unless_recorded(ref)
    return sets


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


def maintain(script: str, path: Path, argv: list, replay_all, mismatches, record) -> None:  # pragma: no cover
    """The reference scripts' command line (``python tests/<script> [--regenerate | --add-version | --add-host |
    --which-host]``) for the reference at ``path``: ``replay_all(ref)`` gives this host's digests of the open
    reference ``ref``, ``mismatches(ref)`` where they differ from it (a list of messages), ``record()`` records it
    anew (no option, or ``--regenerate``)."""
    if argv not in ([], ["--regenerate"], ["--add-version"], ["--add-host"], ["--which-host"]):
        raise SystemExit(f"usage: python tests/{script} [--regenerate | --add-version | --add-host | --which-host]")
    if argv in ([], ["--regenerate"]):
        record()
        return
    with np.load(path) as ref:  # (closed before any file is written)
        found = mismatches(ref) if argv == ["--add-version"] else None
        got = None if argv == ["--add-version"] else replay_all(ref)
    if argv == ["--add-version"]:
        add_installed_version(path, found)
    elif argv == ["--add-host"]:
        print(add_host(path, got))
    else:  # --which-host: the digest set this host reproduces
        match = which_host(path, got)
        print(match.name if match else "none: this host's digests differ from every recorded set")
