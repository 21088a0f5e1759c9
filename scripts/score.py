"""Stage `score`: the metrics of every ordering x extractor x k (the extractors' tables
of scripts/score_runs.py, in one table), the quality-vs-k summary of the curves
(scripts/score_curves.py) and its figure, and summary.md / summary.html."""

import json

import pandas as pd
import pyarrow.parquet as pq

from floorscan import metrics
from floorscan.figures_scoring import plot_quality_vs_k
from floorscan.io import atomic_path, read_table, write_table
from floorscan.score import curves as C
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg = smk.params.cfg
    tau = float(cfg["summary_tau_m"])
    table = metrics.sort_scores(pd.concat([read_table(p) for p in smk.input.runs], ignore_index=True))
    grid_summary = metrics.summarize(table, tau, cfg["summary_levels"])
    meta = {"dataset": smk.wildcards.dataset, "reference_kind": smk.params.reference_kind,
            "reference": smk.params.reference_label}
    write_table(table, smk.output.metrics, metadata=meta)
    # the curves of every extractor: k95 / k99, area under the curve, the oracle's bound
    extractors = [pq.read_schema(p).metadata[b"extractor"].decode() for p in smk.input.curves]
    curves = pd.concat([read_table(p).assign(extractor=e) for e, p in zip(extractors, smk.input.curves)],
                       ignore_index=True)
    registration = read_table(smk.input.registration, columns=["scan_id"])
    n_kept, n_recorded = int(curves["n_kept"].iloc[0]), len(registration)
    summary = C.curve_summary(curves, n_kept, n_recorded, tau, tuple(cfg["summary_levels"]),
                              float(cfg["curve_auc_fraction"]))
    summary.insert(0, "dataset", smk.wildcards.dataset)
    line = " ".join(C.beats_random_line(summary, "cluster_hull", e) for e in sorted(set(extractors)))
    log.info("%s\n%s", line, summary.to_string(index=False))
    write_table(summary, smk.output.summary, metadata={**meta, "reference": "the reference map (occupancy grid)",
                                                        "beats_random": line})
    plot_quality_vs_k(curves, smk.output.quality_vs_k, tau, float(cfg["curve_auc_fraction"]),
                      title=f"{smk.wildcards.dataset}: floor-plan F1 against k")
    # what ingest detected and the register stage's verdict head the summary
    reg = {k.decode(): v.decode() for k, v in (pq.read_schema(smk.input.registration).metadata or {}).items()}
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    recording = json.loads(reg.get("recording", "{}"))
    if verdict:
        (log.info if verdict["ok"] and not verdict["warnings"] else log.warning)("verdict: %s", verdict["line"])
    older = metrics.summary_markdown(grid_summary, tau, cfg["summary_levels"], verdict=verdict,
                                     recording=recording, mode=reg.get("mode", ""))
    head, _, rest = older.partition("\nF1 at tau")
    with atomic_path(smk.output.summary_md) as tmp:
        older_section = "\n## Walls of k scans on the configured k grid\n\nF1 at tau" + rest if rest else ""
        tmp.write_text(head + "\n## Floor plans against the reference map\n\n"
                       + C.summary_markdown(summary, tau, n_kept, n_recorded, line) + older_section)
    with atomic_path(smk.output.summary_html) as tmp:
        cols = ["extractor", "ordering", "f1_all", "k_95", "fraction_kept_95", "fraction_recorded_95", "k_99",
                "fraction_kept_99", "fraction_recorded_99", "auc", "auc_seed_sd", "k95_over_oracle"]
        tmp.write_text(
            f"<html><head><meta charset='utf-8'><title>{smk.wildcards.dataset} summary</title></head><body>"
            f"<h1>{smk.wildcards.dataset}</h1>"
            + (f"<p><b>Verdict: {verdict['line']}</b></p>" if verdict else "")
            + f"<p>{line}</p>"
            + summary[cols].to_html(index=False, float_format=lambda v: f"{v:.3f}", na_rep="-")
            + "</body></html>\n"
        )
