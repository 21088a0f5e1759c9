"""Registration: every kept scan in one map frame, refined by planar ICP (thesis 3.2.2,
3.5); the register stage's steps in order, on a recording in memory.

Algorithm 3 of the thesis, steps 2-6 (step 1, pose interpolation, is the ``poses``
stage):

2. keep the scans that pass the per-scan checks and, among them, those the sampling
   rule takes (``every_n``, or the motion filter; :mod:`floorscan.register.screening`);
3. apply the localizer's pose (``map_point = Rz(yaw) @ p + (x, y, z)``);
4. fitness of the scan against its references under the pose alone; drop the scan
   when the mean is below ``min_prior_fitness``;
5. refine the pose by ICP against references;
6. drop the scan when the mean fitness after ICP is below ``min_icp_fitness``.

Step 5 departs from the thesis: the strategy is ``register.reference`` (``graph``, the
default: :mod:`floorscan.register.posegraph`; ``map``:
:mod:`floorscan.register.scan_to_map`; ``previous``, the thesis's:
:mod:`floorscan.register.sequential`), or without map poses ``mode: odometry``
(:mod:`floorscan.register.odometry`). A new strategy is a function
``(sampled, clouds, sids, t, cfg, initial) -> ScanRegistration`` in a module beside the
others: ``initial`` holds the screening's reasons and the localizer's poses of every
scan (:meth:`~floorscan.register.result.ScanRegistration.before_registration`), and the
strategy returns a new :class:`~floorscan.register.result.ScanRegistration` (kept, drop
reason, fitness, inlier RMSE, pose of every scan), changing no array it was given;
:func:`register_screened` calls it in a new branch and makes the table of its result,
and the schema gets a value of ``reference``.

Usage::

    result = register_scans(scans, scan_index, poses, {"reference": "graph"})
    result.table, result.summary["verdict"]

The register stage itself streams its points from the file
(:func:`floorscan.register.stream.register_recording`, same output).
"""

from __future__ import annotations

import logging
import math
from typing import Any, Mapping

import numpy as np
import pandas as pd

from floorscan.core.config import stage_params
from floorscan.core.geometry import transform_points
from floorscan.core.io import InputError, split_by_scan
from floorscan.register.consistency import stamps_warning
from floorscan.register.losses import Losses, ingest_losses, with_pose_losses, with_screening_losses
from floorscan.register.odometry import register_odometry
from floorscan.register.params import RegistrationConfig
from floorscan.register.posegraph import register_graph
from floorscan.register.prepare import ScanStore
from floorscan.register.result import (
    RegistrationError,
    RegistrationResult,
    ScanRegistration,
    judge,
    raise_if_nothing_registered,
    summarize,
)
from floorscan.register.sampling import choose_thresholds, median_step_m, typical_range_m
from floorscan.register.scan_to_map import register_map
from floorscan.register.screening import aligned_poses, check_columns, prepare_index, sample_scans, screen_scans
from floorscan.register.sequential import register_sequential

log = logging.getLogger(__name__)


def register_scans(
    scans: pd.DataFrame,
    scan_index: pd.DataFrame,
    poses: pd.DataFrame | None = None,
    config: RegistrationConfig | Mapping[str, Any] | None = None,
    recording: Mapping[str, str] | None = None,
) -> RegistrationResult:
    """Register the scans of a recording into the map frame (thesis Algorithm 3, steps 2-6).

    Parameters
    ----------
    scans : pandas.DataFrame
        ``scan_id, x, y, z``: points in the scanner frame, metres (``scans.parquet``).
    scan_index : pandas.DataFrame
        ``scan_id, t_ns`` (and ``n_points``, when present: scans without points are
        losses): one row per scan (``scan_index.parquet``).
    poses : pandas.DataFrame, optional
        ``scan_id, x, y, z, yaw, valid, reason`` (``poses.parquet``): scanner pose in the
        map frame per scan. Required in ``mode="pose"``, ignored in ``mode="odometry"``
        (scan-to-scan ICP from the first usable scan, which defines the map frame).
    config : RegistrationConfig or mapping, optional
        The ``register`` config section; defaults from :class:`RegistrationConfig`.
    recording : mapping of str to str, optional
        What ingest found in the recording (``scan_index.parquet``'s schema metadata:
        ``pose_kind``, ``pose_source``, ``stamps``), for :func:`resolve_config`, and the
        scans ingest lost (``n_frames_read``, ``lost_*``;
        :func:`floorscan.register.losses.ingest_losses`), for the verdict.

    Returns
    -------
    RegistrationResult
        Registered points of the kept scans, one table row per scan, a summary (its
        ``verdict``: :class:`floorscan.register.consistency.Verdict` as a dict), see
        :mod:`floorscan.register.result`.

    Raises
    ------
    InputError
        When a table lacks a column, a point is not finite, the poses do not cover the scan
        index, or poses are missing in pose mode.
    RegistrationError
        When no scan could be registered (the message gives the count per reason and the
        threshold that dropped most scans), or the result is poor: fewer than
        ``min_kept_fraction`` of the sampled scans kept, a map consistency below
        ``min_consistency`` (:mod:`floorscan.register.consistency`), or more than
        ``max_lost_fraction`` of the recording's scans lost before registration (without
        a pose, or lost at ingest: :mod:`floorscan.register.losses`).

    Notes
    -----
    The sampling is :func:`floorscan.register.screening.sample_scans`; the strategies
    are described in their modules (``reference: graph``
    :mod:`floorscan.register.posegraph`, ``map`` :mod:`floorscan.register.scan_to_map`,
    ``previous`` :mod:`floorscan.register.sequential`, ``mode: odometry``
    :mod:`floorscan.register.odometry`), the clouds of each scan in
    :func:`floorscan.register.prepare.scan_clouds` and
    :func:`~floorscan.register.prepare.graph_cloud`. There is no randomness: the same
    input gives the same output.
    """
    cfg = stage_params(RegistrationConfig, config)
    check_columns(scans, "scans.parquet", ["scan_id", "x", "y", "z"])
    index = prepare_index(scan_index)
    bad = ~np.isfinite(scans[["x", "y", "z"]].to_numpy(np.float64)).all(axis=1)
    if bad.any():
        raise InputError(
            f"scans.parquet: {int(bad.sum())} points with non-finite x, y or z (first in scan "
            f"{int(scans['scan_id'].to_numpy()[bad][0])}); expected finite metres"
        )
    clouds = split_by_scan(scans)
    losses, fallback = ingest_losses(scan_index, recording), fallback_reason(cfg, recording)
    cfg = resolve_config(cfg, recording, math.nan if cfg.every_n else _range_sample(clouds))
    aligned = aligned_poses(index, poses, cfg)
    reasons = screen_scans(index, clouds, aligned, cfg)
    table, summary = register_screened(
        index, aligned, reasons, ScanStore(cfg, clouds), cfg, losses=losses, fallback=fallback,
        stamps=stamps_warning(recording, index["t_ns"].to_numpy()),
    )
    sids = table["scan_id"].to_numpy()
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)
    kept = table["kept"].to_numpy(bool)
    keep_ids = sids[kept]
    parts = [transform_points(clouds[int(s)], *f) for s, f in zip(keep_ids, final[kept])]
    registered = pd.DataFrame(
        {
            "scan_id": np.repeat(keep_ids.astype(np.int32), [len(p) for p in parts]),
            **{
                c: (np.concatenate(parts)[:, k] if parts else np.empty(0)).astype(np.float32)
                for k, c in enumerate("xyz")
            },
        }
    )
    return RegistrationResult(registered=registered, table=table, summary=summary)


def resolve_config(
    cfg: RegistrationConfig, recording: Mapping[str, str] | None, range_m: float
) -> RegistrationConfig:
    """The settings a recording needs, from what ingest found in it (logged with why).

    - ``mode: auto``: ``pose`` when the recording has map poses (``pose_kind`` ``map``:
      a localizer topic, the TF chain from ``map``, a log's corrected poses), else
      ``odometry`` (LIDAR odometry: wheel odometry alone is never the map pose);
    - made-up stamps (``stamps`` ``made_up``: all zero, or mostly repeated) carry no
      speed, so the pose-jump checks (``max_speed_m_s``, ``max_turn_rate_rad_s``) are off;
    - without ``every_n``, the motion filter's thresholds not configured are chosen from
      the scanner's typical range ``range_m`` (:mod:`floorscan.register.sampling`).

    Parameters
    ----------
    cfg : RegistrationConfig
    recording : mapping of str to str, or None
        The schema metadata of ``scan_index.parquet`` (keys ``pose_kind``, ``stamps``);
        None or missing keys: map poses, recorded stamps.
    range_m : float
        Typical range of the scanner, metres (:func:`floorscan.register.sampling.typical_range_m`).

    Returns
    -------
    RegistrationConfig
        With ``mode`` ``pose`` or ``odometry`` and the sampling thresholds set.

    Raises
    ------
    InputError
        ``mode: pose`` on a recording without map poses, or ``odometry_scans: sampled``
        without ``every_n``.
    """
    rec = dict(recording or {})
    pose_kind = rec.get("pose_kind", "map")
    changes: dict[str, Any] = {}
    if cfg.mode == "auto":
        changes["mode"] = "pose" if pose_kind == "map" else "odometry"
        log.info(
            "register.mode auto -> %s (pose source: %s)", changes["mode"], rec.get("pose_source", "map poses")
        )
    elif cfg.mode == "pose" and pose_kind != "map":
        raise InputError(
            f"register.mode 'pose' needs map poses, but the recording has none ({rec.get('pose_source', pose_kind)}); "
            "use register.mode auto or odometry, or name a pose source (dataset 'pose')"
        )
    if rec.get("stamps") == "made_up":
        changes.update(max_speed_m_s=math.inf, max_turn_rate_rad_s=math.inf)
        log.info("the scan stamps are made up (%s): pose-jump checks on speed and turn rate are off", rec.get("stamps"))
    if cfg.every_n:
        log.info("sampling: every %d-th usable scan (register.every_n)", cfg.every_n)
    else:
        th = choose_thresholds(range_m, cfg.keep_distance_m, cfg.keep_angle_rad, cfg.keep_range_fraction)
        changes.update(keep_distance_m=th.distance_m, keep_angle_rad=th.angle_rad)
        log.info("sampling: motion filter, %s", th.reason)
        if changes.get("mode", cfg.mode) == "odometry" and cfg.odometry_scans == "sampled":
            raise InputError("register.odometry_scans 'sampled' needs register.every_n (the motion filter samples the odometry's own poses)")
    return cfg.replace(**changes)


def fallback_reason(cfg: RegistrationConfig, recording: Mapping[str, str] | None) -> str:
    """Why the scans will be placed by LIDAR odometry although the user did not ask for
    it (``mode: auto`` on a recording without map poses), for the verdict; ``""`` when
    they will not be, or the user set ``mode: odometry``."""
    rec = dict(recording or {})
    if cfg.mode != "auto" or rec.get("pose_kind", "map") == "map":
        return ""
    return (
        f"no map poses in the recording (pose source: {rec.get('pose_source', rec.get('pose_kind'))}), so the "
        "scans were placed by LIDAR odometry (register.mode auto) and the map frame is the first scan's"
    )


def _range_sample(clouds: Mapping[int, np.ndarray], n: int = 200) -> float:
    """Typical range of a recording from up to ``n`` of its scans, evenly spread."""
    ids = sorted(clouds)
    pick = ids[:: max(1, len(ids) // n)]
    return typical_range_m(clouds[i] for i in pick)


def register_screened(index, aligned, reasons, clouds: ScanStore, cfg: RegistrationConfig, ahead=None,
                      pool=None, losses: Losses | None = None, fallback: str = "",
                      stamps: str = "") -> tuple[pd.DataFrame, dict]:
    """Algorithm 3 steps 2-6 after the per-scan checks: sampling, then the registration
    of the configured mode (``ahead``: pose-graph edges aligned ahead, a finished
    :class:`floorscan.register.edge_stream.EdgeStream`; ``pool``: the worker processes
    of the pose graph's edge ICP). ``losses``: the scans ingest lost
    (:func:`floorscan.register.losses.ingest_losses`; None: the index's scans, none
    lost), to which the scans without a pose are added in pose mode; ``fallback``: why
    the scans are placed by LIDAR odometry (:func:`fallback_reason`); ``stamps``: that
    ingest made the stamps up
    (:func:`floorscan.register.consistency.stamps_warning`). Returns the
    :data:`~floorscan.register.result.REGISTRATION` table and the summary; raises
    :class:`~floorscan.register.result.RegistrationError` when nothing could be
    registered or the verdict fails (its line names every loss)."""
    n = len(index)
    odometry = cfg.mode == "odometry"
    usable = np.flatnonzero(reasons == "")
    if odometry:  # sampled on the odometry's own poses unless every_n is set
        sampled = usable[:: cfg.every_n] if cfg.every_n else None
    else:
        sampled = sample_scans(usable, aligned, cfg)

    pose = np.full((n, 4), np.nan)  # the localizer's, where valid
    if aligned is not None:
        ok = aligned["valid"].to_numpy(bool)
        pose[ok] = aligned.loc[ok, ["x", "y", "z", "yaw"]].to_numpy(np.float64)
    initial = ScanRegistration.before_registration(reasons, pose)

    t = index["t_ns"].to_numpy(np.int64)
    sids = index["scan_id"].to_numpy()
    if odometry:
        reg = register_odometry(usable, sampled, clouds, sids, t, cfg, initial)
        if cfg.loop_closure:
            reg = register_graph(np.flatnonzero(reg.kept), clouds, sids, t, cfg, reg, priors=False, pool=pool)
    elif cfg.reference == "graph":
        reg = register_graph(sampled, clouds, sids, t, cfg, initial, priors=True, ahead=ahead, pool=pool)
    elif cfg.reference == "previous":
        reg = register_sequential(sampled, clouds, sids, t, cfg, initial)
    else:
        reg = register_map(sampled, clouds, sids, t, cfg, initial)
    sampled = reg.sampled
    reason = reg.reason.copy()
    reason[np.setdiff1d(usable, sampled)] = "not_sampled"
    if not cfg.every_n and len(usable) > 1:
        at = reg.pose[usable] if odometry else aligned[["x", "y"]].to_numpy(np.float64)[usable]
        at = at[np.isfinite(at[:, 0])]
        log.info(
            "sampling: %d of %d usable scans (the recording's median step between scans %.3f m; "
            "keep_distance_m %.3f, keep_angle_rad %.3f)",
            len(sampled), len(usable), median_step_m(at[:, 0], at[:, 1]), cfg.keep_distance_m, cfg.keep_angle_rad,
        )

    table = pd.DataFrame(
        {
            "scan_id": sids.astype(np.int32),
            "t_ns": t,
            "kept": reg.kept,
            "reason": reason.astype(str),
            "fitness_prior": reg.fitness_prior,
            "fitness_icp": reg.fitness_icp,
            "inlier_rmse_m": reg.inlier_rmse_m,
            "dx_m": reg.pose_correction[:, 0],
            "dy_m": reg.pose_correction[:, 1],
            "dyaw_rad": reg.pose_correction[:, 2],
            "x_m": reg.pose[:, 0],
            "y_m": reg.pose[:, 1],
            "z_m": reg.pose[:, 2],
            "yaw_rad": reg.pose[:, 3],
        }
    )
    summary = summarize(table, cfg)
    if losses is None:
        losses = ingest_losses(index, None)
    losses = with_screening_losses(
        losses, sids, t, reasons, aligned,
        f"register.max_speed_m_s {cfg.max_speed_m_s:g} or max_turn_rate_rad_s {cfg.max_turn_rate_rad_s:g}",
        cfg.min_points)
    if not odometry:  # LIDAR odometry does not use the poses: a scan without one is not lost
        losses = with_pose_losses(losses, sids, t, table["reason"].to_numpy())
    summary["losses"] = losses.as_dict()
    raise_if_nothing_registered(table, cfg, summary)
    judged = judge(table, clouds, cfg, summary, losses, fallback, stamps)
    summary["verdict"] = judged.as_dict()
    log.info(
        "register (%s): %d scans, %d sampled, %d kept (%d anchors); drops %s",
        cfg.mode, n, len(sampled), int(reg.kept.sum()), reg.n_anchors, summary["drops"],
    )
    (log.info if judged.ok and not judged.warnings else log.warning)("verdict: %s", judged.line())
    if not judged.ok:
        raise RegistrationError(f"register: the result is poor: {judged.line()}")
    return table, summary
