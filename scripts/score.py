"""Stage `score`: the metrics of every ordering x extractor x k (the extractors' tables
of scripts/score_runs.py, in one table), the quality-vs-k summary of the curves
(scripts/score_curves.py) and its figure, and summary.md / summary.html."""

import json

import pandas as pd

from floorscan.core.io import atomic_path, read_metadata, read_table, write_table
from floorscan.core.stage import stage_log
from floorscan.figures.curves import plot_quality_vs_k
from floorscan.figures.report import summary_table_html
from floorscan.score import curves as C
from floorscan.score.runs import sort_scores
from floorscan.score.summary import grid_summary_markdown, summarize, summary_header

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg = smk.params.cfg
    dataset = smk.wildcards.dataset
    tau = float(cfg["summary_tau_m"])
    table = sort_scores(pd.concat([read_table(p) for p in smk.input.runs], ignore_index=True))
    grid_summary = summarize(table, tau, cfg["summary_levels"])
    meta = {"dataset": dataset, "reference_kind": smk.params.reference_kind, "reference": smk.params.reference_label}
    write_table(table, smk.output.metrics, metadata=meta)
    # the curves of every extractor: k95 / k99, area under the curve, the oracle's bound
    curves = pd.concat([read_table(p).assign(extractor=read_metadata(p)["extractor"]) for p in smk.input.curves],
                       ignore_index=True)
    n_kept, n_recorded = int(curves["n_kept"].iloc[0]), len(read_table(smk.input.index, columns=["scan_id"]))
    summary = C.curve_summary(curves, n_kept, n_recorded, tau, tuple(cfg["summary_levels"]),
                              float(cfg["curve_auc_fraction"]))
    summary.insert(0, "dataset", dataset)
    # the recommended ordering first, then the thesis's (Algorithm 1)
    shown = list(dict.fromkeys([smk.params.default_ordering, "cluster_hull"]))
    line = " ".join(C.beats_random_line(summary, o, e) for o in shown for e in sorted(set(curves["extractor"])))
    log.info("%s\n%s", line, summary.to_string(index=False))
    write_table(summary, smk.output.summary, metadata={**meta, "reference": "the reference map (occupancy grid)",
                                                        "beats_random": line})
    plot_quality_vs_k(curves, smk.output.quality_vs_k, tau, float(cfg["curve_auc_fraction"]),
                      title=f"{dataset}: floor-plan F1 against k")
    # the register stage's verdict and what ingest detected head the summary
    reg = read_metadata(smk.input.registration)
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    if verdict:
        (log.info if verdict["ok"] and not verdict["warnings"] else log.warning)("verdict: %s", verdict["line"])
    head = summary_header(dataset, verdict, read_metadata(smk.input.index), reg.get("mode", ""))
    with atomic_path(smk.output.summary_md) as tmp:
        tmp.write_text("\n".join(head) + "\n## Floor plans against the reference map\n\n"
                       + C.summary_markdown(summary, tau, n_kept, n_recorded, line)
                       + "\n## Walls of k scans on the configured k grid\n\n"
                       + grid_summary_markdown(grid_summary, tau, cfg["summary_levels"]))
    with atomic_path(smk.output.summary_html) as tmp:  # the front page's table, on its own
        tmp.write_text(
            f"<html><head><meta charset='utf-8'><title>{dataset} summary</title></head><body>"
            f"<h1>{dataset}</h1>"
            + (f"<p><b>Verdict: {verdict['line']}</b></p>" if verdict else "")
            + f"<p>{line}</p>"
            + summary_table_html(summary, n_kept, smk.params.default_ordering)
            + "</body></html>\n"
        )
