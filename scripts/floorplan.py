"""Stage floorplan: merged walls of one extractor, every ordering and k, as GeoJSON, SVG, DXF, IFC."""
from floorscan.floorplan import write_floorplan
from floorscan.io import read_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    wc = snakemake.wildcards
    for (ordering, k), table in zip(snakemake.params.runs, snakemake.input):
        assert table.endswith(f"/{ordering}/{wc.extractor}/k{k}.parquet"), (ordering, k, table)
        stem = f"results/{wc.dataset}/floorplan/{ordering}_{wc.extractor}_k{k}"
        outputs = {fmt: f"{stem}.{fmt}" for fmt in ("geojson", "svg", "dxf", "ifc")}
        write_floorplan(read_table(table), snakemake.params.cfg, outputs, name=f"{wc.dataset} {ordering} {wc.extractor} k{k}")
        log.info("%s k=%s: floor plan written (%s)", ordering, k, stem)
