"""What the register stage gives: what a strategy gives for every scan
(:class:`ScanRegistration`), the per-scan table (:data:`REGISTRATION`, the drop reason
of each scan), its summary, the verdict, and :class:`RegistrationError` when nothing or
too little registers.

Drop reasons (``reason`` column; kept scans have ``""``, or ``"anchor"`` for a scan kept
without a reference, and the first scan in odometry mode):

- ``no_pose:<reason>``: the poses table has no valid pose (reason from ``poses``);
- ``duplicate``: same timestamp as the previous scan, or exactly the same points;
- ``too_few_points``: fewer than ``min_points`` points;
- ``pose_jump``: the pose moved faster than ``max_speed_m_s`` or turned faster than
  ``max_turn_rate_rad_s`` since the last plausible pose;
- ``not_sampled``: skipped by the sampling rule (not a failure);
- ``low_prior_fitness`` / ``low_icp_fitness``: Algorithm 3 steps 4 and 6 (odometry
  mode: no prior check; ``fitness_prior`` is then the fitness at the constant-velocity
  prediction);
- ``icp_disagrees``: ``reference: graph``, most of the scan's pairs with structure
  (ICP's relative pose) put it elsewhere than its registered pose
  (:mod:`floorscan.register.agreement`; there a scan whose pairs agree with its pose is
  kept whatever its fitness);
- ``icp_failed``: ICP found fewer than 3 correspondences.

A new reason gets its config key in :data:`REASON_THRESHOLD`, so that the "every scan
dropped" error names it.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from dataclasses import dataclass
from typing import Mapping

import numpy as np
import pandas as pd
import pyarrow as pa

from floorscan.core.geometry import transform_points
from floorscan.register.consistency import map_consistency, path_length_m, verdict
from floorscan.register.losses import Losses
from floorscan.register.params import RegistrationConfig

#: One row per scan of ``scan_index`` (``registration.parquet``).
REGISTRATION = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("t_ns", pa.int64()),
        ("kept", pa.bool_()),
        ("reason", pa.string()),
        ("fitness_prior", pa.float64()),
        ("fitness_icp", pa.float64()),
        ("inlier_rmse_m", pa.float64()),
        ("dx_m", pa.float64()),
        ("dy_m", pa.float64()),
        ("dyaw_rad", pa.float64()),
        ("x_m", pa.float64()),
        ("y_m", pa.float64()),
        ("z_m", pa.float64()),
        ("yaw_rad", pa.float64()),
    ]
)

#: Config key behind each failure reason, for the "every scan dropped" error.
REASON_THRESHOLD = {
    "too_few_points": "min_points",
    "pose_jump": "max_speed_m_s / max_turn_rate_rad_s",
    "low_prior_fitness": "min_prior_fitness",
    "low_icp_fitness": "min_icp_fitness",
    "icp_failed": "icp_max_correspondence_m",
    "icp_disagrees": "graph.agreement_m / graph.agreement_rad / graph.agreement_fitness_ratio",
    "duplicate": "(duplicate scans: no threshold)",
    "no_pose": "(poses stage: no valid pose)",
}


#: Drop reasons of sampled scans (registration's own checks, after sampling).
SAMPLED_DROPS = ("low_prior_fitness", "low_icp_fitness", "icp_disagrees", "icp_failed")


class RegistrationError(ValueError):
    """No scan could be registered; the message counts the drops per reason and names
    the config threshold responsible for most of them."""



@dataclass
class RegistrationResult:
    """Output of :func:`floorscan.register.pipeline.register_scans` and
    :func:`floorscan.register.stream.register_recording`.

    Attributes
    ----------
    registered : pandas.DataFrame
        ``scan_id`` int32, ``x, y, z`` float32: points of the kept scans in the map frame
        (metres), in scan order.
    table : pandas.DataFrame
        One row per scan of the scan index, columns of :data:`REGISTRATION`.
    summary : dict
        Counts per reason, drop fractions per threshold, median corrections.
    """

    registered: pd.DataFrame | None
    table: pd.DataFrame
    summary: dict


@dataclass
class ScanRegistration:
    """What a registration strategy gives (thesis Algorithm 3 steps 4-6): one entry per
    scan of the scan index, ``S`` scans, in index order.

    A strategy (``(sampled, clouds, sids, t, cfg, initial) -> ScanRegistration``,
    :mod:`floorscan.register.pipeline`) starts from ``initial``
    (:meth:`before_registration`: the screening's reasons and the initial poses) and
    returns a new one; it changes no array of ``initial``.
    :func:`floorscan.register.pipeline.register_screened` makes the
    :data:`REGISTRATION` table of it.

    Attributes
    ----------
    kept : (S,) bool ndarray
        The scan is in the map.
    reason : (S,) object ndarray of str
        Drop reason (module docstring): ``""`` kept, ``"anchor"`` kept without a
        reference, else why the scan is not kept; the screening's reason for a scan the
        strategy did not register (``not_sampled`` is set by the caller).
    fitness_prior : (S,) float64 ndarray
        Fitness under the initial pose (step 4): the fraction of the scan's points with
        a reference point within the correspondence distance, 0 to 1, the mean over its
        references (``fitness_max_correspondence_m``,
        :func:`floorscan.register.icp.mean_fitness`; the pose graph: over its pairs,
        :func:`floorscan.register.posegraph.scan_fitness`); NaN: not measured.
    fitness_icp : (S,) float64 ndarray
        The same after ICP (step 6).
    inlier_rmse_m : (S,) float64 ndarray
        Root mean square distance of the inlier correspondences after ICP, metres;
        NaN: not measured.
    pose_correction : (S, 3) float64 ndarray
        ``dx, dy`` (metres, map frame) and ``dyaw`` (radians, in [-pi, pi)): the
        registered pose minus the initial one (the localizer's; odometry: the
        constant-velocity prediction), also for a scan then dropped by its fitness after
        ICP; 0 for an anchor, NaN: not registered.
    pose : (S, 4) float64 ndarray
        Final pose ``x, y, z, yaw`` (metres, radians; ``map_point = Rz(yaw) @ p + (x, y,
        z)``): the registered pose of a kept scan (the pose graph and odometry give one
        to the scans they drop, too), else the initial pose; NaN: none.
    sampled : (K,) int64 ndarray
        Index positions of the scans the strategy registered (the sampled scans),
        ascending.
    n_anchors : int
        Scans held by no reference: kept as ``anchor`` (``reference: previous`` and
        ``map``; odometry: the first scan), or without any edge in the pose graph (held
        by their prior only).
    """

    kept: np.ndarray
    reason: np.ndarray
    fitness_prior: np.ndarray
    fitness_icp: np.ndarray
    inlier_rmse_m: np.ndarray
    pose_correction: np.ndarray
    pose: np.ndarray
    sampled: np.ndarray
    n_anchors: int = 0

    @classmethod
    def before_registration(cls, reason: np.ndarray, pose: np.ndarray) -> "ScanRegistration":
        """Every scan before a strategy ran: not kept, nothing measured, the screening's
        ``reason`` ((S,) str) and the initial ``pose`` ((S, 4) float, NaN: none), both
        copied; nothing sampled."""
        n = len(reason)
        return cls(
            kept=np.zeros(n, dtype=bool),
            reason=np.array(reason, dtype=object),
            fitness_prior=np.full(n, np.nan),
            fitness_icp=np.full(n, np.nan),
            inlier_rmse_m=np.full(n, np.nan),
            pose_correction=np.full((n, 3), np.nan),
            pose=np.array(pose, dtype=np.float64).reshape(n, 4),
            sampled=np.zeros(0, dtype=np.int64),
        )

    def copy(self) -> "ScanRegistration":
        """A copy whose arrays are new (a strategy fills its copy of ``initial``)."""
        return dataclasses.replace(
            self, **{f.name: getattr(self, f.name).copy() for f in dataclasses.fields(self) if f.name != "n_anchors"}
        )


def summarize(table: pd.DataFrame, cfg: RegistrationConfig | None = None) -> dict:
    """Counts per reason (``counts``: every scan, ``""`` and ``"anchor"`` are kept;
    ``drops``: the scans not kept), fraction dropped by each threshold, median corrections.

    Drop fractions are given twice: of all scans (``fraction_of_scans``) and of the
    scans that reached the check (``fraction_of_checked``: sampled scans for the fitness
    thresholds, i.e. those passing the prior check for ``low_icp_fitness``).

    Returns
    -------
    dict
        JSON-serialisable.
    """
    reasons = table["reason"].str.replace(r"^no_pose:.*", "no_pose", regex=True)
    counts = dict(sorted(Counter(reasons).items()))
    drops = dict(sorted(Counter(reasons[~table["kept"].to_numpy(bool)]).items()))
    n = len(table)
    sampled = int(table["kept"].sum() + reasons.isin(list(SAMPLED_DROPS)).sum())
    n_prior = int((reasons == "low_prior_fitness").sum())
    n_icp = int((reasons == "low_icp_fitness").sum())
    n_disagree = int((reasons == "icp_disagrees").sum())
    checked_prior = int(table["fitness_prior"].notna().sum())
    checked_icp = int(table["fitness_icp"].notna().sum())
    registered = table["kept"] & table["fitness_icp"].notna()
    dxy = np.hypot(table.loc[registered, "dx_m"], table.loc[registered, "dy_m"])
    dyaw = np.abs(table.loc[registered, "dyaw_rad"])
    out = {
        "n_scans": n,
        "n_sampled": sampled,
        "n_kept": int(table["kept"].sum()),
        "n_registered": int(registered.sum()),
        "counts": counts,
        "drops": drops,
        "fraction_of_scans": {k: v / n for k, v in counts.items()} if n else {},
        "fraction_of_checked": {
            "low_prior_fitness": n_prior / checked_prior if checked_prior else 0.0,
            "low_icp_fitness": n_icp / checked_icp if checked_icp else 0.0,
            "icp_disagrees": n_disagree / checked_prior if checked_prior else 0.0,
        },
        "median_fitness_prior": float(table["fitness_prior"].median()) if checked_prior else math.nan,
        "median_fitness_icp": float(table["fitness_icp"].median()) if checked_icp else math.nan,
        "median_correction_m": float(np.median(dxy)) if len(dxy) else math.nan,
        "median_correction_rad": float(np.median(dyaw)) if len(dyaw) else math.nan,
        "p90_correction_m": float(np.percentile(dxy, 90)) if len(dxy) else math.nan,
    }
    if cfg is not None:
        out["config"] = dataclasses.asdict(cfg)
    return out


def raise_if_nothing_registered(table: pd.DataFrame, cfg: RegistrationConfig, summary: dict) -> None:
    """Raise :class:`RegistrationError` when no scan was registered: the counts per
    reason and the threshold behind most drops (:func:`worst_drop`)."""
    counts = summary["counts"]
    failures = {k: v for k, v in counts.items() if k not in ("", "anchor", "not_sampled")}
    n_kept = summary["n_kept"]
    checked = int(table["fitness_icp"].notna().sum() + (table["reason"] == "low_prior_fitness").sum())
    if n_kept > 0 and not (summary["n_registered"] == 0 and checked > 0):
        return
    if not failures:
        raise RegistrationError(f"register: no scans to register ({len(table)} scans in the index)")
    worst, option = worst_drop(failures, cfg)
    raise RegistrationError(
        f"register: no scan could be registered ({n_kept} kept without a reference) of "
        f"{len(table)}; drops per reason {failures}; most were dropped by '{worst}' (threshold {option})"
    )


def worst_drop(failures: Mapping[str, int], cfg: RegistrationConfig) -> tuple[str, str]:
    """The drop reason behind most lost scans and the option(s) that set it with their
    values (``register.min_prior_fitness=0.15``); ``("", "")`` without drops."""
    if not failures:
        return "", ""
    worst = max(failures, key=lambda k: failures[k])
    parts = REASON_THRESHOLD.get(worst, worst).split(" / ")
    return worst, " / ".join(_option(cfg, p) for p in parts)


def _option(cfg: RegistrationConfig, key: str) -> str:
    """``register.<key>=<value>`` (``graph.<name>`` read from the graph section);
    ``key`` itself when it is no option."""
    section, _, name = key.rpartition(".")
    obj = cfg.graph_params if section == "graph" else (cfg if not section else None)
    return f"register.{key}={getattr(obj, name)}" if obj is not None and hasattr(obj, name) else key


def judge(table: pd.DataFrame, clouds, cfg: RegistrationConfig, summary: dict, losses: Losses | None = None,
          fallback: str = "", stamps: str = ""):
    """The verdict on the registration (:func:`floorscan.register.consistency.verdict`):
    the map's consistency measured on each kept scan's ``clouds.map_cloud`` (a
    :class:`floorscan.register.prepare.ScanStore`) at its final pose; the scans lost
    before registration (``losses``, judged by ``register.max_lost_fraction``); why the
    scans were placed by LIDAR odometry (``fallback``); that ingest made the stamps up
    (``stamps``: :func:`floorscan.register.consistency.stamps_warning`)."""
    kept = table["kept"].to_numpy(bool)
    sids = table["scan_id"].to_numpy()[kept]
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)[kept]
    parts = [transform_points(clouds.map_cloud(int(s)), *f) for s, f in zip(sids, final)]
    cons, n_rev = map_consistency(parts, path_length_m(final[:, 0], final[:, 1]), final[:, :2])
    worst, option = worst_drop({k: v for k, v in summary["drops"].items() if k != "not_sampled"}, cfg)
    return verdict(
        summary["n_sampled"], summary["n_kept"], cons, n_rev, cfg.min_kept_fraction, cfg.min_consistency,
        worst, option, losses=losses, max_lost_fraction=cfg.max_lost_fraction, fallback=fallback, stamps=stamps,
    )
