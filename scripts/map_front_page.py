"""The front page and summary.md of an occupancy map's plan (floorscan.figures.map_page):
the plan, its rooms, what was read of the map, and what a map gives and does not."""
from floorscan.core.stage import stage_log
from floorscan.figures.map_page import write_map_front_page, write_map_summary

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    # summary.md first: the page links it when it exists
    write_map_summary(smk.output.summary_md, smk.wildcards.dataset, smk.input.info, smk.input.floorplan_geojson)
    write_map_front_page(smk.output.front, smk.wildcards.dataset, floorplan_svg=smk.input.floorplan_svg,
                         plan=smk.input.plan, info=smk.input.info, description=smk.params.description)
    log.info("front page %s, %s", smk.output.front, smk.output.summary_md)
