"""Stage register, its figure: the registered map by point density and the scan
locations (thesis Fig. 5.9), in its own job so the per-scan stages need not wait for it;
its title leads with the registration's verdict and what ingest detected."""
import json

from floorscan.figures.registration import density_of_file, plot_registered_map
from floorscan.core.io import describe_recording, read_metadata, read_table
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    density = density_of_file(snakemake.input.registered)  # streamed scan by scan
    meta = read_metadata(snakemake.input.registration)
    subtitle = [json.loads(meta["verdict"])["line"]] if "verdict" in meta else []
    subtitle.append(describe_recording(read_metadata(snakemake.input.index), meta.get("mode", "")))
    plot_registered_map(density, read_table(snakemake.input.registration), snakemake.output.figure,
                        title=snakemake.wildcards.dataset, subtitle=tuple(subtitle))
    log.info("registered map: %d x %d cells of %.2f m", density.nx, density.ny, density.cell_m)
