"""The format of a recording, from its path (a user may give only ``path``).

A dataset without ``format`` is read as what its path is:

- ``rosbag``: a ROS1 ``.bag`` file (or any file starting with the ROS1 bag magic
  ``#ROSBAG V2.0``); a ROS2 bag folder (``metadata.yaml``, or ``.db3`` / ``.mcap``
  files in it); a ``.db3`` or ``.mcap`` file, whose folder is the bag;
- ``carmen``: a ``.log``, ``.log.gz``, ``.clf`` or ``.gz`` file (plain or gzip text)
  whose lines are CARMEN messages: a ``FLASER`` or ``ROBOTLASER1`` line among its first
  lines (the CARMEN logger's laser messages, which follow the log's ``PARAM`` lines and
  some ``ODOM`` ones), or else lines of which at least :data:`CARMEN_SHARE` start with
  a CARMEN message type (:data:`floorscan.ingest.carmen_lines.CARMEN_TYPES`: a log may
  hold many thousand ``ODOM`` lines before its first laser line, which its reader then
  finds), so an unrelated ``.log`` is not taken for one. The text is read as
  :func:`floorscan.ingest.text.open_text` reads it (a UTF-8 byte-order mark dropped,
  trailing garbage after gzip data ignored);
- ``pcd``: a folder holding ``.pcd`` files (with the locations CSV read by
  :mod:`floorscan.ingest.pcd`);
- ``map``: an occupancy map, not a recording of scans: a ROS map_server ``.yaml`` (with
  an ``image`` key) or a ``.pgm`` / ``.png`` image on its own
  (:mod:`floorscan.ingest.occupancy_map`).

Anything else is an :class:`~floorscan.core.io.InputError` naming the path and listing what
is expected. An explicit ``format`` in the dataset always wins over detection.
"""

from __future__ import annotations

import zlib
from pathlib import Path

from floorscan.core.datasets import brace_problem
from floorscan.core.io import InputError
from floorscan.core.messages import quoted, system_error
from floorscan.ingest.carmen_lines import CARMEN_TYPES
from floorscan.ingest.occupancy_map import MAP_IMAGE_SUFFIXES, MAP_YAML_SUFFIXES, is_map_path, map_images
from floorscan.ingest.text import open_text

#: File suffixes of a ROS2 bag's storage (sqlite3, MCAP).
ROS2_STORAGE_SUFFIXES = (".db3", ".mcap")
#: Suffixes of a CARMEN log (the last suffix; ``.log.gz`` ends in ``.gz``).
CARMEN_SUFFIXES = (".log", ".clf", ".gz")
#: CARMEN laser message types that make a file a recording floorscan reads.
CARMEN_LASER_TYPES = ("FLASER", "ROBOTLASER1")
#: Without a laser line among the first lines, the share of them that must start with
#: a CARMEN message type.
CARMEN_SHARE = 0.9
#: How far into a CARMEN candidate the laser line and the message types are looked for.
PEEK_LINES = 20_000
PEEK_BYTES = 8 << 20
ROS1_MAGIC = b"#ROSBAG V2.0"

EXPECTED = (
    "expected a ROS1 .bag file, a ROS2 bag folder (metadata.yaml, .db3 or .mcap files) or its "
    ".db3/.mcap file, a CARMEN log (.log, .log.gz, .clf or .gz text with FLASER or ROBOTLASER1 "
    "lines), a folder of .pcd files with their locations CSV, or an occupancy map (a ROS map_server "
    ".yaml, or a .pgm/.png image); or set the dataset's 'format'"
)


#: The locations CSV of a PCD folder, by default (dataset option ``locations``): a folder
#: holding one is a PCD recording, wherever the scans it names sit below it.
LOCATIONS_CSV = "locations.csv"


def detect_format(path: str | Path) -> str:
    """The format of the recording at ``path``: ``'rosbag'``, ``'carmen'``, ``'pcd'`` or
    ``'map'``.

    Parameters
    ----------
    path : str or Path
        A file or folder (see the module docstring for what each format looks like).

    Returns
    -------
    str
        ``'rosbag'``, ``'carmen'``, ``'pcd'`` or ``'map'``. For ``'rosbag'`` the bag to
        open is :func:`bag_path` of ``path``.

    Raises
    ------
    InputError
        ``path`` does not exist, or is none of the formats (the message names the
        path, what it holds and what is expected); a CARMEN candidate that cannot be
        read (truncated or corrupt gzip).
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: recording not found; {EXPECTED}")
    if path.is_dir():
        names = sorted(p.name for p in path.iterdir())
        if (path / "metadata.yaml").is_file() or any(n.endswith(ROS2_STORAGE_SUFFIXES) for n in names):
            return "rosbag"
        if any(n.lower().endswith(".pcd") for n in names) or (path / LOCATIONS_CSV).is_file():
            return "pcd"  # its scans may sit in a sub-folder its locations CSV names
        shown = ", ".join(n if len(n) <= 60 else quoted(n, 60) for n in names[:10])
        shown += f" ... ({len(names)} entries)" if len(names) > 10 else ""
        raise InputError(
            f"{path}: a folder with neither a ROS2 bag nor .pcd files (it holds: {shown or 'nothing'}); {EXPECTED}"
        )
    suffix = path.suffix.lower()
    if suffix == ".bag" or suffix in ROS2_STORAGE_SUFFIXES:
        return "rosbag"
    with open(path, "rb") as f:
        head = f.read(len(ROS1_MAGIC))
    if head == ROS1_MAGIC:
        return "rosbag"
    if suffix in CARMEN_SUFFIXES:
        why_not = _not_carmen(path)
        if why_not is None:
            return "carmen"
        raise InputError(f"{path}: {why_not}, so not a CARMEN log; {EXPECTED}")
    if suffix in MAP_IMAGE_SUFFIXES:
        return "map"
    if suffix in MAP_YAML_SUFFIXES:
        if is_map_path(path):
            return "map"
        raise InputError(f"{path}: a yaml without an 'image' key, so not a ROS map_server map; {EXPECTED}")
    if suffix == ".pcd":
        raise InputError(f"{path}: a single .pcd file; give the folder of .pcd scans (with locations.csv) instead")
    raise InputError(f"{path}: unknown recording format (suffix {quoted(suffix or 'none', 40)}); {EXPECTED}")


def bag_path(path: str | Path) -> Path:
    """The path rosbags opens for a bag.

    Parameters
    ----------
    path : path
        A ROS1 ``.bag``, a ROS2 bag folder or its ``.db3`` / ``.mcap`` file.

    Returns
    -------
    Path
        A ``.db3`` / ``.mcap`` file's folder, else ``path``.
    """
    path = Path(path)
    if path.is_file() and path.suffix.lower() in ROS2_STORAGE_SUFFIXES:
        return path.parent
    return path


def _not_carmen(path: Path) -> str | None:
    """None when ``path`` (plain or gzip text) reads as a CARMEN log: a laser line among
    its first :data:`PEEK_LINES` lines (at most :data:`PEEK_BYTES`), or else at least
    :data:`CARMEN_SHARE` of those lines (comments and blank ones aside) start with a
    message type of :data:`~floorscan.ingest.carmen_lines.CARMEN_TYPES`. Otherwise why
    not, quoting at most three of the first words of its lines, each cut to 40
    characters."""
    typed = known = 0
    others: list[str] = []
    try:
        with open_text(path, warn=False) as f:
            n_chars = 0
            for _ in range(PEEK_LINES):
                line = f.readline(1 << 16)  # bounded: a binary file may have no newline
                if not line:
                    break
                n_chars += len(line)
                tok = line.split(maxsplit=1)
                if tok and not tok[0].startswith("#"):
                    if tok[0] in CARMEN_LASER_TYPES:
                        return None
                    typed += 1
                    if tok[0] in CARMEN_TYPES:
                        known += 1
                    elif len(others) < 3 and tok[0] not in others:
                        others.append(tok[0])
                if n_chars >= PEEK_BYTES:
                    break
    except (EOFError, OSError, zlib.error) as e:
        if isinstance(e, OSError) and system_error(e) is not None:
            raise  # the machine's (permission denied): named as such by the stage
        raise InputError(f"{path}: cannot read it to detect its format, truncated or corrupt ({e})") from None
    if typed == 0:
        return "no lines (it is empty, or holds comments alone)"
    if known >= CARMEN_SHARE * typed:
        return None
    words = ", ".join(quoted(w, 40) for w in others)
    return (
        f"no {' or '.join(CARMEN_LASER_TYPES)} line in its first {typed} lines, and {typed - known} of them "
        f"start with other words than CARMEN message types (such as {words})"
    )


#: File suffixes that make a file in a folder of recordings a candidate recording
#: (:func:`recordings_in`): ROS1 bags, ROS2 storage files, CARMEN logs, map images (a
#: map_server yaml is one when it has an ``image`` key; the image it names is not one
#: of its own).
RECORDING_SUFFIXES = (".bag", *ROS2_STORAGE_SUFFIXES, *CARMEN_SUFFIXES, *MAP_IMAGE_SUFFIXES)


def is_one_recording(folder: Path) -> bool:
    """Whether a folder is itself one recording: a ROS2 bag (``metadata.yaml``, or
    ``.db3`` / ``.mcap`` files) or a PCD folder (``.pcd`` files, or a
    :data:`LOCATIONS_CSV` whose scans sit in a sub-folder).

    Parameters
    ----------
    folder : Path
        An existing folder; only its own entries are looked at.

    Returns
    -------
    bool
    """
    names = [p.name.lower() for p in folder.iterdir()]
    return ("metadata.yaml" in names or LOCATIONS_CSV in names
            or any(n.endswith((*ROS2_STORAGE_SUFFIXES, ".pcd")) for n in names))


def recordings_in(path: str | Path) -> tuple[list[Path], list[str]]:
    """The recordings a path names: the path itself, or each recording in a folder of
    recordings.

    A file, a ROS2 bag folder and a PCD folder are one recording. Any other folder is a
    folder of recordings: each file with a suffix of :data:`RECORDING_SUFFIXES`, each
    map_server yaml (a ``.yaml`` with an ``image`` key) and each sub-folder that
    :func:`is_one_recording` is one (by name only: ingest reads and detects each, so a
    file that is not what its suffix says fails on its own, naming itself, without
    stopping the others); an image that a map yaml of the folder names is that map's,
    not a recording of its own. Hidden entries are left out.

    Parameters
    ----------
    path : str or Path
        ``--config path=...``.

    Returns
    -------
    recordings : list of Path
        Sorted by name.
    skipped : list of str
        Names of the folder's entries that are not recordings (empty for one recording).

    Raises
    ------
    InputError
        ``path`` does not exist, or is a folder holding no recording (naming what it
        holds and what is expected).
    """
    path = Path(path)
    if not path.exists():
        where = "" if path.is_absolute() else f" in {Path.cwd()} (a relative path is read from the working directory)"
        raise InputError(f"{path}: no such file or folder{where}; {EXPECTED}")
    if (problem := brace_problem(path)) is not None:
        raise InputError(problem)
    if not path.is_dir() or is_one_recording(path):
        return [path], []
    recordings, skipped = [], []
    entries = [e for e in sorted(path.iterdir(), key=lambda p: p.name) if not e.name.startswith(".")]
    map_yamls = [e for e in entries if e.suffix.lower() in MAP_YAML_SUFFIXES and is_map_path(e)]
    images_of_maps = {img.resolve() for y in map_yamls for img in map_images(y)}
    for entry in entries:
        if entry.resolve() in images_of_maps:
            continue
        if (
            entry.is_dir() and is_one_recording(entry)
            or entry.is_file() and entry.suffix.lower() in RECORDING_SUFFIXES
            or entry in map_yamls
        ):
            if brace_problem(entry.name) is not None:
                skipped.append(f"{entry.name} (holds {{ or }}, which Snakemake reads as a wildcard: rename or link it)")
            else:
                recordings.append(entry)
        else:
            skipped.append(entry.name)
    if not recordings:
        shown = ", ".join(quoted(n, 60) for n in skipped[:10]) + (f" ... ({len(skipped)} entries)" if len(skipped) > 10 else "")
        raise InputError(f"{path}: a folder with no recording in it (it holds: {shown or 'nothing'}); {EXPECTED}")
    return recordings, skipped
