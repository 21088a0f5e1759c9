"""Stage select, the recommended selection (floorscan.select.recommend): the first k
scans of the default ordering as a scan list, PLY and PCD points and a reduced copy
of the recording, with selection.json saying why k."""
from floorscan.select.recommend import write_selection
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    write_selection(
        smk.input.ordering, smk.params.ordering, smk.input.index, smk.input.registration, smk.input.registered,
        smk.input.recording, smk.params.dataset, smk.params.cfg,
        {name: smk.output[name] for name in ("scans", "table", "ply", "pcd", "recording", "summary")},
    )
