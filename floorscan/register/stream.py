"""The register stage on a points file (``scans.parquet``), streamed:
:func:`register_recording`.

Two passes over the points: the first screens every scan as it is read, keeps the small
clouds registration needs of the sampled ones
(:class:`~floorscan.register.prepare.ScanStore`) and copies their points to a temporary
file, while the pose graph's edges are aligned in worker processes
(:class:`~floorscan.register.edge_stream.EdgeStream`); after registration
(:func:`floorscan.register.pipeline.register_screened`) the second pass writes the kept
scans' points in the map frame. Usage::

    result = register_recording("scans.parquet", index, poses, cfg, "registered.parquet")
    write_table(result.table, "registration.parquet", schema=REGISTRATION)

A caller with ``graph.workers`` above 1 starts worker processes (``spawn``): a script
calling it keeps its work under ``if __name__ == "__main__":``
(:mod:`floorscan.core.runtime`).
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from floorscan.core.config import stage_params
from floorscan.core.geometry import transform_points
from floorscan.core.io import REGISTERED, SCANS, InputError, ScanRowGroups, iter_scans, parquet_options
from floorscan.core.files import atomic_path
from floorscan.core.runtime import process_pool, progress, start_workers
from floorscan.register.edge_stream import EdgeStream
from floorscan.register.params import RegistrationConfig
from floorscan.register.consistency import stamps_warning
from floorscan.register.losses import ingest_losses
from floorscan.register.pipeline import fallback_reason, register_screened, resolve_config
from floorscan.register.prepare import ScanStore
from floorscan.register.result import RegistrationResult
from floorscan.register.sampling import typical_range_m
from floorscan.register.screening import Screener, aligned_poses, expected_sampled, prepare_index, sampling_rule

log = logging.getLogger(__name__)


def register_recording(
    scans_path: str | os.PathLike,
    scan_index: pd.DataFrame,
    poses: pd.DataFrame | None,
    config: RegistrationConfig | Mapping[str, Any] | None,
    registered_path: str | os.PathLike,
    metadata: Mapping[str, str] | None = None,
    recording: Mapping[str, str] | None = None,
) -> RegistrationResult:
    """:func:`~floorscan.register.pipeline.register_scans` on a points file, streamed:
    memory follows the largest scan, not the recording.

    The whole ``scans.parquet`` of a 3D recording is tens of millions of points. Here it
    is read once in record batches (:func:`floorscan.core.io.iter_scans`): each scan is
    screened as it arrives (:class:`~floorscan.register.screening.Screener`) and the
    sampled ones keep only the small clouds registration needs
    (:func:`~floorscan.register.prepare.graph_cloud` for ``reference: graph``, a few
    hundred points of a 14k-point 3D scan),
    their points going to a temporary Parquet file beside ``registered_path`` (the kept
    scans are sampled ones: 1 in ``every_n``). After registration that file is read
    back and each kept scan's points are transformed into the map frame and written to
    ``registered_path`` (a Parquet writer on :func:`floorscan.core.files.atomic_path`, a row group
    per ~1 M points). Same output as
    :func:`~floorscan.register.pipeline.register_scans` (tested), given the same input.
    With ``graph.workers`` above 1 the pose graph's edge ICP runs in a pool of worker
    processes started at once, while the scans are read
    (:class:`~floorscan.register.edge_stream.EdgeStream`), and ended when the expected
    pairs are aligned (the few pairs not expected are aligned as
    :func:`~floorscan.register.edges.scan_pair_edges` does without a pool); in odometry
    mode the loop closure's edges run in it.
    The figure of the registered map is drawn from that file
    (:func:`floorscan.figures.registration.density_of_file`, rule ``register_figure``).

    Parameters
    ----------
    scans_path : path
        ``scans.parquet``: ``scan_id, x, y, z`` in the scanner frame, metres, rows
        grouped by scan in ascending ``scan_id``.
    scan_index, poses, config
        As for :func:`~floorscan.register.pipeline.register_scans`.
    registered_path : path
        Output ``registered.parquet`` (schema :data:`floorscan.core.io.REGISTERED`).
    metadata : mapping, optional
        Key/value strings stored in the output's schema metadata.
    recording : mapping, optional
        As for :func:`~floorscan.register.pipeline.register_scans`.

    Returns
    -------
    RegistrationResult
        ``registered`` is None: the points are in ``registered_path``.

    Raises
    ------
    InputError
        As :func:`~floorscan.register.pipeline.register_scans`; also when the file's
        scans are not in ascending ``scan_id`` order or a point is not finite (naming
        the file and the scan).
    RegistrationError
        When no scan could be registered, or the verdict fails (as
        :func:`~floorscan.register.pipeline.register_scans`).
    """
    cfg = stage_params(RegistrationConfig, config)
    losses, fallback = ingest_losses(scan_index, recording), fallback_reason(cfg, recording)
    cfg = resolve_config(cfg, recording, math.nan if cfg.every_n else _range_of_file(scans_path))
    n_workers = _edge_workers(cfg, len(scan_index))
    # the edge ICP's worker processes import Open3D while the scans are read, on the
    # core this reading leaves idle; one pool for the whole call
    pool = process_pool(n_workers, preload=("open3d", "floorscan.register.edges")) if n_workers else None
    edges = None
    try:
        if pool is not None:
            start_workers(pool, n_workers)
        index = prepare_index(scan_index)
        aligned = aligned_poses(index, poses, cfg)
        sids = index["scan_id"].to_numpy()
        n = len(sids)
        screen = Screener(index, aligned, cfg)
        store = ScanStore(cfg)
        if cfg.mode == "pose" and cfg.reference == "graph" and pool is not None and aligned is not None:
            # the pose graph's edges are aligned in the workers while the scans are read,
            # for the scans that the index and poses say will be sampled; a scan the
            # points drop after all only costs its pairs again
            expected = expected_sampled(index, aligned, cfg)
            if len(expected):
                t = index["t_ns"].to_numpy(np.int64)[expected]
                init = aligned.iloc[expected][["x", "y", "z", "yaw"]].to_numpy(np.float64)
                edges = EdgeStream(
                    sids[expected], init, (t - t[0]) * 1e-9, cfg.graph_params, ("sequential", "loop"), pool,
                )  # fmt: skip

        def walk():
            """(index position, points) in index order; the file's scans are ascending."""
            k, last = 0, None
            # float32 as stored: most scans are only screened; _first_pass widens the
            # scans it keeps to float64
            for sid, pts in iter_scans(scans_path, dtype=np.float32):
                if last is not None and sid <= last:
                    raise InputError(
                        f"{scans_path}: scan {sid} follows scan {last}; expected the scans in "
                        "ascending scan_id order, as the ingest stage writes them"
                    )
                last = sid
                while k < n and sids[k] < sid:
                    yield k, None
                    k += 1
                if k < n and sids[k] == sid:
                    if not np.isfinite(pts).all():
                        raise InputError(
                            f"{scans_path}: scan {sid} has non-finite x, y or z; expected finite metres"
                        )
                    yield k, pts
                    k += 1
            while k < n:
                yield k, None
                k += 1

        # The sampled scans' points (the kept scans are among them) are copied to a
        # temporary file as they pass, so the second pass reads them, not the whole
        # recording again (1 in every_n scans).
        sampled_path = Path(registered_path).with_name(f".{Path(registered_path).name}.sampled.parquet")
        try:
            with pq.ParquetWriter(sampled_path, SCANS, **parquet_options(SCANS, ["scan_id"])) as sampled_writer:
                with ScanRowGroups(sampled_writer) as sampled_out:
                    _first_pass(progress(walk(), log, total=n, what="scans screened"), sids, screen, store, cfg,
                                sampled_out, edges)
            ahead = edges.finish() if edges is not None else None
            if ahead is not None:  # the expected pairs are aligned: the workers end here
                pool.shutdown()
                pool = None
            table, summary = register_screened(
                index, aligned, screen.reasons, store, cfg, ahead, pool, losses=losses, fallback=fallback,
                stamps=stamps_warning(recording, index["t_ns"].to_numpy()),
            )
            store = None
            if pool is not None:  # odometry's loop closure ran in them
                pool.shutdown()
                pool = None
            _second_pass(table, sids, sampled_path, registered_path, metadata)
        finally:
            sampled_path.unlink(missing_ok=True)
    finally:
        if edges is not None:
            edges.close()
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    return RegistrationResult(registered=None, table=table, summary=summary)


def _edge_workers(cfg: RegistrationConfig, n_scans: int) -> int:
    """Worker processes for the pose graph's edge ICP (0: none, the ICP runs here): as
    many as the edges will need, up to ``graph.workers`` (``edges._chunks``: at least
    200 pairs a worker; at most ~3 pairs a sampled scan are counted here, so small
    recordings get one)."""
    if not (cfg.reference == "graph" or (cfg.mode == "odometry" and cfg.loop_closure)):
        return 0
    workers = cfg.graph_params.workers
    pairs = 3 * n_scans // max(1, cfg.every_n or 5)
    return min(workers, max(1, pairs // 200)) if workers > 1 else 0


def _range_of_file(scans_path, max_points: int = 400_000) -> float:
    """Typical range of a recording from a points file (``scans.parquet``): up to 8 of
    its row groups, evenly spread, every k-th point of them."""
    pf = pq.ParquetFile(scans_path)
    n_groups = pf.metadata.num_row_groups
    if n_groups == 0:
        return math.nan
    groups = sorted(set(np.linspace(0, n_groups - 1, min(8, n_groups)).round().astype(int).tolist()))
    table = pf.read_row_groups(groups, columns=["x", "y"])
    step = max(1, table.num_rows // max_points)
    xy = np.column_stack([table.column(c).to_numpy()[::step] for c in ("x", "y")])
    return typical_range_m([xy])


def _first_pass(scans, sids, screen, store, cfg, sampled_out, edges=None) -> None:
    """Screen the scans as they stream by; keep the sampled ones' registration clouds
    (``store``) and points (``sampled_out``); hand the graph clouds to ``edges``
    (a :class:`floorscan.register.edge_stream.EdgeStream`)."""
    odometry = cfg.mode == "odometry"
    # sampled as register_screened samples; odometry without every_n samples on its
    # own poses later, so every usable scan may be sampled
    sampler = sampling_rule(cfg) if not odometry or cfg.every_n else None
    for k, pts in scans:
        if screen.step(k, pts) != "":
            continue
        if sampler is None:
            is_sampled = True
        elif odometry:
            is_sampled = sampler.step()
        else:
            is_sampled = sampler.step(screen.px[k], screen.py[k], screen.pyaw[k])
        if odometry:
            needs = ("icp",) if cfg.odometry_scans == "all" or is_sampled else ()
            if is_sampled and cfg.loop_closure:
                needs += ("graph",)
        elif is_sampled:
            needs = ("graph",) if cfg.reference == "graph" else ("clouds",)
        else:
            needs = ()
        if needs:
            store.add(int(sids[k]), pts.astype(np.float64), needs)
            if edges is not None and "graph" in needs:
                edges.add(int(sids[k]), store.graph(int(sids[k])))
        if is_sampled:
            sampled_out.add(int(sids[k]), pts)


def _second_pass(table, sids, sampled_path, registered_path, metadata) -> None:
    """The kept scans, read back from ``sampled_path``, into the map frame: ``registered_path``."""
    kept = table["kept"].to_numpy(bool)
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)
    pose_of = {int(s): final[k] for k, s in enumerate(sids) if kept[k]}
    schema = REGISTERED
    if metadata:
        schema = schema.with_metadata({str(k): str(v) for k, v in metadata.items()})
    with atomic_path(registered_path) as tmp:
        # x, y statistics: the register figure's raster extent (density_of_file)
        with pq.ParquetWriter(tmp, schema, **parquet_options(schema, ["scan_id", "x", "y"])) as writer:
            with ScanRowGroups(writer) as out:  # row groups written in a thread
                for sid, pts in iter_scans(sampled_path):
                    pose = pose_of.get(int(sid))
                    if pose is not None:
                        out.add(sid, transform_points(pts, *pose))
