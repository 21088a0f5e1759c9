"""The reduced recording of a PCD folder: a folder with the selected ``.pcd``
files copied and the locations CSV reduced to their rows (field text as it was). Scan
``i`` is the CSV's row ``source_ordinal[i]`` (0-based; a file ingest skipped has no scan).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd

from floorscan.core.io import InputError
from floorscan.core.files import staged_path
from floorscan.ingest.pcd import stamp_column
from floorscan.ingest.reduced_checks import check_count, check_stamps, scan_frames, size_of


def reduce_pcd(source: Path, ids, out_path: Path, detection, t_ns, window_s: float = 0.0) -> dict:
    """The reduced copy of a PCD folder (module docstring): the selected scans' files
    and their rows of the locations CSV.

    Parameters
    ----------
    source, ids, out_path, detection, t_ns
        As :func:`floorscan.ingest.reduced_bag.reduce_bag`.
    window_s : float
        Not used (a PCD folder has no pose messages).

    Returns
    -------
    dict
        As :func:`floorscan.ingest.reduced.write_reduced_recording`, ``format``
        ``pcd``.

    Raises
    ------
    InputError
        ``source`` is not a folder; the locations CSV is missing, unreadable or has no
        ``file`` column; it names a file outside ``source`` or missing; the row count or a
        stamp differs from ingest's.
    """
    if not source.is_dir():
        raise InputError(f"{source}: expected a folder of .pcd files")
    name = str(detection.get("locations") or "locations.csv")
    csv = source / name
    if not csv.is_file():
        raise InputError(f"{csv}: scan locations CSV not found (dataset option 'locations')")
    try:  # the same parser as ingest (floorscan.ingest.pcd.read_locations), the fields as text
        loc = pd.read_csv(csv, dtype=str, keep_default_na=False)
    except Exception as e:
        raise InputError(f"{csv}: cannot read the CSV ({e})") from None
    if "file" not in loc.columns:
        raise InputError(f"{csv}: no 'file' column; expected file,t_ns,x,y,z,yaw")
    frames = scan_frames(csv, ids, detection)  # rows of the CSV (ingest reads them in order)
    check_count(csv, len(loc), ids, t_ns, "scan locations", frames, detection)
    rows = loc.iloc[frames]
    if "t_ns" in loc.columns:
        got = stamp_column(csv, loc["t_ns"])[frames]  # int64: an epoch stamp has more digits than a float64
        check_stamps(csv, ids, got, t_ns)
    files = []
    for f in rows["file"]:
        rel = Path(str(f))
        if rel.is_absolute() or ".." in rel.parts:
            raise InputError(f"{csv}: names {f!r}; expected a path inside {source}")
        if not (source / rel).is_file():
            raise InputError(f"{csv}: names {f!r}, which is not in {source}")
        files.append(rel)
    with staged_path(out_path) as tmp:
        tmp.mkdir()
        for rel in files:
            (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source / rel, tmp / rel)
        (tmp / name).parent.mkdir(parents=True, exist_ok=True)
        rows.to_csv(tmp / name, index=False, lineterminator="\n")
    return {
        "format": "pcd",
        "path": str(out_path),
        "bytes_in": size_of(source),
        "bytes_out": size_of(out_path),
        "messages_in": len(loc),
        "messages_out": len(rows),
        "scan_messages_out": len(rows),
        "topics": {"pcd files": len(rows)},
    }
