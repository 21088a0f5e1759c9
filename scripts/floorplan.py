"""Stage floorplan, the evaluation grid: merged walls of one extractor for every ordering
and k, in the formats of floorplan.evaluation_formats, in the map frame."""
from floorscan.floorplan import floorplan_outputs
from floorscan.floorplan.metadata import recording_timestamp
from floorscan.floorplan.writer import FloorplanWriter
from floorscan.core.io import read_table
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    wc = smk.wildcards
    writer = FloorplanWriter(smk.params.cfg)  # a plan of the same scans as an earlier one is reused
    timestamp = recording_timestamp(smk.input.index)
    for (ordering, k), table in zip(smk.params.runs, smk.input.tables, strict=True):
        assert table.endswith(f"/{ordering}/{wc.extractor}/k{k}.parquet"), (ordering, k, table)
        stem = f"results/{wc.dataset}/evaluation/floorplan/{ordering}_{wc.extractor}_k{k}"
        outputs = floorplan_outputs(stem, smk.params.formats)
        _, reused = writer.write(read_table(table), outputs, dataset=wc.dataset, ordering=ordering,
                                 extractor=wc.extractor, k=k, timestamp=timestamp)
        log.info("%s k=%s: floor plan %s (%s)", ordering, k, stem, "reused: same scans as an earlier plan" if reused else "built")
