"""Stage ingest: read a recording into scans.parquet, scan_index.parquet, pose_stream.parquet."""
from floorscan.ingest import open_recording, write_recording
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    ds = snakemake.params.dataset
    rec = open_recording(ds, snakemake.params.cfg, max_gap_s=snakemake.params.max_gap_s)
    index = write_recording(
        rec,
        snakemake.output.scans,
        snakemake.output.index,
        snakemake.output.pose_stream,
        sensor_height_m=ds.get("sensor_height_m", 0.0),
        metadata={"dataset": ds["name"], "source": rec.source},
    )
    for note in rec.notes:
        log.info("%s", note)
    log.info(
        "%d scans, %d points, %d returns dropped as invalid (NaN, inf or out of range)",
        len(index), index["n_points"].sum(), index["n_dropped"].sum(),
    )
