"""Stage select, the recommended selection (floorscan.select.recommend): the first k
scans of the default ordering as a scan list, PLY and PCD points and a reduced copy
of the recording (the ingest stage's writer, floorscan.ingest.reduced), with
selection.json saying why k."""
from floorscan.core.stage import stage_log
from floorscan.ingest.reduced import write_selected_recording
from floorscan.select.recommend import write_selection

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821

    def reduced(scan_ids):
        """The recording cut to the selected scans, in its own format."""
        return write_selected_recording(smk.input.recording, smk.input.index, smk.params.dataset, scan_ids,
                                        smk.output.recording)

    write_selection(
        smk.input.ordering, smk.params.ordering, smk.input.index, smk.input.registration, smk.input.registered,
        smk.params.dataset, smk.params.cfg,
        {name: smk.output[name] for name in ("scans", "table", "ply", "pcd", "summary")}, reduced,
    )
