"""The text formats, a CARMEN log, an ascii PCD, the locations CSV: their files and
their number fields.

A text recording is opened by :func:`open_text` (its bytes by :func:`open_binary`), plain
or gzip: a UTF-8 byte-order mark is dropped, and bytes after the gzip data that are not another gzip member are left
out with a warning, as ``gzip -d`` does ("trailing garbage ignored").

Every text reader reads a number the same way: :func:`parse_number` one field,
:func:`parse_numbers` many in one numpy call. Both read what Python's ``float`` reads
(``nan`` and ``inf`` included, for the caller to judge) except ``1_0``, and return None
for a field that is not a number, so the caller can name it in its message, quoted by
:func:`floorscan.core.messages.quoted` (at most 200 characters of it: a binary file read
as text has lines of megabytes).
"""

from __future__ import annotations

import io
import logging
import os
import zlib
from pathlib import Path
from typing import BinaryIO, Sequence, TextIO

import numpy as np

GZIP_MAGIC = b"\x1f\x8b"
#: Compressed bytes read at a time.
_CHUNK = 1 << 18

log = logging.getLogger(__name__)


def is_gzip(path: str | os.PathLike) -> bool:
    """Whether the file at ``path`` starts with the gzip magic bytes.

    Parameters
    ----------
    path : path

    Returns
    -------
    bool

    Raises
    ------
    OSError
        The file cannot be opened.
    """
    with open(path, "rb") as f:
        return f.read(2) == GZIP_MAGIC


def open_binary(path: str | os.PathLike, notes: list[str] | None = None, warn: bool = True) -> BinaryIO:
    """The bytes of a text recording, plain or gzip (by its first bytes, whatever its
    suffix): a gzip file is read member after member (``cat a.gz b.gz`` is one file, as
    for ``gzip -d``); bytes after the last member that do not start another one are
    trailing garbage: left out, with a warning when the reader reaches them.

    Parameters
    ----------
    path : path
    notes : list of str, optional
        Gets the warning about trailing garbage appended, for the recording's notes.
    warn : bool
        Log the warning (logger ``floorscan.ingest.text``, level WARNING); False for a
        reader that only peeks (format detection) or reads the file again (the reduced
        recording) and leaves the warning to ingest's reader of the whole file.

    Returns
    -------
    binary file
        Close it (or use ``with``).

    Raises
    ------
    OSError
        The file cannot be opened or read.
    EOFError
        The gzip data ends before its end-of-stream marker (a truncated file), when the
        reader gets there.
    zlib.error
        The gzip data is corrupt (or its CRC does not match), when the reader gets there.
    """
    path = Path(path)
    if not is_gzip(path):
        return open(path, "rb")
    return io.BufferedReader(_GzipMembers(path, notes, warn), buffer_size=1 << 16)


def open_text(path: str | os.PathLike, notes: list[str] | None = None, warn: bool = True) -> TextIO:
    """A text recording, plain or gzip (:func:`open_binary`), as text.

    UTF-8; a byte-order mark before the first line is dropped (an editor's: read as
    ASCII it made the first line's type unknown); bytes that are not UTF-8 are read as
    U+FFFD.

    Parameters
    ----------
    path : path
    notes : list of str, optional
    warn : bool
        As :func:`open_binary`.

    Returns
    -------
    text file
        Iterate it for lines; close it (or use ``with``).

    Raises
    ------
    OSError, EOFError
        As :func:`open_binary`.
    """
    return io.TextIOWrapper(open_binary(path, notes, warn), encoding="utf-8-sig", errors="replace")


class _GzipMembers(io.RawIOBase):
    """The decompressed bytes of a gzip file's members; trailing garbage left out."""

    def __init__(self, path: Path, notes: list[str] | None, warn: bool):
        super().__init__()
        self._path, self._notes, self._warn = path, notes, warn
        self._file = open(path, "rb")
        self._d = zlib.decompressobj(16 + zlib.MAX_WBITS)
        self._buf = memoryview(b"")
        self._done = False
        #: Bytes of trailing garbage found (0 until the reader reaches the end).
        self.trailing = 0

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:
        while not self._buf and not self._done:
            self._fill()
        n = min(len(b), len(self._buf))
        b[:n] = self._buf[:n]
        self._buf = self._buf[n:]
        return n

    def _fill(self) -> None:
        if self._d.eof:  # a member ended: another one, the end, or trailing garbage
            rest = self._d.unused_data
            while len(rest) < len(GZIP_MAGIC):
                more = self._file.read(_CHUNK)
                if not more:
                    break
                rest += more
            if not rest:
                self._done = True
                return
            if rest[: len(GZIP_MAGIC)] != GZIP_MAGIC:
                self._trailing(len(rest) + os.fstat(self._file.fileno()).st_size - self._file.tell())
                return
            self._d = zlib.decompressobj(16 + zlib.MAX_WBITS)
            data = rest
        else:
            data = self._file.read(_CHUNK)
            if not data:
                raise EOFError("Compressed file ended before the end-of-stream marker was reached")
        self._buf = memoryview(self._d.decompress(data))

    def _trailing(self, n_bytes: int) -> None:
        self._done = True
        self.trailing = n_bytes
        note = (
            f"{self._path}: {n_bytes} bytes of trailing garbage after the gzip data ignored "
            "(as gzip -d does); the log was read up to them"
        )
        if self._notes is not None:
            self._notes.append(note)
        if self._warn:
            log.warning("%s", note)

    def close(self) -> None:
        if not self.closed:
            self._file.close()
        super().close()


def parse_number(text: str) -> float | None:
    """A number field of a text recording, or None when ``text`` is not a number.

    Python's ``float`` (``nan`` and ``inf`` included, for the caller to judge), except
    for ``1_0``: Python reads 10, the C readers of these formats (``strtod``) read 1.

    Parameters
    ----------
    text : str

    Returns
    -------
    float or None
    """
    if "_" in text:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def parse_numbers(texts: Sequence[str]) -> np.ndarray | None:
    """:func:`parse_number` of every text, parsed by numpy in one call (it reads what
    ``float`` reads).

    Parameters
    ----------
    texts : (N,) sequence of str

    Returns
    -------
    (N,) float64 ndarray or None
        None when one of them is not a number (the caller finds which, one by one, for
        its message).
    """
    if "_" in "".join(texts):
        return None
    try:
        return np.array(texts, dtype=np.float64)
    except ValueError:
        return None
