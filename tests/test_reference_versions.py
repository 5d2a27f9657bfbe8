"""``tests/reference_versions.py``'s choice of digest set: :func:`which_host` names the set equal to a replay's
digests whole, and no set when one digest or one key differs."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from reference_versions import host_digests, host_sets, which_host  # noqa: E402

DATA = Path(__file__).parent / "data" / "env_step_reference.npz"


def test_which_host_names_the_set_equal_whole():
    sets = host_sets(DATA)
    assert len(sets) >= 2  # the reference and at least one other host's set (what the choice is for)
    for path, (_, digests) in zip(sets, host_digests(DATA)):
        got = {k: v.copy() for k, v in digests.items()}
        assert which_host(DATA, got) == path
        key = sorted(got)[-1]
        got[key][-1] ^= np.uint64(1)  # one bit of one step's digest
        assert which_host(DATA, got) is None
        del got[key]
        assert which_host(DATA, got) is None
