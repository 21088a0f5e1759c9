"""The select stage's files as the later stages read them: which scans.

- :func:`parse_k`, :func:`first_k_scans`: the first k scans of an ordering
  (``orderings/<name>.parquet``: ``rank``, ``scan_id``), for the walls stage's walls of
  the first k scans and the floorplan stage's evaluation grid;
- :func:`curve_ks`: the numbers of scans of the answer's plans of the first k scans
  (the floorplan stage builds them, the score stage scores them: the answer curve);
- :func:`selected_scan_ids`: the selected scans (``selection/scans.parquet``), for the
  map extractor's walls and the recommended plan;
- :func:`read_selection`: ``selection/selection.json``, for the answer and the pages.

The select stage writes them (:mod:`floorscan.select.orderings`,
:mod:`floorscan.select.recommend`).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.core.io import read_table


def parse_k(k: str | int) -> int | None:
    """The ``k`` of the first-k extractor: ``"all"`` -> None, ``"15"`` or 15 -> 15.

    Parameters
    ----------
    k : str or int
        ``"all"`` or a positive integer (as text or int).

    Returns
    -------
    int or None
        None for ``"all"``.

    Raises
    ------
    ValueError
        For anything else or k < 1.
    """
    if str(k) == "all":
        return None
    try:
        v = int(k)
    except (TypeError, ValueError):
        raise ValueError(f"k must be a positive integer or 'all', got {k!r}") from None
    if v < 1:
        raise ValueError(f"k must be a positive integer or 'all', got {k!r}")
    return v


def first_k_scans(ordering: pd.DataFrame, k: str | int) -> list[int]:
    """The first ``k`` scans of an ordering, in rank order.

    Parameters
    ----------
    ordering : pandas.DataFrame
        ``orderings/{ordering}.parquet``: ``rank`` (0-based), ``scan_id``.
    k : int, str
        Number of scans; ``"all"`` or a k larger than the number of ranked scans
        takes all of them.

    Returns
    -------
    list of int
        Scan ids.

    Raises
    ------
    KeyError
        When ``ordering`` lacks ``rank`` or ``scan_id``.
    ValueError
        For a k that is neither ``"all"`` nor a positive integer (:func:`parse_k`).
    """
    for c in ("rank", "scan_id"):
        if c not in ordering.columns:
            raise KeyError(f"ordering lacks column {c!r}; expected rank, scan_id")
    kk = parse_k(k)
    ids = ordering.sort_values("rank", kind="stable")["scan_id"].astype(int).tolist()
    return ids if kk is None else ids[:kk]


def curve_ks(n_kept: int, n_points: int = 24) -> list[int]:
    """About ``n_points`` values of k from 1 to ``n_kept``, geometrically spaced: the
    answer's plans of the first k scans (:mod:`floorscan.floorplan.answer_plans`).

    Parameters
    ----------
    n_kept : int
        Kept scans.
    n_points : int

    Returns
    -------
    list of int
        Distinct, increasing, ``n_kept`` last; empty when ``n_kept`` < 1.
    """
    if n_kept < 1:
        return []
    ks = np.unique(np.round(np.geomspace(1, n_kept, max(2, n_points))).astype(np.int64))
    return sorted(set(ks.tolist()) | {int(n_kept)})


def selected_scan_ids(path: str | os.PathLike) -> np.ndarray:
    """The selected scans of a ``selection/scans.parquet``
    (:func:`floorscan.select.deliverables.write_scan_table`).

    Parameters
    ----------
    path : path

    Returns
    -------
    (k,) int64 ndarray
        Scan ids in rank order.

    Raises
    ------
    KeyError
        When the table has no ``rank`` or ``scan_id`` column.
    """
    table = read_table(path, columns=["rank", "scan_id"])
    return table.sort_values("rank", kind="stable")["scan_id"].to_numpy(np.int64)


def read_selection(path: str | os.PathLike) -> dict:
    """``selection.json`` as the select stage writes it
    (:func:`floorscan.select.recommend.write_selection`).

    Parameters
    ----------
    path : path

    Returns
    -------
    dict
        ``k`` and its ``reason``, ``ordering``, ``n_kept``, ``n_recorded``, ``scans``
        (the scan list's path), ``points`` (PLY and PCD paths), ``recording`` (what the
        reduced recording holds: ``path``, ``bytes_in``, ``bytes_out``,
        ``scan_messages_out``, ...).
    """
    return json.loads(Path(path).read_text())
