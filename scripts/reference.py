"""Stage reference: the occupancy grid of all kept scans (the reference map), written
as a ROS map_server map, a cell table and a figure."""
from floorscan.core.config import stage_params
from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.figures.maps import plot_reference_map
from floorscan.core.occupancy import OccupancyParams, write_grid, write_map_server
from floorscan.score.reference import reference_of_recording

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    params = stage_params(OccupancyParams, smk.params.cfg)
    grid = reference_of_recording(smk.input.registered, read_table(smk.input.registration),
                                  smk.params.walls, params)
    counts = grid.counts()
    log.info("reference map: %d x %d cells of %.2f m; %s", grid.shape[1], grid.shape[0], grid.resolution_m, counts)
    log.info("structure: %d occupied cells hit by >= %d scans; %d occupied cells hit by fewer (not structure)",
             counts["structure"], params.min_scans, counts["single_scan"])
    quality = {}
    if smk.input.get("ground_truth"):  # synthetic: how good the reference is
        from floorscan.score.against_reference import reference_against_ground_truth
        from floorscan.score.geojson import read_wall_faces
        from floorscan.score.ground_truth import OBSERVED_FACE

        quality = reference_against_ground_truth(grid, read_wall_faces(smk.input.ground_truth, "face"),
                                                 read_wall_faces(smk.input.ground_truth, OBSERVED_FACE))
        log.info("reference map against the simulator's true walls: %s",
                 ", ".join(f"{k} {v:.3f}" for k, v in quality.items()))
    write_map_server(grid, smk.output.pgm, smk.output.yaml)
    write_grid(grid, smk.output.cells, {f"against_ground_truth_{k}": repr(v) for k, v in quality.items()})
    plot_reference_map(grid, smk.output.figure, title=f"{smk.wildcards.dataset} reference map")
