"""The recordings of a run: the checks of the ``datasets`` a schema cannot make, a
recording given by ``--config path=...`` (a file or a folder of them) made datasets, and
the ``building`` section's floors resolved to datasets. The Snakefile calls them once,
after :func:`floorscan.core.config.validate_config`.
"""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import Mapping

from floorscan.core.config import BUILDINGS_DIR, ConfigError

#: What a dataset's ``path`` names, for messages.
RECORDING_PATH = (
    "the path of a recording: a ROS1 .bag file, a ROS2 bag folder (or its .db3 / .mcap), "
    "a CARMEN .log or .log.gz, or a folder of .pcd scans with locations.csv"
)


def known_buildings(buildings_dir: str | os.PathLike = BUILDINGS_DIR) -> list[str]:
    """Names of the synthetic buildings: the ``<name>.yaml`` files of ``buildings_dir``
    (:func:`floorscan.sim.building_file.load_building` reads one), sorted."""
    folder = Path(buildings_dir)
    return sorted(p.stem for p in folder.glob("*.yaml")) if folder.is_dir() else []


def check_datasets(config: Mapping, buildings_dir: str | os.PathLike = BUILDINGS_DIR) -> None:
    """What the schema cannot check of a validated config's recordings.

    Parameters
    ----------
    config : mapping
        The workflow config after :func:`validate_config`.
    buildings_dir : path
        The folder of the synthetic buildings (``<name>.yaml``).

    Raises
    ------
    ConfigError
        A ``path`` (top-level or of a dataset) that is empty, saying what a path names;
        a synthetic dataset's ``building`` without a file in ``buildings_dir``, listing
        the known buildings; a dataset's ``path`` with a brace (:func:`brace_problem`).
    """
    if "path" in config:
        paths = config_paths(config)
        if not paths or not all(str(p or "").strip() for p in paths):
            raise ConfigError(f"path (--config path=...) is empty; expected {RECORDING_PATH}")
    for name, ds in (config.get("datasets") or {}).items():
        if ds.get("format") == "synthetic":
            building = str(ds.get("building"))
            if not (Path(buildings_dir) / f"{building}.yaml").is_file():
                raise ConfigError(
                    f"datasets.{name}.building: no building {building!r}; expected one of "
                    f"{known_buildings(buildings_dir)} (the files {os.fspath(buildings_dir)}/<name>.yaml)"
                )
        elif "path" in ds and not str(ds["path"] or "").strip():
            raise ConfigError(f"datasets.{name}.path is empty; expected {RECORDING_PATH}")
        elif "path" in ds and (problem := brace_problem(ds["path"])) is not None:
            raise ConfigError(f"datasets.{name}.path: {problem}")


def brace_problem(path: str | os.PathLike) -> str | None:
    """Why a recording's path cannot be a workflow input, or None: a ``{`` or ``}`` in
    it, which Snakemake reads as a wildcard even escaped (it formats the paths an input
    function returns).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    str or None
        The message: the path, the cause, and the renaming or the link that works.
    """
    import shlex

    text = os.fspath(path)
    if "{" not in text and "}" not in text:
        return None
    name = Path(text).name.replace("{", "").replace("}", "") or "recording"
    return (f"{text}: the path holds {{ or }}, which Snakemake reads as a wildcard: rename the file or folder, or "
            f"link it under a name without them (ln -s {shlex.quote(str(Path(text).resolve()))} {shlex.quote(name)}) "
            "and give the link")


def config_paths(config: Mapping) -> list[str]:
    """The top-level ``path`` of a config as a list: one path (``--config path=...``),
    several (``floorscan run A B``: a list), or none."""
    path = config.get("path")
    if path is None:
        return []
    return [os.fspath(p) for p in path] if isinstance(path, (list, tuple)) else [os.fspath(path)]


def _same_file(a: str | None, b: str) -> bool:
    """Whether two paths name the same file or folder (resolved against the working
    directory, symbolic links followed)."""
    return a is not None and os.path.realpath(a) == os.path.realpath(b)


def dataset_name(path: str | os.PathLike) -> str:
    """The dataset name of a recording: its file or folder name without the recording
    suffixes (``.gz``, ``.log``, ``.clf``, ``.bag``, ``.db3``, ``.mcap``; a map's ``.yaml``,
    ``.yml``, ``.pgm``, ``.png``), other
    characters than letters, digits and ``_`` replaced by ``_``, ``r_`` before a
    leading digit."""
    import re
    from pathlib import PurePath

    name = PurePath(os.fspath(path).rstrip("/")).name
    for suffix in (".gz", ".log", ".clf", ".bag", ".db3", ".mcap", ".yaml", ".yml", ".pgm", ".png"):
        if name.lower().endswith(suffix) and len(name) > len(suffix):
            name = name[: -len(suffix)]
    name = re.sub(r"[^A-Za-z0-9_]", "_", name) or "recording"
    return f"r_{name}" if name[0].isdigit() else name


def add_path_datasets(config: dict, recordings: list) -> list[str]:
    """Make the recordings of the top-level ``path`` (``--config path=/data/run.bag``, or
    a folder of recordings) datasets, the run's targets.

    Each dataset is named by :func:`dataset_name`, holds ``path`` (ingest detects
    the rest), the keys of the top-level ``path_options`` (``scan_topic``, ``pose``, ...:
    what the user sets of every recording of ``path``) and, for a map image, the
    top-level ``resolution_m``. A dataset of that name with the same recording (the same path, relative
    to the working directory or absolute) is reused; with another recording the name
    gets a numeric suffix. The ``building`` section's floors name their recording by
    dataset name or file name; they are resolved to dataset names
    (``building.floors[i].dataset``).

    Parameters
    ----------
    config : dict
        The validated workflow config; changed in place (``datasets``, ``target``,
        ``building``).
    recordings : list of path
        The recordings ``path`` names (:func:`floorscan.ingest.detect.recordings_in`).

    Returns
    -------
    list of str
        The dataset names, in the order of ``recordings``.

    Raises
    ------
    ConfigError
        A floor of ``building`` names no recording of the run or a dataset not
        configured, or two floors name the same recording.
    """
    datasets = config.setdefault("datasets", {})
    names, by_file = [], {}
    for path in recordings:
        base = name = dataset_name(path)
        n = 1
        while (name in datasets and not _same_file(datasets[name].get("path"), os.fspath(path))) or name in names:
            n += 1
            name = f"{base}_{n}"
        entry = {"description": f"{os.fspath(path)} (--config path)", "path": os.fspath(path)}
        if config.get("resolution_m") is not None and Path(path).suffix.lower() in (".pgm", ".png"):
            entry["resolution_m"] = config["resolution_m"]  # a map image's metres a pixel
        datasets.setdefault(name, entry)
        datasets[name].update(copy.deepcopy(config.get("path_options") or {}))  # a reused dataset too
        names.append(name)
        by_file[Path(path).name] = name
    if names:
        config["target"] = names
    resolve_building(config, by_file)
    return names


def resolve_building(config: dict, by_file: Mapping[str, str] | None = None) -> None:
    """Resolve the ``building`` section's floors to datasets, in place: each floor's
    ``recording`` (a dataset name, or the file name of a recording of ``path``) becomes
    ``dataset``; ``storey`` defaults to ``Floor <i>`` and ``elevation_m`` to 0.

    Raises
    ------
    ConfigError
        A floor names no known dataset or recording, or two floors name one.
    """
    building = config.get("building")
    if not building:
        return
    by_file = dict(by_file or {})
    known = set(config.get("datasets") or {})
    seen = {}
    for i, floor in enumerate(building.get("floors") or []):
        ref = str(floor.get("recording", floor.get("dataset", "")))
        name = ref if ref in known else by_file.get(ref)
        if name is None:
            raise ConfigError(
                f"building.floors[{i}].recording: {ref!r} is neither a dataset nor a recording of path; "
                f"expected one of {sorted(known | set(by_file))}"
            )
        if name in seen:
            raise ConfigError(f"building.floors[{i}].recording: {ref!r} is already floor {seen[name]}")
        if name == "building":
            raise ConfigError(f"building.floors[{i}].recording: a dataset named 'building' would write in "
                              "results/building/, the building's folder; rename the recording")
        seen[name] = i
        floor["dataset"] = name
        floor.setdefault("storey", f"Floor {i}")
        floor["elevation_m"] = float(floor.get("elevation_m", 0.0))
