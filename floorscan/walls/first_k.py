"""The wall segments of the first k scans of each ordering (stage ``walls``, rule ``walls``).

The per-scan walls (:func:`floorscan.walls.extract.extract_walls`) do not depend on
the ordering or on k, so the walls of the first k scans of an ordering are a filter
of them (:func:`first_k_walls`, the scans of
:func:`floorscan.core.selection.first_k_scans`), in rank order; :func:`k_walls_tables`
makes the tables of every ordering and k of a run
(``walls/{ordering}/{extractor}/k{k}.parquet``, schema
:data:`floorscan.walls.tables.WALLS`). The thesis evaluates the floor plans of
the first k scans against k (section 5.4).
"""

from __future__ import annotations

from typing import Iterator, Mapping, Sequence

import pandas as pd

from floorscan.core.selection import first_k_scans
from floorscan.walls.tables import WALLS


def first_k_walls(walls: pd.DataFrame, ordering: pd.DataFrame, k: str | int) -> tuple[pd.DataFrame, list[int]]:
    """The wall segments of the first ``k`` scans of an ordering (stage ``walls``).

    Parameters
    ----------
    walls : pandas.DataFrame
        Per-scan wall segments (schema :data:`WALLS`).
    ordering : pandas.DataFrame
        ``orderings/{ordering}.parquet``: ``rank`` (0-based), ``scan_id``.
    k : int, str
        Number of scans; ``"all"`` or a k larger than the number of ranked scans
        takes all of them.

    Returns
    -------
    segments : pandas.DataFrame
        Rows of ``walls`` whose scan is among the first k, in rank order (then the
        per-scan order).
    scan_ids : list of int
        The first k scans, in rank order.

    Raises
    ------
    KeyError
        When ``ordering`` lacks ``rank`` or ``scan_id``.
    """
    ids = first_k_scans(ordering, k)
    pos = {s: i for i, s in enumerate(ids)}
    sel = walls[walls["scan_id"].isin(pos)].copy()
    sel["_pos"] = sel["scan_id"].map(pos)
    sel = sel.sort_values("_pos", kind="stable").drop(columns="_pos").reset_index(drop=True)
    return sel[WALLS.names], ids


def k_walls_tables(
    walls: pd.DataFrame, orderings: Mapping[str, pd.DataFrame], names: Sequence[str], ks: Sequence[str | int]
) -> Iterator[tuple[str, str | int, pd.DataFrame, list[int]]]:
    """:func:`first_k_walls` of every ordering of ``names`` and every k of ``ks``.

    Parameters
    ----------
    walls : pandas.DataFrame
        Per-scan wall segments (schema :data:`~floorscan.walls.tables.WALLS`).
    orderings : mapping of str to pandas.DataFrame
        The orderings by name (``rank``, ``scan_id``).
    names : sequence of str
        The orderings to cut, in order.
    ks : sequence of int or str
        The numbers of scans (``"all"``: every ranked scan).

    Yields
    ------
    (ordering, k, segments, scan_ids)
        In the order ordering, then k (the order of the rule's ``expand``).

    Raises
    ------
    KeyError
        When ``orderings`` lacks one of ``names``, or as :func:`first_k_walls`.
    """
    for ordering in names:
        for k in ks:
            segments, scan_ids = first_k_walls(walls, orderings[ordering], k)
            yield ordering, k, segments, scan_ids
