"""What an error message says: the user's data quoted short, a system error named.

- :func:`quoted`: a piece of the user's data (a line of a file, a field, a topic name)
  as a message quotes it, at most :data:`MAX_QUOTE` characters (a CARMEN reader given a
  ROS1 bag printed a line of 831,111 characters of binary);
- :func:`shorten_message`: the same bound on a whole message, for messages that quote
  the user's data without :func:`quoted`;
- :func:`system_error` and :func:`system_error_message`: an ``OSError`` that is the
  machine's, not the recording's (no space left, a read-only file system, permission
  denied), as one paragraph that names the path and what to do;
- :func:`count_text`: a count and its noun (``1 room``, ``12 rooms``), as every message
  and page counts things.
"""

from __future__ import annotations

import errno
import os
import re
from pathlib import Path
from typing import Iterable

#: The most characters of the user's data a message quotes.
MAX_QUOTE = 200

#: Errors of the machine, not of the recording: errno -> (what happened, what to do).
#: ``{path}`` is the file or folder, ``{folder}`` the folder holding it.
SYSTEM_ERRORS = {
    errno.ENOSPC: (
        "no space left on the device holding {path}",
        "free some space there (`df -h {folder}` shows what is left) or put results/ on a larger disk "
        "(results/ may be a symbolic link to it), then run again",
    ),
    errno.EDQUOT: (
        "disk quota exceeded writing {path}",
        "free some of your quota (`quota -s`) or put results/ on another disk "
        "(results/ may be a symbolic link to it), then run again",
    ),
    errno.EROFS: (
        "{path} is on a read-only file system",
        "run the workflow where results/ can be written (a copy of the workflow, or results/ as a symbolic "
        "link to a writable disk), or remount the disk read-write, then run again",
    ),
    errno.EACCES: (
        "permission denied {doing} {path}",
        "give your user {access} access to it (`ls -ld {path}` shows its owner and mode; "
        "e.g. `chmod u+{mode} {path}`), or run the workflow as a user who has it, then run again",
    ),
}
SYSTEM_ERRORS[errno.EPERM] = SYSTEM_ERRORS[errno.EACCES]

#: The message of each system error, for an ``OSError`` without its ``errno`` (pyarrow
#: raises some with the text alone).
_STRERRORS = {code: os.strerror(code) for code in SYSTEM_ERRORS}


def quoted(text: object, limit: int = MAX_QUOTE) -> str:
    """``repr`` of ``text`` (a ``str``; other objects as ``str(text)``), at most ``limit``
    characters of it, and the number left out when it is cut.

    Parameters
    ----------
    text : object
        The user's data: a line, a field, a topic name.
    limit : int
        The most characters of ``text`` quoted.

    Returns
    -------
    str
        ``'abc'``; or ``'abc…' (1,234 characters)`` when ``text`` is longer than
        ``limit``: its first ``limit`` characters and an ellipsis.

    Examples
    --------
    >>> quoted("FLASER 3 1.0")
    "'FLASER 3 1.0'"
    >>> quoted("x" * 1000, 5)
    "'xxxxx…' (1,000 characters)"
    """
    s = text if isinstance(text, str) else str(text)
    if len(s) <= limit:
        return repr(s)
    return f"{s[:limit] + '…'!r} ({len(s):,} characters)"


def shorten_message(message: str, token_limit: int = MAX_QUOTE, total_limit: int = 1000) -> str:
    """``message`` with every run of more than ``token_limit`` characters without a
    space cut to ``token_limit`` and an ellipsis, then the whole cut in its middle to
    at most about ``total_limit`` characters.

    The bound of :data:`MAX_QUOTE` on the user's data, for a message that quoted it
    whole (binary read as text has few spaces); the messages written by floorscan
    itself are shorter than these limits and come out unchanged.

    Parameters
    ----------
    message : str
    token_limit : int
        The most characters kept of a run without white space.
    total_limit : int
        The most characters kept of the message (plus the note of what was cut).

    Returns
    -------
    str
    """
    def cut(m: re.Match) -> str:
        token = m.group(0)
        return f"{token[:token_limit]}…({len(token):,} characters)"

    out = re.sub(rf"\S{{{token_limit + 1},}}", cut, message)
    if len(out) > total_limit:
        head, tail = out[: total_limit * 3 // 4], out[-(total_limit // 4):]
        out = f"{head} …[{len(out) - len(head) - len(tail):,} characters cut]… {tail}"
    return out


def system_error(exc: BaseException) -> OSError | None:
    """The ``OSError`` of :data:`SYSTEM_ERRORS` that ``exc`` is or was raised from.

    Parameters
    ----------
    exc : BaseException

    Returns
    -------
    OSError or None
        ``exc`` or one of its ``__cause__`` / ``__context__`` chain (five deep at most)
        with an errno of :data:`SYSTEM_ERRORS`; None for any other error.
    """
    seen = 0
    while exc is not None and seen < 5:
        if isinstance(exc, OSError) and _errno(exc) is not None:
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


def _errno(exc: OSError) -> int | None:
    if exc.errno in SYSTEM_ERRORS:
        return exc.errno
    if exc.errno is None:
        text = str(exc)
        for code, strerror in _STRERRORS.items():
            if strerror in text:
                return code
    return None


def system_error_message(
    exc: OSError, inputs: Iterable[str | os.PathLike] = (), outputs: Iterable[str | os.PathLike] = ()
) -> str:
    """The paragraph for a :func:`system_error`: what happened to which path, what to do.

    Parameters
    ----------
    exc : OSError
        With an errno of :data:`SYSTEM_ERRORS` (or its text); its ``filename`` is the
        path named, else the folder of ``outputs`` (pyarrow's errors name no file).
    inputs : iterable of path
        The job's inputs: permission denied on one of them (or inside one of its
        folders) is a read, on anything else a write.
    outputs : iterable of path
        The job's outputs.

    Returns
    -------
    str
        e.g. ``"no space left on the device holding results/lab/scans.parquet: free
        some space there (`df -h results/lab` shows what is left) ..., then run again
        ([Errno 28] No space left on device)"``.
    """
    code = _errno(exc)
    outputs = [str(p) for p in outputs]
    if exc.filename is not None:
        path = os.fsdecode(exc.filename)
    elif outputs:
        folders = sorted({str(Path(p).parent) for p in outputs})
        path = folders[0] if len(folders) == 1 else os.path.commonpath(outputs)
        if len(outputs) == 1:
            path = outputs[0]
    else:
        path = "the job's outputs"
    reading = _is_input(path, inputs)
    what, todo = SYSTEM_ERRORS[code]
    fields = {
        "path": path,
        "folder": str(Path(path).parent) if Path(path).suffix else path,
        "doing": "reading" if reading else "writing",
        "access": "read" if reading else "write",
        "mode": "r" if reading else "w",
    }
    detail = f"[Errno {code}] {os.strerror(code)}"
    return f"{what.format(**fields)}: {todo.format(**fields)} ({detail})"


def _is_input(path: str, inputs: Iterable[str | os.PathLike]) -> bool:
    p = Path(os.path.abspath(path))
    for i in inputs:
        q = Path(os.path.abspath(i))
        if p == q or q in p.parents:
            return True
    return False


def count_text(n: int, noun: str) -> str:
    """``"1 room"``, ``"12 rooms"``: a count of things as the plan's SVG summary, the
    pages and the run's last lines give it.

    Parameters
    ----------
    n : int
    noun : str
        Singular; the plural adds ``s``.

    Returns
    -------
    str
    """
    return f"{n} {noun}{'' if n == 1 else 's'}"
