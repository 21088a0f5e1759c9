"""Stage register, its figure: the registered map by point density and the scan
locations (thesis Fig. 5.9), in its own job so the per-scan stages need not wait for it;
its title leads with the registration's verdict and what ingest detected."""
import json

import pyarrow.parquet as pq

from floorscan.figures_registration import density_of_file, plot_registered_map
from floorscan.io import read_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    density = density_of_file(snakemake.input.registered)  # streamed scan by scan
    meta = {k.decode(): v.decode() for k, v in (pq.read_schema(snakemake.input.registration).metadata or {}).items()}
    subtitle = []
    if "verdict" in meta:
        subtitle.append(json.loads(meta["verdict"])["line"])
    found = json.loads(meta.get("recording", "{}"))
    detected = ", ".join(f"{k} {found[k]}" for k in ("format", "scan_topic", "pose_source", "stamps") if k in found)
    if detected or "mode" in meta:
        subtitle.append(f"{detected or 'as configured'}; register mode {meta.get('mode', 'pose')}")
    plot_registered_map(density, read_table(snakemake.input.registration), snakemake.output.figure,
                        title=snakemake.wildcards.dataset, subtitle=tuple(subtitle))
    log.info("registered map: %d x %d cells of %.2f m", density.nx, density.ny, density.cell_m)
