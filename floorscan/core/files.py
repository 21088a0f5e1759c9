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
import hashlib
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

    Parameters
    ----------
    paths : iterable of path
        The outputs whose temporaries to remove; a path with an empty name is skipped.
    only_atomic : bool
        Only the temporaries of :func:`atomic_path` (``.<name>.<8 characters>.tmp``);
        otherwise every hidden ``.<name>.<anything>`` entry (:func:`staged_path`'s folders
        too).

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
    so a failed stage leaves no half-written output; an ``OSError`` that names no file
    or the temporary is made to name ``path``. Temporaries of ``path`` that an
    earlier, killed writer left (``.<name>.<8 characters>.tmp``) are removed first,
    unless this process removed them already (:func:`remove_stale_temporaries`).

    Parameters
    ----------
    path : path
        The output; its folder is created when missing.

    Yields
    ------
    Path
        The temporary path (``.<name>.<8 characters>.tmp`` in the same folder) to write.

    Raises
    ------
    BaseException
        Whatever the writer raised, re-raised after the temporary is removed (an
        ``OSError`` then names ``path``).
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
    except BaseException as e:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        _name_output(e, tmp, path)
        raise


def _name_output(exc: BaseException, tmp: Path, path: Path) -> None:
    """Make an ``OSError`` of writing temporary ``tmp`` name output ``path`` instead (or
    name it at all: pyarrow's errors of a full disk name no file), for the message
    (:func:`floorscan.core.messages.system_error_message`)."""
    if isinstance(exc, OSError) and (exc.filename is None or os.fspath(exc.filename) == str(tmp)):
        exc.filename = str(path)


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

    Parameters
    ----------
    path : path
        The output file or folder; its parent folder is created when missing.

    Yields
    ------
    Path
        ``<temporary folder>/<name of path>``, to write.

    Raises
    ------
    FileNotFoundError
        The writer wrote nothing at the yielded path.
    OSError
        From the writer or the renames, re-raised naming ``path``.
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
    except OSError as e:
        _name_output(e, tmp, path)
        raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def write_json(obj: object, path: str | os.PathLike) -> None:
    """Write JSON atomically (:func:`atomic_path`), sorted keys, 2-space indent.

    Parameters
    ----------
    obj : object
        JSON-serialisable, numpy scalars and arrays too (``_json_default``).
    path : path
    """
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(obj, indent=2, sort_keys=True, default=_json_default) + "\n")


def _json_default(o: object) -> object:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def recording_fingerprint(path: str | os.PathLike) -> dict[str, int | str] | None:
    """What a recording on disk is, cheaply: its files' sizes and modification times.

    Passed through the ingest rule's ``params:``, it makes Snakemake rerun ingest when the
    recording changes, whatever its modification time: a recording replaced by an older
    copy (``cp -p``) is older than the tables made from it, so Snakemake's time stamps
    alone would keep the old tables. Size and modification time in nanoseconds are what
    ``rsync`` and ``make`` trust; reading every byte of a recording of gigabytes at each
    start of the workflow to hash it would cost more than an ingest.

    Parameters
    ----------
    path : path
        A recording: a file (ROS1 bag, CARMEN log), or a folder (ROS2 bag, PCD folder),
        whose every file below it counts (hidden ones and symbolic links followed too).

    Returns
    -------
    dict or None
        ``{"files": n, "bytes": total size in bytes, "stat_sha256": hex digest}``, the
        digest of each file's path relative to ``path``, size and ``st_mtime_ns``, in
        path order (a short value however many files a PCD folder has); None when
        ``path`` does not exist (Snakemake then reports the missing input).
    """
    path = Path(path)
    try:
        top = path.stat()
    except OSError:
        return None
    if path.is_dir():
        files = []
        for root, dirs, names in os.walk(path, followlinks=True):
            dirs.sort()
            for name in names:
                p = Path(root) / name
                try:
                    st = p.stat()
                except OSError:  # a dangling link: counted as it is
                    st = p.lstat()
                files.append((p.relative_to(path).as_posix(), st.st_size, st.st_mtime_ns))
        files.sort()
    else:
        files = [("", top.st_size, top.st_mtime_ns)]
    digest = hashlib.sha256()
    for name, size, mtime_ns in files:
        digest.update(f"{name}\0{size}\0{mtime_ns}\n".encode("utf-8", "surrogateescape"))
    return {"files": len(files), "bytes": sum(f[1] for f in files), "stat_sha256": digest.hexdigest()[:16]}


def writable_problem(folder: str | os.PathLike, probe_bytes: int = 4096) -> str | None:
    """Why the workflow cannot write in ``folder``, or None when it can.

    Checked at the start of a run (``workflow/rules/common.smk``), before Snakemake
    makes its first folder: a read-only results folder otherwise ends in Snakemake's
    own traceback, or in the traceback of the first stage. A file of ``probe_bytes``
    bytes is written in ``folder`` (in the nearest folder above it that exists, when it
    does not) and removed; it has no name (``O_TMPFILE``) where the system allows, so
    even a killed run leaves nothing.

    Parameters
    ----------
    folder : path
        A folder the workflow writes in (``results``, ``.snakemake``).
    probe_bytes : int
        Bytes written, so that a full disk is found as well as a read-only one.

    Returns
    -------
    str or None
        One paragraph naming the folder, the error and what to do
        (:func:`floorscan.core.messages.system_error_message`); None when it can be
        written.
    """
    from floorscan.core.messages import system_error, system_error_message

    folder = Path(folder)
    probe = folder
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    try:
        with tempfile.TemporaryFile(dir=probe) as f:
            f.write(b"\0" * probe_bytes)
            f.flush()
    except OSError as e:
        if system_error(e) is None:  # not the machine's (a vanished folder): Snakemake's to judge
            return None
        e.filename = os.path.abspath(folder)
        return system_error_message(e)
    return None
