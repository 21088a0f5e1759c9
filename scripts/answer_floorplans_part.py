"""Stage floorplan, the answer's plans of the first k scans, one job's share of the k grid:
the plan the answer is made with of the first k scans of the default ordering, for k on
a geometric grid, as Parquet tables for the score stage's answer curve
(floorscan.floorplan.answer_plans; rule answer_floorplans merges the shares). The walls
of a set of scans are the walls stage's map extractor (floorscan.walls.map_lines). The
last k, all kept scans, is the plan of rule all_scans_floorplan, not built here."""
from floorscan.core.config import stage_params
from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.core.wall_points import ScanParams
from floorscan.floorplan.answer_plans import first_k_scans_points, write_answer_plans
from floorscan.floorplan.params import FloorplanParams
from floorscan.walls.map_lines import MapParams, map_segments
from floorscan.walls.map_stage import map_grid_params

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    walls = smk.params.walls or {}
    map_params = stage_params(MapParams, walls.get("map"))
    seed = int(walls.get("seed", 0))

    def segments_of(points, grid):
        """The map extractor's segments of these wall points on their grid."""
        return map_segments(points, grid, map_params, seed=seed)

    scans = first_k_scans_points(smk.input.registered, read_table(smk.input.registration),
                                 read_table(smk.input.ordering), stage_params(ScanParams, walls))
    done = write_answer_plans(
        scans, segments_of, map_grid_params(walls),
        stage_params(FloorplanParams, smk.params.floorplan), smk.output.plans,
        {"dataset": smk.wildcards.dataset, "ordering": smk.params.ordering},
        part=int(smk.wildcards.part), parts=int(smk.params.parts), all_scans=False,
    )
    log.info("the answer's plans of the first k scans of %s, part %s of %d: k %s; walls %s", smk.params.ordering,
             smk.wildcards.part, smk.params.parts,
             " ".join(str(d["k"]) for d in done), " ".join(str(d["n_walls"]) for d in done))
