"""The per-run scores table of a dataset (``score/<extractor>.parquet``, merged into
``metrics.parquet``): one row per ordering x extractor x k.

:func:`score_dataset` scores every run's walls with the bitmap metrics (thesis section
5.1, :mod:`floorscan.score.bitmap`) and the tolerance metrics (ISPRS benchmark,
:mod:`floorscan.score.tolerance`), and its floor plan's faces with the latter
(``plan_*`` columns); the runs of one ordering and extractor in increasing k are scored
incrementally (:class:`floorscan.score.growing.GrowingWalls`). The orderings x
extractors are split over processes by :func:`floorscan.core.runtime.map_in_processes`
(the only process pool of the score package); the table does not depend on their
number. :func:`sort_scores` orders the rows (and the concatenated tables of the
per-extractor jobs) as one call over all runs would.

The runs themselves: :func:`run_grid` lists the wall files scored (every ordering x
extractor x k of the walls stage), :func:`figure_runs` and :func:`figure_floorplans`
those the figures draw (the ``score.figure_*`` keys); the workflow passes them to the
jobs through ``params:`` (``workflow/rules/score.smk``, ``figures.smk``).
"""

from __future__ import annotations

import math
import os
from typing import Mapping

import numpy as np

from floorscan.core.segment_raster import grid_for, rasterize_segments
from floorscan.core.plan_tables import plan_faces_and_walls
from floorscan.core.score_tables import GROUND_TRUTH, REFERENCE
from floorscan.score.growing import PAIR_REACH_M, GrowingWalls, SamplePairs
from floorscan.core.config import stage_params
from floorscan.score.params import ScoreParams
from floorscan.score.segments import gt_samples
from floorscan.core.segments import as_segments
from floorscan.score.tolerance import recall_precision
from floorscan.core.score_tables import tau_label


def run_grid(orderings, extractors, ks) -> list[list[str]]:
    """``[ordering, extractor, k label]`` of every wall file scored: orderings outermost,
    then extractors, then k in the order given.

    Parameters
    ----------
    orderings, extractors : iterable of str
        ``walls.orderings``, ``walls.extractors``.
    ks : iterable of int or str
        ``walls.k``.

    Returns
    -------
    list of list of str
        k labels as strings, "5" or "all".
    """
    return [[o, e, str(k)] for o in orderings for e in extractors for k in ks]


def figure_runs(cfg: Mapping, extractors) -> list[list]:
    """``[ordering, extractor, k label]`` of the wall files the figures draw: every
    extractor at ``cfg["figure_k"]`` and "all", for ``cfg["figure_orderings"]`` and then
    ``cfg["figure_ordering"]`` (each ordering once, in that order).

    Parameters
    ----------
    cfg : mapping
        The ``score`` config section.
    extractors : iterable of str

    Returns
    -------
    list of list of str

    Raises
    ------
    KeyError
        When ``cfg`` lacks one of those keys.
    """
    k = str(cfg["figure_k"])
    orderings = list(dict.fromkeys(list(cfg["figure_orderings"]) + [cfg["figure_ordering"]]))
    return [[o, e, kk] for o in orderings for e in extractors for kk in (k, "all")]


def figure_floorplans(cfg: Mapping) -> list[list]:
    """``[ordering, extractor]`` of the floor plans at ``figure_k`` that the figures
    draw (thesis Fig. 5.5): ``cfg["figure_orderings"]`` with ``cfg["figure_extractor"]``.

    Parameters
    ----------
    cfg : mapping
        The ``score`` config section.

    Returns
    -------
    list of list of str
    """
    return [[o, cfg["figure_extractor"]] for o in cfg["figure_orderings"]]


def k_scans(k_label: str, n_kept: int) -> int:
    """Number of scans behind ``k{k_label}``: ``min(k, n_kept)``, ``n_kept`` for "all".

    Parameters
    ----------
    k_label : str
        ``"all"`` or an integer.
    n_kept : int

    Returns
    -------
    int

    Raises
    ------
    ValueError
        When ``k_label`` is neither.
    """
    if str(k_label) == "all":
        return int(n_kept)
    return min(int(k_label), int(n_kept))


def score_dataset(
    runs: list[dict],
    references: dict[str, np.ndarray],
    reference_kind: str,
    cfg: "ScoreParams | Mapping",
    dataset: str = "",
    log=None,
    recall_references: dict[str, np.ndarray] | None = None,
    workers: int = 1,
):
    """Score every ordering x extractor x k of a dataset: one row per run.

    Parameters
    ----------
    runs : list of dict
        One per wall file, with keys ``ordering``, ``extractor``, ``k`` (label: "5" or
        "all"), ``walls`` (DataFrame with x0, y0, x1, y1, or the path of its Parquet
        table, read when the run is scored so that one run's walls are in memory at a
        time), ``n_kept`` (scans the ordering ranks, i.e. kept scans) and
        ``n_floorplan_walls`` (int or None); optionally ``floorplan_faces``, the merged
        faces of the run's floor plan (``(F, 4)`` segments), scored with the same
        tolerance metrics into the ``plan_precision_<tau>``, ``plan_recall_<tau>`` and
        ``plan_f1_<tau>`` columns (one wall per wall: the product a user opens, not the
        per-scan segments); or ``floorplan``, the plan's Parquet folder (:mod:`floorscan.core.plan_tables`), from
        which both are read when the run is scored (unless ``floorplan_faces`` is
        given too). Runs of one ordering and extractor
        in increasing k (each wall set containing the previous one) are scored
        incrementally, from the new walls only, with the same result. The last run of
        an ordering whose walls (as a set) and plan faces equal an earlier run's of
        its extractor (every ordering's ``k = all``) takes that run's metrics.
    references : dict
        ``{extractor: (M, 4) segments}``: what each extractor's walls are scored
        against. On synthetic datasets every extractor maps to the same ground truth
        (``sim/walls.geojson`` faces); on real ones to the walls of that extractor from
        all kept scans.
    reference_kind : {"ground_truth", "reference"}
        Written to the ``reference_kind`` column.
    cfg : ScoreParams or mapping
        The ``score`` config section: ``cell_m``, ``wall_width_m``, ``margin_m``,
        ``taus_m``, ``sample_step_m``.
    dataset : str
        Written to the ``dataset`` column.
    recall_references : dict, optional
        ``{extractor: (M, 4) segments}`` that recall (completeness) and the distances
        are measured against instead of ``references``: on synthetic datasets the
        observed faces (:func:`floorscan.sim.ground_truth.observed_faces`; thesis 5.2, walls
        never visible from the LIDAR cannot be recovered). Precision and the bitmap
        metrics stay against ``references``, and ``recall_all_<tau>`` gives recall
        against ``references`` too.
    workers : int
        Processes (:func:`floorscan.core.runtime.map_in_processes`; the score rule's
        ``threads``) over which the orderings x extractors are split. Each ordering and
        extractor is scored in one process, so the table does not depend on it
        (tested); the walls are then best given as paths (runs are pickled to the
        workers). The per-run lines are logged when all are scored.

    Returns
    -------
    pandas.DataFrame
        One row per run, sorted by ordering, extractor and number of scans; its
        :data:`SCORE_TIME` column is the seconds the run took (not a metric).

    Raises
    ------
    ValueError
        When ``reference_kind`` is unknown, a run's extractor has no reference, or the
        references are all empty (no grid can be built).
    """
    cfg = stage_params(ScoreParams, cfg)
    import pandas as pd

    if reference_kind not in (GROUND_TRUTH, REFERENCE):
        raise ValueError(f"reference_kind must be {GROUND_TRUTH!r} or {REFERENCE!r}")
    groups: dict[tuple, list[dict]] = {}
    for run in runs:
        groups.setdefault((run["ordering"], run["extractor"]), []).append(run)
    keys = list(groups)
    n = max(1, min(int(workers), len(keys)))
    args = (references, reference_kind, cfg, dataset, recall_references)
    if n == 1:
        rows = _score_rows(runs, *args)
    else:
        from floorscan.core.runtime import map_in_processes

        shares = [[r for key in keys[w::n] for r in groups[key]] for w in range(n)]
        rows = [row for part in map_in_processes(_score_rows, [(share, *args) for share in shares], n) for row in part]
    df = sort_scores(pd.DataFrame(rows))
    if log is not None:
        tau = tau_label(cfg.taus_m[0])
        for r in rows:
            log.info("%s %s k=%s: %d segments, F1@%s %.3f, wall CM %.3f", r["ordering"], r["extractor"], r["k"],
                     r["n_segments"], tau, r[f"f1_{tau}"], r["wall_correct_match"])
    return df


def sort_scores(table):
    """Metrics rows in the order of :func:`score_dataset`: by ordering, extractor,
    number of scans and k label (a new frame, index 0..n-1). Concatenated tables of
    parts of a dataset's runs (the ``score_runs`` jobs, one per extractor) sorted so
    equal the table of one :func:`score_dataset` call over all runs.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :func:`score_dataset` (empty allowed).

    Returns
    -------
    pandas.DataFrame
    """
    if not table.empty:
        table = table.sort_values(["ordering", "extractor", "n_scans", "k"], kind="stable")
    return table.reset_index(drop=True)


def _score_rows(runs, references, reference_kind, cfg, dataset, recall_references) -> list[dict]:
    """The rows of :func:`score_dataset` of ``runs``, in run order (one process)."""
    import time

    refs = {e: as_segments(s) for e, s in references.items()}
    nonempty = [s for s in refs.values() if len(s)]
    if not nonempty:
        raise ValueError(f"dataset {dataset!r}: every {reference_kind} wall set is empty")
    # One grid for the whole dataset: the bounds of all references plus the margin.
    grid = grid_for(np.vstack(nonempty), cfg.cell_m, cfg.margin_m)
    ref_bitmaps: dict[str, np.ndarray] = {}
    ref_samples: dict[str, np.ndarray] = {}
    all_samples: dict[str, np.ndarray] = {}
    growing: dict[tuple[str, str], GrowingWalls] = {}
    sample_pairs: dict[str, SamplePairs] = {}
    all_pairs: dict[str, SamplePairs | None] = {}
    raster_caches: dict[str, dict] = {}
    # A run with the same walls and floor plan as an earlier one of its extractor (every
    # ordering's k = all: the same scans) has its metrics; when no larger k of its
    # ordering follows, they are taken, not computed again from its growing state.
    last_of_group = {(r["ordering"], r["extractor"]): n for n, r in enumerate(runs)}
    scored: dict[tuple, dict] = {}
    rows = []
    for n_run, run in enumerate(runs):
        ext = run["extractor"]
        if ext not in refs:
            raise ValueError(f"no {reference_kind} walls for extractor {ext!r}")
        if recall_references is not None and ext not in recall_references:
            raise ValueError(f"no recall reference walls for extractor {ext!r}")
        if ext not in ref_bitmaps:
            ref_bitmaps[ext] = rasterize_segments(refs[ext], grid, cfg.wall_width_m)
            all_samples[ext] = gt_samples(refs[ext], cfg.sample_step_m)
            ref_samples[ext] = (
                all_samples[ext] if recall_references is None
                else gt_samples(as_segments(recall_references[ext]), cfg.sample_step_m)
            )
            # Shared by the orderings of an extractor: its samples' pairs and wall cells.
            sample_pairs[ext] = SamplePairs(ref_samples[ext], PAIR_REACH_M)
            all_pairs[ext] = (
                None if recall_references is None else SamplePairs(all_samples[ext], max(cfg.taus_m))
            )
            raster_caches[ext] = {}
        t0 = time.perf_counter()
        walls = run["walls"]
        if isinstance(walls, (str, os.PathLike)):
            from floorscan.core.io import read_table

            walls = read_table(walls, columns=["x0", "y0", "x1", "y1"])
        walls = as_segments(walls)
        plan_path = run.get("floorplan")
        if plan_path is not None and run.get("floorplan_faces") is None:
            plan, nfp = plan_faces_and_walls(plan_path)
        else:
            plan, nfp = run.get("floorplan_faces"), run.get("n_floorplan_walls")
        same = (ext, _set_digest(walls), None if plan is None else _set_digest(as_segments(plan)))
        key = (run["ordering"], ext)
        m = scored.get(same) if last_of_group[key] == n_run else None
        if m is not None:
            growing.pop(key, None)  # the ordering's last run: its state is not needed again
            rows.append(_score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, dict(m), t0))
            continue
        if key not in growing:
            # One state per ordering and extractor: its k grow in the order of runs.
            growing[key] = GrowingWalls(
                refs[ext], ref_bitmaps[ext], grid, cfg.wall_width_m, cfg.taus_m,
                ref_samples[ext],
                None if recall_references is None else all_samples[ext],
                pairs=sample_pairs[ext], all_pairs=all_pairs[ext], raster_cache=raster_caches[ext],
            )  # fmt: skip
        m = growing[key].score(walls)
        if plan is not None:
            pm = recall_precision(plan, refs[ext], cfg.taus_m, ref_samples[ext], pairs=sample_pairs[ext])
            for tau in cfg.taus_m:
                for what in ("precision", "recall", "f1"):
                    m[f"plan_{what}_{tau_label(tau)}"] = pm[f"{what}_{tau_label(tau)}"]
        scored.setdefault(same, dict(m))
        if last_of_group[key] == n_run:  # its bitmap and distances are not needed again
            growing.pop(key)
        rows.append(_score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, m, t0))
    return rows


#: Column of :func:`score_dataset`'s rows: the seconds the run took to score. For the
#: stage's log; the score stage leaves it out of ``metrics.parquet`` (the same input
#: gives the same file).
SCORE_TIME = "score_time_s"


def _score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, m: dict, t0: float) -> dict:
    import time

    n_kept = int(run["n_kept"])
    n_scans = k_scans(run["k"], n_kept)
    return {
        "dataset": dataset,
        "reference_kind": reference_kind,
        "ordering": run["ordering"],
        "extractor": run["extractor"],
        "k": str(run["k"]),
        "n_scans": n_scans,
        "n_scans_kept": n_kept,
        "scan_fraction": n_scans / n_kept if n_kept else math.nan,
        "n_segments": int(len(walls)),
        "n_floorplan_walls": -1 if nfp is None else int(nfp),
        "cell_m": float(grid.cell_m),
        "wall_width_m": float(cfg.wall_width_m),
        **m,
        SCORE_TIME: time.perf_counter() - t0,
    }


def _set_digest(segments: np.ndarray) -> bytes:
    """Digest of a set of segments (rows in any order)."""
    import hashlib

    seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    seg = seg[np.lexsort(seg.T[::-1])] if len(seg) else seg
    return hashlib.sha256(seg.tobytes()).digest()
