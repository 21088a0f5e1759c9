"""Stage `score`: the metrics of every ordering x extractor x k (the extractors' tables
of scripts/score_runs.py, in one table), the quality-vs-k summary of the curves
(scripts/score_curves.py) and its figure, and summary.md / summary.html."""

from floorscan.core.config import stage_params
from floorscan.core.stage import stage_log
from floorscan.score.params import ScoreParams
from floorscan.figures.curves import plot_quality_vs_k
from floorscan.figures.summary_page import write_summary_page
from floorscan.score.stage import write_scores

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg, dataset = stage_params(ScoreParams, smk.params.cfg), smk.wildcards.dataset
    scores = write_scores(
        smk.input.runs, smk.input.curves, smk.input.index, smk.input.registration, smk.output, cfg, dataset,
        smk.params.default_ordering, {"kind": smk.params.reference_kind, "label": smk.params.reference_label},
    )
    plot_quality_vs_k(scores.curves, smk.output.quality_vs_k, float(cfg.summary_tau_m),
                      float(cfg.curve_auc_fraction), title=f"{dataset}: floor-plan F1 against k")
    write_summary_page(smk.output.summary_html, dataset, scores.summary, scores.n_kept, scores.beats_random,
                       scores.verdict, smk.params.default_ordering)
