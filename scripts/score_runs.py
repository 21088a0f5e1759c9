"""Stage `score`, one extractor: metrics of its walls for every ordering x k (thesis
section 5.1 and ISPRS-style tolerance metrics). scripts/score.py merges the
extractors and writes the scan-reduction summary."""

from floorscan.score import metrics
from floorscan.core.io import read_table, write_table
from floorscan.score.against_reference import score_plans
from floorscan.score.reference import read_grid
from floorscan.core.stage import stage_log

# With threads above 1 the orderings are scored in spawned worker processes: each imports
# this script again (as __mp_main__), and must not run the stage.
if __name__ == "__main__":
    with stage_log(snakemake) as log:  # noqa: F821
        smk = snakemake  # noqa: F821
        cfg = smk.params.cfg
        kind = smk.params.reference_kind
        # every extractor's reference: the bitmap grid spans all of them, as in one job
        extractors = list(smk.params.extractors)
        references = metrics.load_references(
            kind, extractors, smk.input.get("ground_truth"), smk.input.get("reference", [])
        )
        recall_refs = metrics.load_recall_references(
            kind, extractors, smk.input.get("ground_truth"), cfg["recall_reference"]
        )
        log.info("scoring %s against the %s: %s", smk.wildcards.extractor, smk.params.reference_label,
                 {e: len(s) for e, s in references.items()})
        if recall_refs is not None:
            log.info("recall against the %s features: %s segments", cfg["recall_reference"],
                     {e: len(s) for e, s in recall_refs.items()})
        n_kept = {o: len(read_table(p, columns=["scan_id"]))
                  for o, p in zip(smk.params.orderings, smk.input.orderings)}
        # Paths, not tables: score_dataset reads one run's walls and floor plan at a time.
        runs = [
            {"ordering": o, "extractor": e, "k": k, "walls": wp, "n_kept": n_kept[o], "floorplan": fp}
            for (o, e, k), wp, fp in zip(smk.params.runs, smk.input.walls, smk.input.floorplans)
        ]
        table = metrics.score_dataset(
            runs, references, kind, cfg, smk.wildcards.dataset, log, recall_references=recall_refs,
            workers=smk.threads,
        )
        # the plans against the reference map (occupancy grid of all kept scans)
        against_map = score_plans(runs, read_grid(smk.input.reference_map), tuple(cfg["taus_m"]),
                                  metrics.floorplan_faces)
        table = table.merge(against_map, on=["ordering", "extractor", "k"], how="left", validate="one_to_one")
        # the time of each run to this log, not into the metrics (the same input gives the same file)
        seconds = table.pop(metrics.SCORE_TIME)
        if len(seconds):
            slowest = int(seconds.to_numpy().argmax())
            log.info("scored %d runs in %.2f s, the slowest %.2f s (%s)", len(table), seconds.sum(),
                     seconds.iloc[slowest], "/".join(str(table[c].iloc[slowest]) for c in ("ordering", "extractor", "k")))
        meta = {"dataset": smk.wildcards.dataset, "reference_kind": kind,
                "reference": smk.params.reference_label, "extractor": smk.wildcards.extractor}
        write_table(table, smk.output.metrics, metadata=meta)
