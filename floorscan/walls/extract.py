"""Wall extraction of every scan of a dataset, one extractor (stage ``walls``, rule
``scan_walls_shard``).

:func:`extract_walls` takes a registered points table (or its scans streamed from the
file: memory holds one scan) and an extractor name of
:data:`floorscan.walls.extractors.REGISTRY`, and returns the wall segments of every
scan (schema :data:`floorscan.walls.tables.WALLS`) and a status row per scan
(:data:`~floorscan.walls.tables.SCAN_STATUS`, with the seconds of its extraction,
:data:`~floorscan.walls.tables.SCAN_TIMES`). Per scan (:func:`extract_scan`): its 2D
wall points (:func:`floorscan.core.wall_points.scan_points_2d`), then the extractor's
lines and segments (:mod:`floorscan.walls.ransac`, thesis section 5.3, Algorithm 4;
:mod:`floorscan.walls.cluster`, section 3.4).

The walls of a scan depend only on its points, the extractor parameters and the
seed: the random generator of scan ``s`` is ``numpy.random.default_rng((seed, s))``,
so the walls of a scan do not change with the ordering or the number of scans used,
and the scans can be split into shards (:mod:`floorscan.walls.shards`).

Per-scan problems never raise: a scan gets no walls and a reason in its status row
(:data:`floorscan.walls.tables.REASONS`). Segments stay tuples until one frame per job.
"""

from __future__ import annotations

import logging
import time
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from floorscan.core.config import schema_section_defaults, stage_params
from floorscan.walls.extractors import REGISTRY, Extractor, get_extractor
from floorscan.walls.params import RansacParams
from floorscan.core.wall_points import ScanParams, scan_points_2d
from floorscan.walls.tables import SCAN_STATUS, WALLS, segments_frame

log = logging.getLogger(__name__)


def extract_scan(
    xyz: np.ndarray,
    extractor: str,
    scan: ScanParams,
    params: Mapping[str, Any],
    seed,
) -> tuple[pd.DataFrame, str, int]:
    """Wall segments of one scan with ``extractor``; never raises on bad points.

    Parameters
    ----------
    xyz : (N, 3) float ndarray
        Scan points in the map frame, metres; ``z`` is height above the floor.
    extractor : str
        A name of :data:`floorscan.walls.extractors.REGISTRY`.
    scan : ScanParams
    params : mapping of str to parameter object
        The extractor's config sections by key, e.g. ``{"ransac": RansacParams(),
        "cluster_ransac": ClusterParams()}`` (each built by :func:`floorscan.core.config.stage_params`).
    seed : int, sequence of int or numpy.random.Generator

    Returns
    -------
    segments : pandas.DataFrame
        As :func:`floorscan.walls.ransac.ransac`.
    reason : str
        "" when segments were found, else one of :data:`~floorscan.walls.tables.REASONS`.
    n_points : int
        Wall points the extractor saw.

    Raises
    ------
    ValueError
        For an unknown extractor.
    KeyError
        When ``params`` lacks a section the extractor reads.
    """
    entry = get_extractor(extractor)
    own = [params[key] for key in entry.config]
    rows, reason, n_pts = _extract_scan_rows(xyz, entry, scan, params["ransac"], own, seed)
    return segments_frame(rows), reason, n_pts


def _extract_scan_rows(
    xyz, entry: Extractor, scan: ScanParams, ransac: RansacParams, own: list, seed
) -> tuple[list[tuple], str, int]:
    """:func:`extract_scan` with the segments as a list of tuples (no frame per scan);
    ``own`` are the parameters ``entry.rows`` takes."""
    pts, reason = scan_points_2d(xyz, scan)
    if reason:
        return [], reason, 0
    if len(pts) < ransac.min_points:
        return [], "too_few_points", len(pts)
    rows = entry.rows(pts, *own, seed)
    return rows, ("" if rows else "no_wall_found"), len(pts)


def extract_walls(
    points: pd.DataFrame | Iterable[tuple[int, np.ndarray]], extractor: str, cfg: Mapping[str, Any]
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Wall segments of every scan of a registered points table (stage ``scan_walls``).

    Parameters
    ----------
    points : pandas.DataFrame or iterable of (int, (n, 3) float ndarray)
        ``registered.parquet``: ``scan_id, x, y, z`` (map frame, metres, z above
        floor) as a frame, or streamed scan by scan as ``(scan_id, xyz)``
        (:func:`floorscan.core.io.iter_scans`; memory then holds one scan).
    extractor : str
        A name of :data:`floorscan.walls.extractors.REGISTRY` (``"ransac"``,
        ``"cluster_ransac"``).
    cfg : mapping
        The ``walls`` config section (``seed``, ``height_band_m``: the keys of
        :data:`floorscan.walls.extractors.EXTRACT_KEYS`); a key named as an extractor's
        parameter class (``ransac``, ``cluster_ransac``) may hold an instance of it or a
        mapping of its fields (default: the class's defaults). Scan ``s`` uses the generator
        ``numpy.random.default_rng((seed, s))``, independent of the other scans.

    Returns
    -------
    walls : pandas.DataFrame
        Schema :data:`~floorscan.walls.tables.WALLS`, rows ordered by scan_id then
        discovery.
    status : pandas.DataFrame
        The columns of :data:`~floorscan.walls.tables.SCAN_STATUS` and ``time_s``
        (:data:`~floorscan.walls.tables.SCAN_TIMES`): one row per scan, ``reason`` ""
        or one of :data:`~floorscan.walls.tables.REASONS`, ``time_s`` wall-clock
        seconds of the extraction. Written as two tables: ``write_table(status, path,
        schema=SCAN_STATUS)`` leaves the time out.

    Raises
    ------
    KeyError
        When ``points`` lacks a column or ``cfg`` has an unknown key.
    ValueError
        For an unknown extractor, or a streamed scan id that comes twice.
    """
    if isinstance(points, pd.DataFrame):
        from floorscan.core.io import split_by_scan

        scans: Iterable[tuple[int, np.ndarray]] = split_by_scan(points).items()
    else:
        scans = points
    entry = get_extractor(extractor)
    # every extractor's parameters (ransac, cluster_ransac, ...): their defaults unless cfg holds them
    classes = {key: cls for e in REGISTRY.values() for key, cls in e.config.items()}
    scan_p = stage_params(ScanParams, {key: value for key, value in cfg.items() if key not in classes})
    params = {key: stage_params(cls, cfg.get(key), f"walls.{key}") for key, cls in classes.items()}
    ransac_p, own = params["ransac"], [params[key] for key in entry.config]
    seed = int(cfg.get("seed", schema_section_defaults("walls")["seed"]))
    if entry.prepare is not None:  # imports before timing the first scan
        entry.prepare(*own)
    per_scan: dict[int, list[tuple]] = {}
    status = []
    for scan_id, xyz in scans:
        scan_id = int(scan_id)
        if scan_id in per_scan:
            raise ValueError(f"scan {scan_id}: its points come in two separate runs; expected them together")
        t0 = time.perf_counter()
        rows, reason, n_pts = _extract_scan_rows(xyz, entry, scan_p, ransac_p, own, (seed, scan_id))
        dt = time.perf_counter() - t0
        per_scan[scan_id] = rows
        status.append((scan_id, n_pts, len(rows), reason, dt))
    ids = sorted(per_scan)
    rows = [r for s in ids for r in per_scan[s]]
    n_rows = [len(per_scan[s]) for s in ids]
    walls_df = segments_frame(rows)
    walls_df.insert(0, "scan_id", np.repeat(np.asarray(ids, dtype=np.int32), n_rows))
    walls_df = walls_df[WALLS.names]
    status.sort(key=lambda r: r[0])
    status_df = pd.DataFrame(status, columns=[*SCAN_STATUS.names, "time_s"]).astype(
        {"scan_id": "int32", "n_points": "int32", "n_walls": "int32", "reason": "str", "time_s": "float64"}
    )
    counts = status_df.loc[status_df.reason != "", "reason"].value_counts().to_dict()
    log.info(
        "%s: %d scans, %d wall segments, %.3f s/scan, scans without walls: %s",
        extractor, len(status_df), len(walls_df), status_df.time_s.mean() if len(status_df) else 0.0,
        counts or "none",
    )
    return walls_df, status_df
