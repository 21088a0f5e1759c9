"""Stage register: scans in the map frame, refined by ICP (thesis Algorithm 3 steps 2-6)."""

# The edge ICP's worker processes are spawned: each imports this script again (as
# __mp_main__) and must not run the stage, nor import what only the stage needs.
if __name__ == "__main__":
    import json

    from floorscan.core.io import read_metadata, read_table, write_table
    from floorscan.core.stage import stage_log
    from floorscan.register.result import REGISTRATION
    from floorscan.register.stream import register_recording

    # an error names the recording (ingest's metadata of the scan index)
    with stage_log(snakemake, source=snakemake.input.index) as log:  # noqa: F821
        smk = snakemake  # noqa: F821
        # the edge ICP runs in the rule's threads (processes); the edges do not depend on it
        cfg = dict(smk.params.cfg)
        cfg["graph"] = {**(cfg.get("graph") or {}), "workers": smk.threads}
        # what ingest found in the recording: pose kind (map poses or none), stamps
        recording = read_metadata(smk.input.index)
        poses = read_table(smk.input.poses)
        out_meta = {"dataset": smk.wildcards.dataset, "units": "metres, radians"}
        # streamed: the points are read scan by scan and written as they are registered
        result = register_recording(
            smk.input.scans, read_table(smk.input.index), poses, cfg,
            smk.output.registered, metadata=out_meta, recording=recording,  # figure: rule register_figure
        )
        s = result.summary
        out_meta.update(verdict=json.dumps(s["verdict"]), mode=s["config"]["mode"])
        write_table(result.table, smk.output.registration, schema=REGISTRATION, metadata=out_meta)
        log.info(
            "kept %d of %d scans (%d sampled); dropped by reason %s; fraction of the checked scans each "
            "keep test drops %s; median correction %.3f m, %.3f rad",
            s["n_kept"], s["n_scans"], s["n_sampled"], s["drops"], s["fraction_of_checked"],
            s["median_correction_m"], s["median_correction_rad"],
        )
