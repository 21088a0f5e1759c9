"""Stage `score`, one extractor: metrics of its walls for every ordering x k (thesis
section 5.1 and ISPRS-style tolerance metrics) and of its floor plans against the
reference map. scripts/score.py merges the extractors and writes the scan-reduction
summary."""

# With threads above 1 the orderings are scored in spawned worker processes: each imports
# this script again (as __mp_main__), and must not run the stage.
if __name__ == "__main__":
    from floorscan.core.stage import stage_log
    from floorscan.score.stage import write_run_scores

    with stage_log(snakemake):  # noqa: F821
        smk = snakemake  # noqa: F821
        write_run_scores(
            dict(smk.input.items()), smk.params.runs, smk.params.orderings, smk.output.metrics, smk.params.cfg,
            smk.wildcards.dataset, smk.wildcards.extractor,
            {"kind": smk.params.reference_kind, "label": smk.params.reference_label},
            smk.params.extractors, workers=smk.threads,
        )
