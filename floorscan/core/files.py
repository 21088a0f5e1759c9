"""Files written atomically: a crash never leaves a half file.

Writers go to a temporary name in the target folder and rename (:func:`atomic_path` for
a file; :func:`staged_path` for a folder, or for a writer that chooses its format by the
file's extension). A temporary of an output ``name`` is a hidden sibling ``.<name>.*``
(:func:`atomic_path`: ``.<name>.<8 characters>.tmp``); one left by a killed run is
removed by the next run of the stage (:func:`remove_stale_temporaries`, called by
:func:`floorscan.core.stage.stage_log` for the outputs of the job) and by the first
:func:`atomic_path` of the same file in a process.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np


_UMASK = os.umask(0)
os.umask(_UMASK)

#: The random part of a ``tempfile.mkstemp`` / ``mkdtemp`` name (8 characters).
_MKSTEMP_CHARS = r"[a-z0-9_]{8}"


def _tmp_path(path: Path) -> Path:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def stale_temporaries(path: str | os.PathLike, only_atomic: bool = False) -> list[Path]:
    """The temporaries of output ``path`` present beside it, sorted.

    A writer of ``path`` names its temporaries ``.<name>.*`` in the same folder: files
    of :func:`atomic_path` (``.<name>.<8 characters>.tmp``), folders of
    :func:`staged_path` and the simulator (``...tmp``,
    ``...old``), the register stage's copy of the sampled scans
    (``.<name>.sampled.parquet``). Run while no job writes ``path`` (a stage's outputs
    are its own), they are left by a killed run.

    Parameters
    ----------
    path : path
        An output file or folder.
    only_atomic : bool
        Only the files :func:`atomic_path` makes.

    Returns
    -------
    list of Path
    """
    path = Path(path)
    return _temporaries_of(path, _listing(path.parent), only_atomic) if path.name else []


def _listing(folder: Path) -> set[str]:
    """The hidden entries of ``folder`` (every temporary is one; usually there are none)."""
    try:
        return {n for n in os.listdir(folder) if n.startswith(".")}
    except (FileNotFoundError, NotADirectoryError):
        return set()


def _temporaries_of(path: Path, names: Iterable[str], only_atomic: bool) -> list[Path]:
    """The names among ``names`` (hidden entries of ``path``'s folder) that are
    temporaries of ``path``."""
    prefix = f".{path.name}."
    tail = rf"{_MKSTEMP_CHARS}\.tmp" if only_atomic else r".+"
    pattern = re.compile(rf"{re.escape(prefix)}{tail}")
    return sorted(path.parent / n for n in names if pattern.fullmatch(n))


#: Outputs whose stale temporaries this process removed already (:func:`atomic_path`
#: looks for them once, not at every write: only a killed process leaves one).
_SWEPT: set[Path] = set()


def remove_stale_temporaries(
    paths: Iterable[str | os.PathLike], only_atomic: bool = False
) -> list[tuple[Path, Path]]:
    """Remove :func:`stale_temporaries` of each of ``paths`` (files and folders), each
    folder listed once.

    Call it before a stage writes ``paths``: a run killed with SIGKILL (or a machine
    that went down) cannot remove its temporaries, and Snakemake does not know them.

    Returns
    -------
    list of (Path, Path)
        Each temporary removed and the output it belonged to.
    """
    listings: dict[Path, set[str]] = {}
    removed = []
    for path in map(Path, paths):
        if not path.name:
            continue
        names = listings.get(path.parent)
        if names is None:
            names = listings[path.parent] = _listing(path.parent)
        for p in _temporaries_of(path, names, only_atomic):
            names.discard(p.name)
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                with contextlib.suppress(FileNotFoundError):
                    p.unlink()
            removed.append((p, path))
        _SWEPT.add(path)
    return removed


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is left untouched,
    so a failed stage leaves no half-written output. Temporaries of ``path`` that an
    earlier, killed writer left (``.<name>.<8 characters>.tmp``) are removed first,
    unless this process removed them already (:func:`remove_stale_temporaries`).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path not in _SWEPT:
        remove_stale_temporaries([path], only_atomic=True)
    tmp = _tmp_path(path)
    try:
        yield tmp
        if tmp.is_file():  # mkstemp makes files private (0600); give them the usual umask mode
            tmp.chmod(0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def staged_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a path with the name of ``path`` inside a temporary folder beside it; on
    success move it to ``path`` (replacing a file or folder there).

    For writers that choose the format by the extension (Open3D) or write a folder
    (a ROS2 bag, a PCD folder) and so cannot use :func:`atomic_path`. On an exception
    the temporary folder is removed and ``path`` is left untouched. A folder at
    ``path`` is replaced by two renames (the old one moved aside first), so a reader
    sees the old or the new folder, or for an instant none. What the writer creates
    inside the private temporary folder keeps the mode it was created with (the
    umask's), and only it is moved out.

    Raises
    ------
    FileNotFoundError
        The writer wrote nothing at the yielded path.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    try:
        tmp = stage / path.name
        yield tmp
        if not tmp.exists():
            raise FileNotFoundError(f"{path}: nothing was written")
        if path.is_dir() and not path.is_symlink():
            os.replace(path, stage / (path.name + ".old"))
        os.replace(tmp, path)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def write_json(obj: object, path: str | os.PathLike) -> None:
    """Write JSON atomically, sorted keys, 2-space indent."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, sort_keys=True, default=_json_default) + "\n")


def _json_default(o: object) -> object:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serializable: {type(o).__name__}")
