"""Stage floorplan: merged walls of one extractor, every ordering and k, as GeoJSON, SVG, DXF, IFC."""
from floorscan.floorplan import FLOORPLAN_FORMATS, FloorplanWriter
from floorscan.io import read_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    wc = snakemake.wildcards
    writer = FloorplanWriter(snakemake.params.cfg)  # a plan of the same scans as an earlier one is copied
    for (ordering, k), table in zip(snakemake.params.runs, snakemake.input):
        assert table.endswith(f"/{ordering}/{wc.extractor}/k{k}.parquet"), (ordering, k, table)
        stem = f"results/{wc.dataset}/floorplan/{ordering}_{wc.extractor}_k{k}"
        outputs = {fmt: f"{stem}.{fmt}" for fmt in FLOORPLAN_FORMATS}
        _, copied = writer.write(read_table(table), outputs, name=f"{wc.dataset} {ordering} {wc.extractor} k{k}")
        log.info("%s k=%s: floor plan %s (%s)", ordering, k, "copied: same scans as an earlier plan" if copied else "written", stem)
