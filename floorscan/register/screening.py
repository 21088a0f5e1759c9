"""The per-scan checks before registration and the sampling among the scans that pass
(thesis Algorithm 3 step 2).

- :func:`screen_scans` / :class:`Screener`: missing pose, duplicate, too few points,
  pose jump, one scan at a time in recording order (every check depends on the scan and
  the ones before it only, so the stream screens the scans as they are read);
- :func:`sample_scans`: the scans registration takes among the usable ones, by
  ``every_n`` or the motion filter (:mod:`floorscan.register.sampling`);
- :func:`prepare_index`, :func:`aligned_poses`: the scan index and the poses, checked
  and aligned row by row.

A new per-scan check is a branch of :meth:`Screener.step` with its reason, and the
reason's config key in :data:`floorscan.register.result.REASON_THRESHOLD`.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np
import pandas as pd

from floorscan.core.geometry import wrap_angle
from floorscan.core.io import InputError
from floorscan.register.params import RegistrationConfig
from floorscan.register.sampling import EveryN, MotionFilter


def check_columns(df: pd.DataFrame, name: str, columns: list[str]) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(f"{name}: columns {missing} missing; expected {columns}")



def prepare_index(scan_index: pd.DataFrame) -> pd.DataFrame:
    check_columns(scan_index, "scan_index.parquet", ["scan_id", "t_ns"])
    index = scan_index[["scan_id", "t_ns"]].sort_values("scan_id", kind="stable").reset_index(drop=True)
    if index["scan_id"].duplicated().any():
        raise InputError("scan_index.parquet: scan_id is not unique")
    return index


def aligned_poses(index: pd.DataFrame, poses: pd.DataFrame | None, cfg: RegistrationConfig) -> pd.DataFrame | None:
    """The localizer's pose of every scan of the index, in index order (thesis
    Algorithm 3, step 1's result as the register stage reads it).

    Parameters
    ----------
    index : pandas.DataFrame
        ``scan_index.parquet``: one row per scan, ``scan_id``.
    poses : pandas.DataFrame or None
        ``poses.parquet``: ``scan_id``, ``x``, ``y``, ``z`` (metres), ``yaw`` (radians),
        ``valid``, ``reason``; one row per scan.
    cfg : RegistrationConfig
        ``mode``: ``odometry`` needs no poses.

    Returns
    -------
    pandas.DataFrame or None
        One row per scan of ``index`` (S rows), the columns of ``poses``; ``valid`` is
        false where the pose is missing or not finite. None in odometry mode.

    Raises
    ------
    InputError
        Pose mode without poses; ``poses.parquet`` without those columns, with a
        repeated ``scan_id``, or without a row for a scan of the index.
    """
    if cfg.mode == "odometry":
        return None
    if poses is None:
        raise InputError("register: mode 'pose' needs poses.parquet (or set mode: odometry)")
    return _align_poses(index, poses)


def _align_poses(index: pd.DataFrame, poses: pd.DataFrame) -> pd.DataFrame:
    check_columns(poses, "poses.parquet", ["scan_id", "x", "y", "z", "yaw", "valid", "reason"])
    if poses["scan_id"].duplicated().any():
        raise InputError("poses.parquet: scan_id is not unique")
    p = poses.set_index("scan_id").reindex(index["scan_id"].to_numpy())
    missing = p["valid"].isna()
    if missing.any():
        raise InputError(
            f"poses.parquet: no row for {int(missing.sum())} scans of scan_index.parquet "
            f"(first scan_id {int(p.index[missing.to_numpy()][0])}); expected one row per scan"
        )
    p = p.reset_index()
    p["valid"] = p["valid"].astype(bool) & np.isfinite(p[["x", "y", "z", "yaw"]].to_numpy(float)).all(axis=1)
    p["reason"] = p["reason"].fillna("").astype(str)
    return p



def screen_scans(
    index: pd.DataFrame,
    clouds: Mapping[int, np.ndarray],
    poses: pd.DataFrame | None,
    cfg: RegistrationConfig,
) -> np.ndarray:
    """Per-scan checks before sampling: missing pose, duplicate, too few points, pose jump.

    Parameters
    ----------
    index : pandas.DataFrame
        ``scan_id``, ``t_ns`` sorted by ``scan_id`` (recording order).
    clouds : mapping of int to (N, 3) ndarray
        Points of each scan (scanner frame); absent scans have no points.
    poses : pandas.DataFrame or None
        Aligned with ``index`` (same order): ``x, y, z, yaw, valid, reason``. None in
        odometry mode (no pose checks).
    cfg : RegistrationConfig

    Returns
    -------
    (S,) object ndarray
        Reason per scan, ``""`` for scans that pass.
    """
    screen = Screener(index, poses, cfg)
    for i, sid in enumerate(index["scan_id"].to_numpy()):
        screen.step(i, clouds.get(int(sid)))
    return screen.reasons


class Screener:
    """The per-scan checks of :func:`screen_scans`, one scan at a time in recording
    order: every check depends on the scan and the scans before it only, so
    :func:`floorscan.register.stream.register_recording` screens while it streams
    the points."""

    def __init__(self, index: pd.DataFrame, poses: pd.DataFrame | None, cfg: RegistrationConfig):
        n = len(index)
        self.cfg = cfg
        self.reasons = np.full(n, "", dtype=object)
        self.t = index["t_ns"].to_numpy(np.int64)
        self.poses = poses
        if poses is not None:
            valid = poses["valid"].to_numpy(bool)
            for i in np.flatnonzero(~valid):
                r = str(poses["reason"].iloc[i]) or "invalid"
                self.reasons[i] = f"no_pose:{r}"
            self.px, self.py, self.pyaw = (poses[c].to_numpy(np.float64) for c in ("x", "y", "yaw"))
        self.prev = None  # the previous scan's points (duplicate check)
        self.last = None  # last plausible pose (pose-jump check)

    def step(self, i: int, pts: np.ndarray | None, points_unseen: bool = False) -> str:
        """Screen scan ``i`` (index position) with its points (None: no points);
        returns its reason (``""``: usable). ``points_unseen``: the points are not
        known yet and taken to pass (the scans expected to be usable, from the
        index and poses alone)."""
        cfg, reasons, t = self.cfg, self.reasons, self.t
        size = 0 if pts is None else len(pts)
        if reasons[i] == "":
            if i > 0 and t[i] == t[i - 1]:
                reasons[i] = "duplicate"
            elif points_unseen:
                pass
            elif size < max(cfg.min_points, 1):
                reasons[i] = "too_few_points"
            elif self.prev is not None and np.array_equal(pts, self.prev):
                reasons[i] = "duplicate"  # the same returns as the scan before
        self.prev = pts if size else None
        if self.poses is None or reasons[i].startswith("no_pose") or reasons[i] == "duplicate":
            return reasons[i]
        # pose jump: against the last plausible pose (a single outlier drops one scan; after
        # a relocalisation the scans resume once the jump fits the speed limit)
        last = self.last
        if last is not None:
            dt = (t[i] - t[last]) * 1e-9
            dist = math.hypot(self.px[i] - self.px[last], self.py[i] - self.py[last])
            turn = abs(float(wrap_angle(self.pyaw[i] - self.pyaw[last])))
            if (
                dt < 0
                or dist > cfg.max_speed_m_s * dt + cfg.pose_jump_slack_m
                or turn > cfg.max_turn_rate_rad_s * dt + cfg.pose_jump_slack_rad
            ):
                if reasons[i] == "":
                    reasons[i] = "pose_jump"
                return reasons[i]
        self.last = i
        return reasons[i]


def sampling_rule(cfg: RegistrationConfig):
    """The sampling rule of Algorithm 3 step 2: ``every_n`` when set, else the motion
    filter (:mod:`floorscan.register.sampling`; thresholds resolved by
    :func:`floorscan.register.pipeline.resolve_config`)."""
    if cfg.every_n:
        return EveryN(cfg.every_n)
    if cfg.keep_distance_m is None or cfg.keep_angle_rad is None:
        raise ValueError("register: the motion filter's thresholds are not resolved (resolve_config)")
    return MotionFilter(cfg.keep_distance_m, cfg.keep_angle_rad)


def sample_scans(usable: np.ndarray, aligned: pd.DataFrame, cfg: RegistrationConfig) -> np.ndarray:
    """Index positions of the sampled scans among ``usable`` (pose modes)."""
    sampler = sampling_rule(cfg)
    x, y, yaw = (aligned[c].to_numpy(np.float64) for c in ("x", "y", "yaw"))
    return np.asarray([i for i in usable if sampler.step(x[i], y[i], yaw[i])], dtype=np.int64)


def expected_sampled(index: pd.DataFrame, aligned: pd.DataFrame, cfg) -> np.ndarray:
    """Index positions of the scans that will be sampled if every scan's points pass
    the screening (the checks of the index and poses only; sampled as
    :func:`floorscan.register.pipeline.register_screened` samples)."""
    screen = Screener(index, aligned, cfg)
    for i in range(len(index)):
        screen.step(i, None, points_unseen=True)
    return sample_scans(np.flatnonzero(screen.reasons == ""), aligned, cfg)
