"""Stage register: scans in the map frame, refined by ICP (thesis Algorithm 3 steps 2-6)."""
import json

from floorscan.core.io import read_metadata, read_table, write_table
from floorscan.register.registration import REGISTRATION, register_recording
from floorscan.core.stage import stage_log

# an error names the recording (ingest's metadata of the scan index)
with stage_log(snakemake, source=snakemake.input.index) as log:
    # the edge ICP runs in the rule's threads (processes); the edges do not depend on it
    cfg = dict(snakemake.params.cfg)
    cfg["graph"] = {**(cfg.get("graph") or {}), "workers": snakemake.threads}
    # what ingest found in the recording: pose kind (map poses or none), stamps
    recording = read_metadata(snakemake.input.index)
    poses = read_table(snakemake.input.poses)
    out_meta = {"dataset": snakemake.wildcards.dataset, "units": "metres, radians"}
    # streamed: the points are read scan by scan and written as they are registered
    result = register_recording(
        snakemake.input.scans, read_table(snakemake.input.index), poses, cfg,
        snakemake.output.registered, metadata=out_meta, recording=recording,  # figure: rule register_figure
    )
    s = result.summary
    out_meta.update(verdict=json.dumps(s["verdict"]), mode=s["config"]["mode"])
    write_table(result.table, snakemake.output.registration, schema=REGISTRATION, metadata=out_meta)
    log.info(
        "kept %d of %d scans (%d sampled); dropped by reason %s; fraction of the checked scans each "
        "fitness threshold drops %s; median correction %.3f m, %.3f rad",
        s["n_kept"], s["n_scans"], s["n_sampled"], s["drops"], s["fraction_of_checked"],
        s["median_correction_m"], s["median_correction_rad"],
    )
