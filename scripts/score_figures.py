"""Stage `score`, the last figures of a dataset: metrics against k (thesis Fig. 5.4)
and the time and memory of every stage (Table 5.1)."""

from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.figures.scoring import make_score_figures

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    make_score_figures(
        dataset=smk.wildcards.dataset,
        metrics=read_table(smk.input.metrics),
        bench_dir=smk.params.bench_dir,
        outputs=dict(smk.output.items()),
        cfg=smk.params.cfg,
        log=log,
    )
