"""The recordings of a run: the checks of the ``datasets`` a schema cannot make, a
recording given by ``--config path=...`` (a file or a folder of them) made datasets, and
the ``building`` section's floors resolved to datasets. The Snakefile calls them once,
after :func:`floorscan.core.config.validate_config`.

A recording's dataset is named after its file (:func:`dataset_name`): ``trace0.bag`` is
the dataset ``trace0`` wherever it lies; the shipped examples of ``config/config.yaml``
(``demo``, ``trace0``, ...) give way to a path of the same name
(:func:`add_path_datasets`).
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
    """The dataset name of a recording or map: its file or folder name without the
    recording suffixes (``.gz``, ``.log``, ``.clf``, ``.bag``, ``.db3``, ``.mcap``; a
    map's ``.yaml``, ``.yml``, ``.pgm``, ``.png``), each character other than a letter, a
    digit, ``_`` or ``-`` replaced by ``_``.

    The replacement is kept for what the name is used as: a folder ``results/<name>/``
    printed unquoted in the answer, a word of ``--config target=[...]`` and a key of
    ``--set datasets.<name>.<key>=...`` (a space or a ``.`` would break the last two).
    A ``-`` stays: a wildcard holds it (``intel-corrected.log.gz`` is
    ``intel-corrected``, ``lab run.bag`` is ``lab_run``, ``2024.05.bag`` is
    ``2024_05``).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    str
        ``recording`` when nothing is left.
    """
    import re
    from pathlib import PurePath

    name = PurePath(os.fspath(path).rstrip("/")).name
    for suffix in (".gz", ".log", ".clf", ".bag", ".db3", ".mcap", ".yaml", ".yml", ".pgm", ".png"):
        if name.lower().endswith(suffix) and len(name) > len(suffix):
            name = name[: -len(suffix)]
    return re.sub(r"[^A-Za-z0-9_-]", "_", name) or "recording"


#: The shipped config: its datasets are the examples (the synthetic buildings, the
#: recordings of ../shared/data), which give way to a path of the same name.
SHIPPED_CONFIG = "config/config.yaml"


def shipped_datasets(path: str | os.PathLike = SHIPPED_CONFIG) -> dict:
    """The datasets of the shipped config file, as written there.

    Parameters
    ----------
    path : path
        ``config/config.yaml`` of the repository.

    Returns
    -------
    dict
        ``{name: entry}``; empty when the file is missing or names none.
    """
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}
    except OSError:
        return {}
    return dict(data.get("datasets") or {}) if isinstance(data, dict) else {}


def _is_shipped(entry: Mapping, shipped: Mapping | None) -> bool:
    """Whether a configured dataset is the shipped one: every key the shipped config
    gives it has the shipped value (the schema may have filled in more)."""
    return bool(shipped) and all(entry.get(k) == v for k, v in shipped.items())


def _what_it_names(entry: Mapping) -> str:
    if entry.get("format") == "synthetic":
        return f"the synthetic building {entry.get('building')!r}"
    return os.fspath(entry.get("path", "another recording"))


def add_path_datasets(config: dict, recordings: list, shipped: Mapping | None = None) -> list[str]:
    """Make the recordings of the top-level ``path`` (``--config path=/data/run.bag``, or
    a folder of recordings) datasets, the run's targets.

    A recording's dataset is named after its file, always (:func:`dataset_name`), and
    holds ``path`` (ingest detects the rest), the keys of the top-level ``path_options``
    (``scan_topic``, ``pose``, ...: what the user sets of every recording of ``path``)
    and, for a map image, the top-level ``resolution_m``. A configured dataset of that
    name is reused when it has the same recording (the same path, relative to the
    working directory or absolute); a shipped example of that name (``shipped``, as
    :func:`shipped_datasets` reads it, unchanged by the user's config) gives way: the
    path's dataset replaces it in this run. The ``building`` section's floors name
    their recording by dataset name or file name; they are resolved to dataset names
    (``building.floors[i].dataset``).

    Parameters
    ----------
    config : dict
        The validated workflow config; changed in place (``datasets``, ``target``,
        ``building``).
    recordings : list of path
        The recordings ``path`` names (:func:`floorscan.ingest.detect.recordings_in`).
    shipped : mapping, optional
        The shipped config's datasets, ``{name: entry}``.

    Returns
    -------
    list of str
        The dataset names, in the order of ``recordings``.

    Raises
    ------
    ConfigError
        Two recordings of the run with one name; a dataset of the user's config with
        the name of a recording of the run and another recording; a floor of
        ``building`` that names no recording of the run or a dataset not configured,
        or two floors that name the same recording.
    """
    datasets = config.setdefault("datasets", {})
    shipped = dict(shipped or {})
    names, by_file, given = [], {}, {}
    for path in recordings:
        name = dataset_name(path)
        if name in given:
            raise ConfigError(
                f"path: {given[name]} and {os.fspath(path)} would both be the dataset {name!r} (a recording's dataset "
                "is named after its file): rename one, or run them one at a time"
            )
        given[name] = os.fspath(path)
        entry = {"description": f"{os.fspath(path)} (--config path)", "path": os.fspath(path)}
        if config.get("resolution_m") is not None and Path(path).suffix.lower() in (".pgm", ".png"):
            entry["resolution_m"] = config["resolution_m"]  # a map image's metres a pixel
        known = datasets.get(name)
        if known is None or (not _same_file(known.get("path"), os.fspath(path)) and _is_shipped(known, shipped.get(name))):
            datasets[name] = entry  # new, or a shipped example of that name giving way
        elif not _same_file(known.get("path"), os.fspath(path)):
            raise ConfigError(
                f"datasets.{name} names {_what_it_names(known)}; the recording {os.fspath(path)} would be the dataset "
                f"{name!r} too (a recording's dataset is named after its file): rename the dataset or the file"
            )
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
