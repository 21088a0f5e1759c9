"""Open the recording a dataset names, in its format (given, or detected from its path).

The readers are :func:`floorscan.ingest.rosbag.open_bag`,
:func:`floorscan.ingest.carmen.open_carmen` and
:func:`floorscan.ingest.pcd.open_pcd_folder`, each imported when its format is read;
the format is detected by :func:`floorscan.ingest.detect.detect_format`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from floorscan.core.io import InputError
from floorscan.ingest.recording import Recording


def open_recording(dataset: Mapping[str, Any], cfg: Mapping[str, Any], max_gap_s: float) -> Recording:
    """Open the recording a dataset entry names.

    The format is the dataset's ``format`` when given, else detected from ``path``
    (:func:`floorscan.ingest.detect.detect_format`); ``Recording.detected["format"]``
    holds it either way. What the reader skipped (scans without a valid return, broken
    frames, unlisted files, unknown lines) is in ``Recording.detected`` and the notes
    once ``Recording.scans`` is exhausted (:data:`floorscan.ingest.recording.LOSS_KEYS`).

    Parameters
    ----------
    dataset : mapping
        The dataset's config entry: ``path``, optional ``format`` (rosbag, carmen, pcd)
        and the format's options (see ``workflow/schemas/config.schema.yaml``).
    cfg : mapping
        The ``ingest`` config section.
    max_gap_s : float
        The pose stage's gap limit; a TF chain leaves out samples inside a longer gap
        of any of its links, so the gap stays visible in the pose stream.

    Returns
    -------
    Recording
        Its scans are read lazily, as ``Recording.scans`` is iterated.

    Raises
    ------
    InputError
        The path is missing, its format cannot be detected (without ``format``), or the
        recording cannot be read (message names the file).
    """
    fmt = dataset.get("format")
    path = Path(dataset["path"])
    if not path.exists():
        raise InputError(f"{path}: recording not found (dataset format {fmt or 'to be detected'!r})")
    how = "set in the dataset"
    if fmt is None:
        from floorscan.ingest.detect import detect_format

        fmt, how = detect_format(path), "detected from the path"
    if fmt == "rosbag":
        from floorscan.ingest.rosbag import open_bag

        rec = open_bag(path, dataset, max_gap_s=max_gap_s)
    elif fmt == "carmen":
        from floorscan.ingest.carmen import open_carmen

        rec = open_carmen(path, dataset, cfg)
    elif fmt == "pcd":
        from floorscan.ingest.pcd import open_pcd_folder

        rec = open_pcd_folder(path, dataset, cfg)
    else:
        raise InputError(f"{path}: unsupported dataset format {fmt!r}; expected rosbag, carmen or pcd")
    # in place: a lazy reader adds its loss counts to this dict as the scans are read
    others = {k: v for k, v in rec.detected.items() if k != "format"}
    rec.detected.clear()
    rec.detected.update({"format": fmt, **others})
    rec.notes.insert(0, f"format {fmt} ({how})")
    return rec
