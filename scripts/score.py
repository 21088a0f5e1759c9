"""Stage `score`: the metrics of every ordering x extractor x k (the extractors' tables
of scripts/score_runs.py, in one table) and the scan-reduction summary."""

import json

import pandas as pd
import pyarrow.parquet as pq

from floorscan import metrics
from floorscan.io import atomic_path, read_table, write_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg = smk.params.cfg
    table = metrics.sort_scores(pd.concat([read_table(p) for p in smk.input.runs], ignore_index=True))
    summary = metrics.summarize(table, cfg["summary_tau_m"], cfg["summary_levels"])
    log.info("%d runs scored; summary:\n%s", len(table), summary.to_string(index=False))
    meta = {"dataset": smk.wildcards.dataset, "reference_kind": smk.params.reference_kind,
            "reference": smk.params.reference_label}
    write_table(table, smk.output.metrics, metadata=meta)
    write_table(summary, smk.output.summary, metadata=meta)
    # what ingest detected and the register stage's verdict head the summary
    reg = {k.decode(): v.decode() for k, v in (pq.read_schema(smk.input.registration).metadata or {}).items()}
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    recording = json.loads(reg.get("recording", "{}"))
    if verdict:
        (log.info if verdict["ok"] and not verdict["warnings"] else log.warning)("verdict: %s", verdict["line"])
    with atomic_path(smk.output.summary_md) as tmp:
        tmp.write_text(
            metrics.summary_markdown(
                summary, cfg["summary_tau_m"], cfg["summary_levels"], verdict=verdict, recording=recording,
                mode=reg.get("mode", ""),
            )
        )
