"""The tables of the walls stage: their Parquet schemas and the reasons a scan has no walls.

* :data:`WALLS`: wall segments, ``walls/{extractor}/per_scan.parquet`` and
  ``walls/{ordering}/{extractor}/k{k}.parquet``;
* :data:`SCAN_STATUS`: one row per scan, ``walls/{extractor}/scan_status.parquet``;
* :data:`SCAN_TIMES`: the seconds of each scan's extraction (benchmarks folder);
* :data:`REASONS`: why a scan gave no walls.

An extractor returns its segments as tuples ``(x0, y0, x1, y1, n_inliers, rmse_m)``;
:func:`segments_frame` makes the frame of them (the columns of :data:`WALLS` without
``scan_id``).
"""

from __future__ import annotations

import pandas as pd
import pyarrow as pa

#: Wall segments of scans (``walls/{extractor}/per_scan.parquet`` and
#: ``walls/{ordering}/{extractor}/k{k}.parquet``).
WALLS = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("x0", pa.float64()),
        ("y0", pa.float64()),
        ("x1", pa.float64()),
        ("y1", pa.float64()),
        ("n_inliers", pa.int32()),
        ("rmse_m", pa.float64()),
    ]
)
#: One row per scan of ``registered.parquet`` (``walls/{extractor}/scan_status.parquet``).
#: No timing: the same input gives the same file (the times: :data:`SCAN_TIMES`).
SCAN_STATUS = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("n_points", pa.int32()),
        ("n_walls", pa.int32()),
        ("reason", pa.string()),
    ]
)
#: The wall-clock seconds of each scan's extraction
#: (``benchmarks/scan_walls_{extractor}_times.parquet``, thesis Fig. 5.10): beside the
#: benchmark files, since they change from run to run.
SCAN_TIMES = pa.schema([("scan_id", pa.int32()), ("time_s", pa.float64())])
#: Reasons a scan gives no walls ("" when it gave walls).
REASONS = (
    "non_finite_coordinates",  # a NaN/inf coordinate: the scan is corrupt, not used
    "no_points_in_height_band",  # 3D scan with no point between the band's heights
    "too_few_points",  # fewer than min_points wall points
    "no_wall_found",  # no line with min_inliers inliers and min_length_m
)

_SEGMENT_COLUMNS = ["x0", "y0", "x1", "y1", "n_inliers", "rmse_m"]


def segments_frame(rows: list[tuple]) -> pd.DataFrame:
    """Wall segments as a frame.

    Parameters
    ----------
    rows : list of tuple
        ``(x0, y0, x1, y1, n_inliers, rmse_m)`` per segment, metres.

    Returns
    -------
    pandas.DataFrame
        Those columns: ``n_inliers`` int32, the others float64 (metres).
    """
    df = pd.DataFrame(rows, columns=_SEGMENT_COLUMNS)
    return df.astype({c: "float64" for c in _SEGMENT_COLUMNS if c != "n_inliers"} | {"n_inliers": "int32"})
