"""Checks shared by the reduced-recording writers (:mod:`floorscan.select.recording`):
the recording still holds the scans ingest numbered, with the stamps it recorded; the
size of what was read and written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from floorscan.core.io import InputError


def size_of(path: Path) -> int:
    """Bytes of a file, or of every file under a folder."""
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def check_count(source: Path, n: int, ids: np.ndarray, t_ns: np.ndarray | None, what: str) -> None:
    """Check that the recording still holds the scans ingest numbered.

    Raises
    ------
    InputError
        When it holds another number of scans (``n``, of ``what``) than the scan index
        (``t_ns``), or fewer than the largest selected ``ids``.
    """
    if t_ns is not None and n != len(t_ns):
        raise InputError(
            f"{source}: holds {n} {what}, the scan index {len(t_ns)}; expected the recording ingest read "
            "(it changed since ingest: rerun ingest)"
        )
    if ids[-1] >= n:
        raise InputError(
            f"{source}: selected scan_id {int(ids[-1])} is not in the recording ({n} {what}, ids 0..{n - 1}); "
            "expected ids of this recording's ingest"
        )


def check_stamps(source: Path, ids: np.ndarray, got: np.ndarray, t_ns: np.ndarray | None) -> None:
    """Check that the selected scans' stamps ``got`` are the scan index's ``t_ns[ids]``.

    Raises
    ------
    InputError
        Naming the first scan whose stamp differs (the recording changed since ingest).
    """
    if t_ns is None:
        return
    bad = np.flatnonzero(got != t_ns[ids])
    if bad.size:
        i = int(ids[bad[0]])
        raise InputError(
            f"{source}: scan {i} is stamped {int(got[bad[0]])} ns, the scan index says {int(t_ns[i])} ns "
            f"({bad.size} of {len(ids)} selected scans differ); expected the recording ingest read "
            "(it changed since ingest: rerun ingest)"
        )
