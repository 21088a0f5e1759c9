"""The laser lines of a CARMEN log: their layouts, and one line's fields read and checked.

Line formats (CARMEN logger documentation, as in the Radish datasets)::

    FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
    ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy
        remission_mode n r1..rn n_remissions v1..vm laser_x laser_y laser_theta
        robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis
        ipc_timestamp ipc_hostname logger_timestamp

``x y theta`` (FLASER) and ``laser_x laser_y laser_theta`` (ROBOTLASER1) are the laser's
corrected pose in the map frame.

FLASER beams span the field of view (default 180 degrees) starting at -fov/2. With an
even beam count (180, 360) the increment is fov/n; with an odd one (181, 361) both ends
are included and it is fov/(n-1): the convention of the Radish logs' readers.

Malformed lines. A laser line is read only when it has exactly the fields its
counts imply: ``2 + n + 9`` for FLASER, ``24 + n + m`` for ROBOTLASER1 (n beams, m
remissions); a field too many or too few would shift every later field (a range read as
the pose, the pose as the stamp), so it is an ``InputError`` naming ``file:line``, the
counts and the layout, never parsed from shifted positions. Every numeric field must be a
number; the corrected pose, ROBOTLASER1's ``start_angle``, ``angular_resolution`` and
``maximum_range`` must be finite. The error names the line and the field. Non-finite
*ranges* are not errors: they are "no return", dropped and counted like the others.
``ipc_timestamp`` is read as written (NaN, inf, negative included): whether a stamp out
of range is a malformed line or the whole log's stamps are junk and made up is decided
over all the laser lines (:mod:`floorscan.ingest.carmen_stamps`; the message is
:func:`stamp_problem`).

Broken geometry. A well-formed ROBOTLASER1 line whose ``angular_resolution`` is 0, whose
``fov`` is not finite or wider than a full turn (degrees), or disagrees with
``n x angular_resolution`` by more than one beam, would draw its beams at wrong angles:
:func:`robotlaser_geometry_problem` says what, and the reader skips the line's scan and
counts it (``lost_bad_frames``); its pose is kept.
"""

from __future__ import annotations

import math
import re

import numpy as np

from floorscan.ingest.carmen_stamps import WRAP_S
from floorscan.ingest.points import angle_span_problem
from floorscan.ingest.text import parse_number, parse_numbers


LASER_TYPES = ("FLASER", "ROBOTLASER1")
#: Message types a CARMEN log may hold: those the CARMEN logger's file header defines
#: (``carmen/src/logger/writelog.c``: PARAM, SYNC, ODOM, TRUEPOS, RAWLASER1-4,
#: POSITIONLASER, ROBOTLASER1-2, NMEAGGA, NMEARMC, SONAR, BUMPER, SCANMARK, IMU,
#: VECTORMOVE, ROBOTVELOCITY, FOLLOWTRAJECTORY, BASEVELOCITY and the old FLASER, RLASER,
#: LASER3, LASER4, REMISSION*), plus COMMENT and NEFF (the number of effective particles
#: of the Radish corrected logs). A line of another type is counted as unknown
#: (``lost_unknown_lines``): a misspelt or garbled line type loses its scan silently.
CARMEN_TYPES = frozenset(
    (
        "PARAM", "COMMENT", "SYNC", "ODOM", "TRUEPOS", "RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4",
        "POSITIONLASER", "ROBOTLASER1", "ROBOTLASER2", "NMEAGGA", "NMEARMC", "SONAR", "BUMPER", "SCANMARK", "IMU",
        "VECTORMOVE", "ROBOTVELOCITY", "FOLLOWTRAJECTORY", "BASEVELOCITY", "FLASER", "RLASER", "LASER3", "LASER4",
        "REMISSIONFLASER", "REMISSIONRLASER", "REMISSIONLASER3", "REMISSIONLASER4", "NEFF",
    )
)
#: The field layout of each laser line, for error messages.
LAYOUTS = {
    "FLASER": "FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp",
    "ROBOTLASER1": (
        "ROBOTLASER1 laser_type start_angle fov angular_resolution maximum_range accuracy remission_mode "
        "n r1..rn m v1..vm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety "
        "side_safety turn_axis ipc_timestamp ipc_hostname logger_timestamp"
    ),
}
#: Fields of a FLASER line besides its n ranges.
FLASER_FIXED_FIELDS = 11
#: Fields of a ROBOTLASER1 line besides its n ranges and m remissions.
ROBOTLASER1_FIXED_FIELDS = 24

_INTEGER = re.compile(r"\+?[0-9]+")


class MalformedLine(ValueError):
    """A laser line that does not follow its layout (the message says how)."""


def _number(tok: list[str], i: int, name: str) -> float:
    v = parse_number(tok[i])
    if v is None:
        raise MalformedLine(f"field {i + 1} ({name}) is {tok[i]!r}; expected a number")
    return v


def _finite(tok: list[str], i: int, name: str) -> float:
    v = _number(tok, i, name)
    if not math.isfinite(v):
        raise MalformedLine(f"field {i + 1} ({name}) is {tok[i]}; expected a finite number")
    return v


def _count(tok: list[str], i: int, name: str, minimum: int) -> int:
    t = tok[i]
    if not _INTEGER.fullmatch(t) or int(t) < minimum:
        raise MalformedLine(f"field {i + 1} ({name}) is {t!r}; expected an integer >= {minimum}")
    return int(t)


def _numbers(tok: list[str], a: int, b: int, what: str) -> np.ndarray:
    """Fields ``a:b`` as float64, any value (NaN and inf included)."""
    values = parse_numbers(tok[a:b])
    if values is None:  # name the field (one by one: slow, but only on a bad line)
        values = np.array([_number(tok, i, f"{what} {i - a + 1}") for i in range(a, b)], dtype=np.float64)
    return values


def stamp_problem(field: int, text: str) -> str:
    """What is wrong with an ``ipc_timestamp`` out of range, for the malformed line's
    message.

    Parameters
    ----------
    field : int
        The field's position, 1-based.
    text : str
        The field as written.

    Returns
    -------
    str
    """
    return (
        f"field {field} (ipc_timestamp) is {text}; expected a finite time in seconds, 0 or more and "
        f"below {WRAP_S:.0f} (2^31 s, the 32-bit wrap)"
    )


def parse_laser_line(kind: str, tok: list[str], fov_rad: float, lineno: int) -> dict:
    """One laser line's fields, read only when their count is exactly the layout's
    (CARMEN's FLASER and ROBOTLASER1 message layouts).

    Parameters
    ----------
    kind : str
        ``"FLASER"`` or ``"ROBOTLASER1"``.
    tok : list of str
        The line split on white space, the type first.
    fov_rad : float
        FLASER's field of view, radians (the line does not give it).
    lineno : int
        The line's number, 1-based, stored as ``line``.

    Returns
    -------
    dict
        ``t_s`` (the ``ipc_timestamp`` as written, seconds; NaN, inf or negative too:
        :mod:`floorscan.ingest.carmen_stamps` judges the log's stamps together), ``ranges``
        ((n,) float64, metres), ``start`` and ``inc`` (first beam angle and increment,
        radians), ``rmax`` (the line's maximum range, metres; inf for FLASER), ``pose``
        ((3,) float64: x, y metres, theta radians, the laser's), ``line``, ``kind``,
        ``problem`` (None, or what is wrong with a ROBOTLASER1 line's beam geometry,
        :func:`robotlaser_geometry_problem`: the reader skips its scan), ``stamp_field``
        (1-based) and ``stamp_text``.

    Raises
    ------
    MalformedLine
        A field count other than the layout's (FLASER ``2 + n + 9``, ROBOTLASER1
        ``24 + n + m``), a non-numeric field (the stamp too), a non-finite pose, angle
        or maximum range.
    """
    rmax = math.inf
    if kind == "FLASER":
        if len(tok) < 2:
            raise MalformedLine(f"{len(tok)} fields; expected 2 + n + 9")
        n = _count(tok, 1, "n, the beam count", 1)
        need = n + FLASER_FIXED_FIELDS
        if len(tok) != need:
            raise MalformedLine(f"{len(tok)} fields for n = {n} beams; expected 2 + n + 9 = {need}")
        ranges = _numbers(tok, 2, 2 + n, "range")
        k = 2 + n
        names = ("x", "y", "theta")
        inc = fov_rad / (n - 1) if n % 2 == 1 and n > 1 else fov_rad / n
        start = -fov_rad / 2.0
        others = ("odom_x", "odom_y", "odom_theta")
        stamp_at = k + 6
        problem = None
    else:
        if len(tok) < 9:
            raise MalformedLine(f"{len(tok)} fields; expected 24 + n + m (n at field 9)")
        n = _count(tok, 8, "n, the beam count", 1)
        if len(tok) < 10 + n:
            raise MalformedLine(
                f"{len(tok)} fields for n = {n} beams; expected 24 + n + m, at least {ROBOTLASER1_FIXED_FIELDS + n}"
            )
        m = _count(tok, 9 + n, "m, the remission count", 0)
        need = ROBOTLASER1_FIXED_FIELDS + n + m
        if len(tok) != need:
            raise MalformedLine(
                f"{len(tok)} fields for n = {n} beams and m = {m} remissions; expected 24 + n + m = {need}"
            )
        _number(tok, 1, "laser_type")
        start = _finite(tok, 2, "start_angle")
        fov = _number(tok, 3, "fov")
        inc = _finite(tok, 4, "angular_resolution")
        problem = robotlaser_geometry_problem(fov, inc, n)
        line_rmax = _finite(tok, 5, "maximum_range")
        _number(tok, 6, "accuracy")
        _number(tok, 7, "remission_mode")
        ranges = _numbers(tok, 9, 9 + n, "range")
        _numbers(tok, 10 + n, 10 + n + m, "remission")
        k = 10 + n + m
        names = ("laser_x", "laser_y", "laser_theta")
        others = ("robot_x", "robot_y", "robot_theta", "tv", "rv", "forward_safety", "side_safety", "turn_axis")
        stamp_at = k + 11
        if line_rmax > 0:
            rmax = line_rmax
    pose = np.array([_finite(tok, k + j, name) for j, name in enumerate(names)])
    for j, name in enumerate(others):
        _number(tok, k + 3 + j, name)
    t_s = _number(tok, stamp_at, "ipc_timestamp")
    _number(tok, stamp_at + 2, "logger_timestamp")
    return {
        "t_s": t_s, "ranges": ranges, "start": start, "inc": inc, "rmax": rmax, "pose": pose, "line": lineno, "kind": kind,
        "problem": problem, "stamp_field": stamp_at + 1, "stamp_text": tok[stamp_at],
    }


def robotlaser_geometry_problem(fov: float, resolution: float, n: int) -> str | None:
    """What is wrong with a ROBOTLASER1 line's beam geometry, or None.

    Parameters
    ----------
    fov : float
        ``fov`` field (field of view), radians.
    resolution : float
        ``angular_resolution`` field, radians between beams (finite: checked as the line
        is read).
    n : int
        Beam count.

    Returns
    -------
    str or None
        The field and what was expected: ``angular_resolution`` 0; ``fov`` not finite, or
        wider than a full turn (degrees?); ``|fov|`` and ``n x |angular_resolution|``
        more than one beam (``|angular_resolution|``) apart (loggers write both ``n`` and
        ``n - 1`` steps for the same scan).
    """
    if resolution == 0.0:
        return "field 5 (angular_resolution) is 0; expected the non-zero angle between beams, radians"
    if not math.isfinite(fov):
        return f"field 4 (fov) is {fov}; expected a finite field of view, radians"
    bad = angle_span_problem(fov, "field 4 (fov)")
    if bad:
        return bad
    span = n * abs(resolution)
    if abs(abs(fov) - span) > abs(resolution) * (1.0 + 1e-6):
        return (
            f"field 4 (fov) is {fov:g} rad, but n x angular_resolution = {n} x {resolution:g} = {span:g} rad; "
            "expected them within one beam"
        )
    return None
