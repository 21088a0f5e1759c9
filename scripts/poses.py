"""Stage poses: the pose of each scan at its timestamp (thesis Algorithm 3 step 1)."""
from floorscan.core.io import POSES, read_metadata, read_table, write_table
from floorscan.core.config import stage_params
from floorscan.ingest.params import PosesParams
from floorscan.ingest.poses import missing_poses_line, scan_poses
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    index = read_table(snakemake.input.index)
    stream = read_table(snakemake.input.pose_stream)
    # messages name the recording and its pose source, not the intermediate table
    detected = read_metadata(snakemake.input.pose_stream)
    source = f"{detected.get('source', snakemake.input.pose_stream)} (poses: {detected.get('pose_source', 'none')})"
    params = stage_params(PosesParams, snakemake.params.cfg)
    poses = scan_poses(index, stream, params.max_gap_s, source)
    write_table(poses, snakemake.output.poses, schema=POSES)
    if stream.empty:
        found = detected.get("pose_source", "none")
        log.info(
            "no map pose source in the recording (%s): none of the %d scans has a pose (no_pose_source); "
            "the register stage places them by LIDAR odometry", found, len(poses),
        )
    elif missing := missing_poses_line(poses):  # a localizer that starts late or stops part-way
        log.warning("%s", missing)
    else:
        log.info("all %d scans have a pose", len(poses))
