"""Simulate stage: a rover records a synthetic building (floorscan.sim.simulate.run_simulation)."""

from floorscan.sim.simulate import run_simulation
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821 (injected by Snakemake)
    out = snakemake.output  # noqa: F821
    counts = run_simulation(
        snakemake.input.building,  # noqa: F821
        snakemake.params.dataset,  # noqa: F821
        snakemake.params.cfg,  # noqa: F821
        {"bag": out.bag, "pcd": out.pcd, "true_poses": out.true_poses, "stl": out.stl,
         "walls": out.walls},
    )
    log.info("simulated %s", counts)
