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
from floorscan.score import curves as C
from floorscan.score.runs import sort_scores
from floorscan.score.summary import grid_summary_markdown, summarize, summary_header

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
    """Write ``metrics.parquet``, ``summary.parquet`` and ``summary.md`` of a dataset.

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
    cfg : mapping
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
    tau = float(cfg["summary_tau_m"])
    table = sort_scores(pd.concat([read_table(p) for p in runs], ignore_index=True))
    grid_summary = summarize(table, tau, cfg["summary_levels"])
    meta = {"dataset": dataset, "reference_kind": reference["kind"], "reference": reference["label"]}
    write_table(table, outputs["metrics"], metadata=meta)
    # the curves of every extractor: k95 / k99, area under the curve, the oracle's bound
    frames = [read_table(p).assign(extractor=read_metadata(p)["extractor"]) for p in curves]
    curve_table = pd.concat(frames, ignore_index=True)
    n_kept, n_recorded = int(curve_table["n_kept"].iloc[0]), len(read_table(index, columns=["scan_id"]))
    summary = C.curve_summary(curve_table, n_kept, n_recorded, tau, tuple(cfg["summary_levels"]),
                              float(cfg["curve_auc_fraction"]))
    summary.insert(0, "dataset", dataset)
    # the recommended ordering first, then the thesis's (Algorithm 1)
    shown = list(dict.fromkeys([default_ordering, "cluster_hull"]))
    line = " ".join(C.beats_random_line(summary, o, e) for o in shown for e in sorted(set(curve_table["extractor"])))
    log.info("%s\n%s", line, summary.to_string(index=False))
    write_table(summary, outputs["summary"], metadata={**meta, "reference": "the reference map (occupancy grid)",
                                                        "beats_random": line})
    # the register stage's verdict and what ingest detected head the summary
    reg = read_metadata(registration)
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    if verdict:
        (log.info if verdict["ok"] and not verdict["warnings"] else log.warning)("verdict: %s", verdict["line"])
    head = summary_header(dataset, verdict, read_metadata(index), reg.get("mode", ""))
    with atomic_path(outputs["summary_md"]) as tmp:
        tmp.write_text("\n".join(head) + "\n## Floor plans against the reference map\n\n"
                       + C.summary_markdown(summary, tau, n_kept, n_recorded, line)
                       + "\n## Walls of k scans on the configured k grid\n\n"
                       + grid_summary_markdown(grid_summary, tau, cfg["summary_levels"]))
    return Scores(curve_table, summary, n_kept, line, verdict)
