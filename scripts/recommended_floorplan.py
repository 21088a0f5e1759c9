"""Stage floorplan, the recommended plan: the merged walls of the selected scans
(selection/scans.parquet) as results/<dataset>/floorplan.* in every export format
(floorscan.floorplan.EXPORT_FORMATS: GeoJSON, SVG, DXF, IFC), and their occupancy grid as
a ROS map_server / Nav2 map (map.pgm, map.yaml)."""
from floorscan.floorplan.writer import write_recommended_floorplan
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    outputs = {k: v for k, v in smk.output.items() if k not in ("plan", "map_pgm", "map_yaml")}  # by format
    plan = write_recommended_floorplan(
        smk.input.scans, smk.input.walls, smk.input.index, outputs, smk.params.cfg, grid_path=smk.input.grid,
        dataset=smk.wildcards.dataset, ordering=smk.params.ordering, extractor=smk.params.extractor,
        map_paths=(smk.output.map_pgm, smk.output.map_yaml), plan_folder=smk.output.plan,
    )
    log.info("floor plan of %d selected scans (%s, %s walls): %d walls, %d faces, %d clutter, %d junctions -> %s",
             plan["n_scans"], smk.params.ordering, smk.params.extractor, plan["n_walls"], plan["n_faces"],
             plan["n_clutter"], plan["n_junctions"], ", ".join(outputs.values()))
