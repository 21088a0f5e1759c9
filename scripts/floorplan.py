"""Stage floorplan: merged walls of one (ordering, extractor), every k, as GeoJSON, SVG, DXF, IFC."""
from floorscan.floorplan import write_floorplan
from floorscan.io import read_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    wc = snakemake.wildcards
    for k, table in zip(snakemake.params.k, snakemake.input):
        assert table.endswith(f"/k{k}.parquet"), (k, table)
        stem = f"results/{wc.dataset}/floorplan/{wc.ordering}_{wc.extractor}_k{k}"
        outputs = {fmt: f"{stem}.{fmt}" for fmt in ("geojson", "svg", "dxf", "ifc")}
        plan = write_floorplan(read_table(table), snakemake.params.cfg, outputs, name=f"{wc.dataset} {wc.ordering} {wc.extractor} k{k}")
        log.info("k=%s: floor plan written (%s)", k, stem)
