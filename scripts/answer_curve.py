"""Stage score, the answer's quality curve: the map extractor's plan of the first k scans
of the default ordering against the reference map (floorscan.score.answer_curve). The
plan of a set of scans is made as the answer's is: the walls stage's map extractor
(floorscan.walls.map_lines) and the floorplan stage's builder (floorscan.floorplan.plan)."""
from dataclasses import replace

from floorscan.core.config import stage_params
from floorscan.core.files import atomic_path
from floorscan.core.io import read_table
from floorscan.core.occupancy import OccupancyParams, read_grid
from floorscan.core.score_tables import k_reaching
from floorscan.core.stage import stage_log
from floorscan.core.wall_points import ScanParams
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import build_floorplan
from floorscan.score.answer_curve import answer_curve
from floorscan.walls.map_lines import MapParams, map_segments

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    walls = smk.params.walls or {}
    map_params = stage_params(MapParams, walls.get("map"))
    plan_params = stage_params(FloorplanParams, smk.params.floorplan)
    seed = int(walls.get("seed", 0))

    def answer_plan(points, grid):
        """The answer's plan of these wall points: the map extractor's segments on their grid, made a plan."""
        return build_floorplan(map_segments(points, grid, map_params, seed=seed), plan_params, grid)

    curve = answer_curve(
        smk.input.registered, read_table(smk.input.registration), read_table(smk.input.ordering),
        read_grid(smk.input.reference), answer_plan, stage_params(ScanParams, walls),
        replace(OccupancyParams(), resolution_m=map_params.support_cell_m),
    )
    with atomic_path(smk.output.curve) as tmp:
        curve.to_csv(tmp, index=False, float_format="%.4f")
    log.info("the answer's plan against the reference map: F1 at 5 cm %s; k95 %s, k99 %s of %d kept scans",
             " ".join(f"{k}:{f:.3f}" for k, f in zip(curve["k"], curve["f1_5cm"])),
             k_reaching(curve, 0.95), k_reaching(curve, 0.99), int(curve["k"].iloc[-1]) if len(curve) else 0)
