"""The merge of the walls shards (stage ``walls``, rule ``scan_walls``).

The scans are extracted in shards of scan ranges (rule ``scan_walls_shard``, one job
per shard and extractor; :mod:`floorscan.core.shards`). :func:`merge_shards` checks the
shard files against the plan they were named by (read again from the register
stage's files) and concatenates them in scan order: exactly the tables one unsharded
job (:func:`floorscan.walls.extract.extract_walls`) gives.
"""

from __future__ import annotations

import logging
import os
from typing import Sequence

import pandas as pd
import pyarrow as pa

from floorscan.core.shards import plan_from_files, read_shards
from floorscan.walls.tables import SCAN_TIMES, WALLS

_log = logging.getLogger(__name__)


def merge_shards(
    extractor: str,
    registration: str | os.PathLike,
    registered: str | os.PathLike,
    shard_scans: int,
    shard_walls: Sequence[str | os.PathLike],
    shard_status: Sequence[str | os.PathLike],
    shard_times: Sequence[str | os.PathLike] | None = None,
    log: logging.Logger | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame, pa.Table | None]:
    """The per-scan walls, scan status and scan times of one extractor from its shards.

    Parameters
    ----------
    extractor : str
        The extractor's name, for messages.
    registration, registered : path
        The register stage's ``registration.parquet`` and ``registered.parquet``: the
        shard plan (:func:`floorscan.core.shards.plan_from_files`).
    shard_scans : int
        Kept scans per shard (config ``walls.shard_scans``).
    shard_walls, shard_status : sequence of path
        The shards' ``per_scan.parquet`` and ``scan_status.parquet``, in plan order,
        each in a folder named by its shard's label.
    shard_times : sequence of path, optional
        The shards' ``times.parquet``; None: no times.
    log : logging.Logger, optional
        Where the counts are logged (default: this module's logger).

    Returns
    -------
    walls : pandas.DataFrame
        Schema :data:`~floorscan.walls.tables.WALLS`, in scan order.
    status : pandas.DataFrame
        The scan status rows (:data:`~floorscan.walls.tables.SCAN_STATUS`), in scan order.
    times : pyarrow.Table or None
        Schema :data:`~floorscan.walls.tables.SCAN_TIMES`; None without ``shard_times``.

    Raises
    ------
    InputError
        As :func:`floorscan.core.shards.plan_from_files`.
    ValueError
        When the shard files are not the plan's, or as
        :func:`floorscan.core.shards.concat_shards`.
    """
    log = log or _log
    # the plan the workflow named the shards by, from the register stage's files
    plan = plan_from_files(registration, registered, shard_scans)
    walls, _ = read_shards(shard_walls, plan, f"{extractor} wall shards")
    status, _ = read_shards(shard_status, plan, f"{extractor} scan status shards")
    status = status.to_pandas()
    reasons = status.query("reason != ''")["reason"].value_counts().to_dict()
    log.info("%s: %d scans, %d wall segments from %d shards, scans without walls: %s",
             extractor, len(status), walls.num_rows, len(plan["shards"]), reasons or "none")
    times = None
    if shard_times is not None:
        times, _ = read_shards(shard_times, plan, f"{extractor} scan time shards")
        times = times.cast(SCAN_TIMES)
    # through pandas, as the unsharded stage wrote them: the same file, metadata included
    return walls.cast(WALLS).to_pandas(), status, times
