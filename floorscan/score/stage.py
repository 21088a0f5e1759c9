"""The score stage's tables: every run's metrics in one table, the quality-vs-k summary
of the curves and ``summary.md`` (thesis Chapter 5; the ISPRS benchmark's completeness
and correctness against the reference map, :mod:`floorscan.score.against_reference`).

:func:`write_scores` is what ``scripts/score.py`` calls; the figure and the front page's
HTML table of the same summary are drawn by :mod:`floorscan.figures`.
"""

from __future__ import annotations

import json
import logging
import os
from dataclasses import dataclass
from typing import Mapping, Sequence

import pandas as pd

from floorscan.core.files import atomic_path
from floorscan.core.io import read_metadata, read_table, write_table
from floorscan.score.curve_summary import curve_summary, curve_summary_markdown
from floorscan.core.score_tables import beats_random_line
from floorscan.core.config import stage_params
from floorscan.score.params import ScoreParams
from floorscan.score.runs import sort_scores
from floorscan.score.summary import grid_summary_markdown, summarize

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Scores:
    """What :func:`write_scores` read and wrote, for the figures.

    Attributes
    ----------
    curves : DataFrame
        The quality-vs-k curves of every extractor (column ``extractor`` added).
    summary : DataFrame
        Per ordering and extractor: k95, k99, AUC, the oracle's ratio (``summary.parquet``).
    n_kept : int
        Kept scans of the dataset.
    beats_random : str
        The line saying whether the recommended and the thesis's ordering beat random.
    verdict : dict or None
        The register stage's verdict (``ok``, ``warnings``, ``line``), when it wrote one.
    """

    curves: pd.DataFrame
    summary: pd.DataFrame
    n_kept: int
    beats_random: str
    verdict: dict | None


def write_scores(
    runs: Sequence[str | os.PathLike],
    curves: Sequence[str | os.PathLike],
    index: str | os.PathLike,
    registration: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    cfg: Mapping,
    dataset: str,
    default_ordering: str,
    reference: Mapping[str, str],
) -> Scores:
    """Write ``metrics.parquet``, ``summary.parquet`` and ``evaluation/summary.md`` (the
    evaluation's part of ``summary.md``) of a dataset.

    Parameters
    ----------
    runs : paths
        The scores table of each extractor (rule ``score_runs``).
    curves : paths
        The quality-vs-k curves of each extractor (rule ``score_curves``); their
        metadata names the extractor.
    index, registration : path
        ``scan_index.parquet`` (what ingest detected; the recorded scans) and
        ``registration.parquet`` (the register stage's verdict in its metadata).
    outputs : mapping
        Paths ``metrics``, ``summary`` and ``summary_md``.
    cfg : ScoreParams or mapping
        The ``score`` config section (``summary_tau_m``, ``summary_levels``,
        ``curve_auc_fraction``).
    dataset, default_ordering : str
        The dataset, and the ordering the selection recommends (shown first).
    reference : mapping
        ``kind`` and ``label`` of the reference the runs were scored against.

    Returns
    -------
    Scores
    """
    cfg = stage_params(ScoreParams, cfg)
    tau = float(cfg.summary_tau_m)
    table = sort_scores(pd.concat([read_table(p) for p in runs], ignore_index=True))
    grid_summary = summarize(table, tau, cfg.summary_levels)
    meta = {"dataset": dataset, "reference_kind": reference["kind"], "reference": reference["label"]}
    write_table(table, outputs["metrics"], metadata=meta)
    # the curves of every extractor: k95 / k99, area under the curve, the oracle's bound
    frames = [read_table(p).assign(extractor=read_metadata(p)["extractor"]) for p in curves]
    curve_table = pd.concat(frames, ignore_index=True)
    n_kept, n_recorded = int(curve_table["n_kept"].iloc[0]), len(read_table(index, columns=["scan_id"]))
    summary = curve_summary(curve_table, n_kept, n_recorded, tau, tuple(cfg.summary_levels),
                            float(cfg.curve_auc_fraction))
    summary.insert(0, "dataset", dataset)
    # the recommended ordering first, then the thesis's (Algorithm 1)
    shown = list(dict.fromkeys([default_ordering, "cluster_hull"]))
    line = " ".join(beats_random_line(summary, o, e) for o in shown for e in sorted(set(curve_table["extractor"])))
    log.info("%s\n%s", line, summary.to_string(index=False))
    write_table(summary, outputs["summary"], metadata={**meta, "reference": "the reference map (occupancy grid)",
                                                        "beats_random": line})
    # the register stage's verdict and what ingest detected head the summary
    reg = read_metadata(registration)
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    if verdict:
        (log.info if verdict["ok"] and not verdict["warnings"] else log.warning)("verdict: %s", verdict["line"])
    with atomic_path(outputs["summary_md"]) as tmp:  # the evaluation's part of summary.md (rule front_page)
        tmp.write_text("## Floor plans against the reference map\n\n"
                       + curve_summary_markdown(summary, tau, n_kept, n_recorded, line)
                       + "\n## Walls of k scans on the configured k grid\n\n"
                       + grid_summary_markdown(grid_summary, tau, cfg.summary_levels))
    return Scores(curve_table, summary, n_kept, line, verdict)


def write_run_scores(
    inputs: Mapping,
    runs: Sequence[Sequence],
    orderings: Sequence[str],
    output: str | os.PathLike,
    cfg: Mapping,
    dataset: str,
    extractor: str,
    reference: Mapping[str, str],
    extractors: Sequence[str],
    workers: int = 1,
) -> pd.DataFrame:
    """Score every wall set and floor plan of one extractor (rule ``score_runs``) and write
    the table: the thesis's bitmap CM/FP/FN (section 5.1) and the tolerance metrics
    against the ground truth or reference walls (:func:`floorscan.score.runs.score_dataset`),
    and each plan against the reference map (:func:`floorscan.score.against_reference.score_plans`).

    Parameters
    ----------
    inputs : mapping
        The rule's inputs: ``walls`` and ``floorplans`` (one per run, in ``runs`` order),
        ``orderings`` (one per ordering), ``reference_map``, and ``ground_truth`` or
        ``reference`` (the reference walls of every extractor).
    runs : sequence of [ordering, extractor, k label]
    orderings : sequence of str
        The orderings of ``inputs["orderings"]``.
    output : path
        The table (``score/<extractor>.parquet``).
    cfg : ScoreParams or mapping
        The ``score`` config section.
    dataset, extractor : str
    reference : mapping
        ``kind`` (ground truth or reference) and ``label``.
    extractors : sequence of str
        Every extractor of the dataset: the bitmap grid spans all their references.
    workers : int
        Processes for the scoring (the rule's threads).

    Returns
    -------
    DataFrame
        The table written (one row per run).
    """
    cfg = stage_params(ScoreParams, cfg)
    from floorscan.score.against_reference import read_reference, score_plans
    from floorscan.core.plan_tables import plan_faces_and_walls
    from floorscan.score.ground_truth import load_recall_references, load_references
    from floorscan.score.runs import SCORE_TIME, score_dataset

    kind = reference["kind"]
    references = load_references(kind, list(extractors), inputs.get("ground_truth"), inputs.get("reference", []))
    recall_refs = load_recall_references(kind, list(extractors), inputs.get("ground_truth"), cfg.recall_reference)
    log.info("scoring %s against the %s: %s", extractor, reference["label"], {e: len(s) for e, s in references.items()})
    if recall_refs is not None:
        log.info("recall against the %s features: %s segments", cfg.recall_reference,
                 {e: len(s) for e, s in recall_refs.items()})
    n_kept = {o: len(read_table(p, columns=["scan_id"])) for o, p in zip(orderings, inputs["orderings"])}
    # the walls as paths, not tables: score_dataset reads one run's walls at a time; the
    # plans (a few hundred faces each) are read once for both scorings
    plans = {fp: plan_faces_and_walls(fp) for fp in dict.fromkeys(inputs["floorplans"])}
    run_files = [
        {"ordering": o, "extractor": e, "k": k, "walls": wp, "n_kept": n_kept[o], "floorplan": fp,
         "floorplan_faces": plans[fp][0], "n_floorplan_walls": plans[fp][1]}
        for (o, e, k), wp, fp in zip(runs, inputs["walls"], inputs["floorplans"], strict=True)
    ]
    table = score_dataset(run_files, references, kind, cfg, dataset, log, recall_references=recall_refs,
                          workers=workers)
    # the plans against the reference map (occupancy grid of all kept scans)
    against_map = score_plans(run_files, read_reference(inputs["reference_map"]), tuple(cfg.taus_m),
                              lambda path: plans[path][0])
    table = table.merge(against_map, on=["ordering", "extractor", "k"], how="left", validate="one_to_one")
    # the time of each run to the log, not into the metrics (the same input gives the same file)
    seconds = table.pop(SCORE_TIME)
    if len(seconds):
        slowest = int(seconds.to_numpy().argmax())
        log.info("scored %d runs in %.2f s, the slowest %.2f s (%s)", len(table), seconds.sum(), seconds.iloc[slowest],
                 "/".join(str(table[c].iloc[slowest]) for c in ("ordering", "extractor", "k")))
    meta = {"dataset": dataset, "reference_kind": kind, "reference": reference["label"], "extractor": extractor}
    write_table(table, output, metadata=meta)
    return table
