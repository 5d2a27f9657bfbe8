"""PartialStore holds each saved batch file in a few integers, and merges every one of them in grid order.

A sweep's client keeps one byte per point (``done``) and, per batch file it
wrote, the file's first and last point and its name's id: 24 bytes in three
arrays (plus their over-allocation, at most an eighth), where a tuple with a
``Path`` took ~460 bytes (a 10^6-point sweep writes ~10^4 files: ~5 MB).
Files of an older version (``batch-START-ID.csv``, no end in the name) are
kept by path and merged too.
"""

from __future__ import annotations

import gc
import tracemalloc

from simgrip.sweep.grid import make_grid
from simgrip.sweep.point import COLUMNS
from simgrip.sweep.store import PartialStore, iter_csv

#: bytes per batch file held: a quarter of the tuple-with-Path's ~460, far above the arrays' 24 (+1/8)
MAX_BYTES_PER_FILE = 115
FILES = 240


def _record(grid, i):
    rec = {c: None for c in COLUMNS}
    rec.update(grid.point(i).values(), index=i, status="settled", held=True, feasible=True, valid=True,
               normal_force=1.0 + i, wall_time_s=1e-3, point_time_s=2e-3, message="", bvp_message="", bvp_warning="")
    return rec


def test_batch_files_are_held_in_a_few_bytes_and_merged_in_order(tmp_path):
    grid = make_grid("I", kappa=(-7, -3, FILES), links=8, reference="none")
    store = PartialStore(tmp_path, grid)
    store.open(False)
    order = list(range(0, FILES, 2)) + list(range(1, FILES, 2))  # out of grid order, as results arrive
    held = {}
    tracemalloc.start()
    try:
        for k, i in enumerate(order):
            store.buffer = [_record(grid, i)]
            store.flush()  # one file per point
            if k + 1 in (FILES // 4, FILES):
                gc.collect()
                held[k + 1] = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    per_file = (held[FILES] - held[FILES // 4]) / (FILES - FILES // 4)
    assert per_file < MAX_BYTES_PER_FILE, f"{per_file:.0f} B held per batch file"
    assert len(store.batches) == FILES and all(path.is_file() for _, _, path in store.batches)

    # an older version's file (no end in its name) is taken over by path and merged in its place
    first, last, path = next(b for b in store.batches if b[0] == 7)
    path.rename(path.with_name(f"batch-{first:09d}-{path.stem.rsplit('-', 1)[1]}.csv"))
    again = PartialStore(tmp_path, grid)
    assert again.open(True) == FILES
    counts = again.merge(tmp_path / "sweep.csv")
    rows = list(iter_csv(tmp_path / "sweep.csv"))
    assert counts["points"] == FILES and [r["normal_force"] for r in rows] == [1.0 + i for i in range(FILES)]
