"""Stage ingest: read a recording into scans.parquet, scan_index.parquet, pose_stream.parquet.

What ingest detected (format, scan topic, pose source and kind, stamps, a CARMEN log's
max range) is logged and stored in the schema metadata of the index and pose stream."""
from floorscan.ingest.readers import open_recording
from floorscan.ingest.recording import detected_line
from floorscan.ingest.writer import write_recording
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    ds = snakemake.params.dataset
    rec = open_recording(ds, snakemake.params.cfg, max_gap_s=snakemake.params.max_gap_s)
    log.info("detected: %s", detected_line(rec.detected))
    for note in rec.notes:
        log.info("%s", note)
    index = write_recording(
        rec,
        snakemake.output.scans,
        snakemake.output.index,
        snakemake.output.pose_stream,
        sensor_height_m=ds.get("sensor_height_m", 0.0),
        metadata={"dataset": ds["name"], "source": rec.source},
    )
    log.info(
        "%d scans, %d points, %d returns dropped as invalid (NaN, inf, below the minimum range, "
        "at or beyond the maximum range)",
        len(index), index["n_points"].sum(), index["n_dropped"].sum(),
    )
