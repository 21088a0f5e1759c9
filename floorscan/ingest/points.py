"""The returns every reader keeps: finite and in ``[range_min, range_max)``; the scans it skips.

A return at the maximum range is the scanner's "no return" (the Stage simulator, for
one, reports every beam that hits nothing at exactly ``range_max``) and would draw an arc
of fake wall, so the interval is open at the top. :func:`laser_scan_points` turns a
planar range scan into points; :func:`filter_points` applies the same rule to points;
:func:`no_return_reason` and :func:`no_point_reason` say why a scan kept none.

A scan frame that cannot be used is skipped and counted, the same way in every reader
(:class:`ScanLosses`): a frame with broken geometry or that cannot be decoded
(``lost_bad_frames``), or without a valid return (``lost_no_points``). A few are noted
(the first one named) and logged as a warning; more than half of the frames broken, or
no usable frame at all, is an ``InputError`` naming the first one and its field.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from floorscan.core.io import InputError

log = logging.getLogger(__name__)


def laser_scan_points(
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
) -> tuple[np.ndarray, int]:
    """Convert a planar range scan to points in the scanner frame.

    Parameters
    ----------
    ranges : (B,) float ndarray
        Range of each beam, metres; beam i points at ``angle_min + i * angle_increment``
        radians, counter-clockwise from the scanner's +x.
    range_min, range_max : float
        Valid range interval ``[range_min, range_max)``, metres: a return at
        ``range_max`` is the scanner's "no return" (the Stage simulator, for one,
        reports every beam that hits nothing at exactly ``range_max``).

    Returns
    -------
    points : (N, 3) float32 ndarray
        Valid returns (z = 0), metres.
    n_dropped : int
        Beams dropped: NaN, inf, below ``range_min``, at or beyond ``range_max``.
    """
    r = np.asarray(ranges, dtype=np.float64)
    angles = angle_min + angle_increment * np.arange(r.size)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= range_min) & (r < range_max)
    pts = np.zeros((int(ok.sum()), 3), dtype=np.float32)
    pts[:, 0] = r[ok] * np.cos(angles[ok])
    pts[:, 1] = r[ok] * np.sin(angles[ok])
    return pts, int(r.size - ok.sum())


def filter_points(
    points: np.ndarray, range_min: float | None = None, range_max: float | None = None
) -> tuple[np.ndarray, int]:
    """Drop non-finite points and points outside a range interval (distance from origin).

    The same rule as :func:`laser_scan_points`: a point is kept when its distance ``d``
    satisfies ``range_min <= d < range_max`` (each bound only when given).

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    range_min, range_max : float, optional
        Range interval ``[range_min, range_max)``, metres.

    Returns
    -------
    points : (M, 3) float32 ndarray
        ``points`` itself when it is float32 and every point is kept (no copy).
    n_dropped : int
        Points dropped: non-finite or outside the range interval.
    """
    p = np.asarray(points)
    if p.dtype != np.float32:  # float32 input (PointCloud2) is checked as it is: no copy
        p = p.astype(np.float64)
    p = p.reshape(-1, 3)
    ok = np.isfinite(p[:, 0]) & np.isfinite(p[:, 1]) & np.isfinite(p[:, 2])  # per column: cheaper than all(axis=1)
    if range_min is not None or range_max is not None:
        q = p.astype(np.float64)  # distances in float64, whatever the input
        with np.errstate(invalid="ignore"):
            d = np.sqrt(q[:, 0] ** 2 + q[:, 1] ** 2 + q[:, 2] ** 2)
        if range_min is not None:
            ok &= d >= range_min
        if range_max is not None:
            ok &= d < range_max
    n_ok = int(np.count_nonzero(ok))
    kept = p.astype(np.float32, copy=False) if n_ok == len(p) else p[ok].astype(np.float32, copy=False)
    return kept, len(p) - n_ok


def no_return_reason(ranges: np.ndarray, range_min: float, range_max: float) -> str:
    """Why none of ``ranges`` is a valid return, for messages: ``of its 181 ranges, 181
    are NaN; expected finite ranges in [range_min 0.05, range_max 30) m``.

    Parameters
    ----------
    ranges : (B,) float ndarray
        Ranges of one scan, metres.
    range_min, range_max : float
        The valid interval ``[range_min, range_max)``, metres.

    Returns
    -------
    str
    """
    r = np.asarray(ranges, dtype=np.float64).ravel()
    with np.errstate(invalid="ignore"):
        parts = (
            ("NaN", int(np.count_nonzero(np.isnan(r)))),
            ("inf", int(np.count_nonzero(np.isinf(r)))),
            (f"below range_min {range_min:g} m", int(np.count_nonzero(np.isfinite(r) & (r < range_min)))),
            (f"at or beyond range_max {range_max:g} m", int(np.count_nonzero(np.isfinite(r) & (r >= range_max)))),
        )
    counts = ", ".join(f"{k} {name}" for name, k in parts if k)
    return (
        f"of its {r.size} ranges, {counts or 'none'} are invalid; expected finite ranges in "
        f"[range_min {range_min:g}, range_max {range_max:g}) m"
    )


def no_point_reason(points: np.ndarray, range_min: float | None, range_max: float | None) -> str:
    """Why :func:`filter_points` kept none of ``points``, for messages: ``of its 181
    points, 181 are not finite and 0 outside the dataset's range limits [None, None) m``.

    Parameters
    ----------
    points : (N, 3) float ndarray
        The points of one scan, metres.
    range_min, range_max : float or None
        The dataset's range limits given to :func:`filter_points` (None: none).

    Returns
    -------
    str
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    n_finite = int(np.count_nonzero(np.isfinite(p).all(axis=1)))
    return (
        f"of its {len(p)} points, {len(p) - n_finite} are not finite and {n_finite} outside the dataset's "
        f"range limits [{range_min}, {range_max}) m"
    )


class FrameError(InputError):
    """One scan frame that cannot be used; a reader skips and counts it (:class:`ScanLosses`).

    Attributes
    ----------
    where : str
        The frame: the file, the topic, the message index and its stamp (a bag:
        :func:`floorscan.ingest.ros_messages.message_label`), or ``file:line``.
    what : str
        What is wrong, naming the field and what was expected.
    loss : str
        ``"bad_frame"`` (broken geometry, cannot be decoded) or ``"no_points"`` (no valid
        return).
    """

    def __init__(self, where: str, what: str, loss: str = "bad_frame"):
        super().__init__(f"{where}: {what}")
        self.where, self.what, self.loss = where, what, loss


def ordinal_ranges(ordinals: list[int]) -> str:
    """Sorted ordinals as ranges: ``[3, 17, 18, 19]`` -> ``"3,17-19"``.

    Parameters
    ----------
    ordinals : list of int
        Any order; duplicates count once.

    Returns
    -------
    str
        ``""`` for none.
    """
    out: list[str] = []
    xs = sorted(set(int(v) for v in ordinals))
    i = 0
    while i < len(xs):
        j = i
        while j + 1 < len(xs) and xs[j + 1] == xs[j] + 1:
            j += 1
        out.append(str(xs[i]) if i == j else f"{xs[i]}-{xs[j]}")
        i = j + 1
    return ",".join(out)


def parse_ordinal_ranges(text: str) -> list[int]:
    """The ordinals of :func:`ordinal_ranges`' text, sorted: ``"3,17-19"`` -> ``[3, 17, 18, 19]``; ``""`` -> ``[]``.

    Parameters
    ----------
    text : str

    Returns
    -------
    list of int
        Sorted, unique.

    Raises
    ------
    ValueError
        A part that is not ``a`` or ``a-b`` with ``0 <= a <= b`` (decimal integers).
    """
    out: set[int] = set()
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        a, sep, b = part.partition("-")
        if not a.strip().isdigit() or (sep and not b.strip().isdigit()):
            raise ValueError(f"{part!r} is not an ordinal or a range of ordinals (e.g. 3 or 17-19)")
        lo, hi = int(a), int(b) if sep else int(a)
        if hi < lo:
            raise ValueError(f"{part!r} is a range that ends before it starts")
        out.update(range(lo, hi + 1))
    return sorted(out)


@dataclasses.dataclass
class ScanLosses:
    """The scan frames a reader saw and the ones it skipped.

    A frame is skipped with :meth:`skip` (a :class:`FrameError` says why). More than
    :data:`MAX_BAD_FRACTION` of the frames broken, or no usable frame at all, is an
    ``InputError`` (:meth:`check`); otherwise the losses go into
    :attr:`floorscan.ingest.recording.Recording.detected` (:meth:`detected`, keys of
    :data:`floorscan.ingest.recording.LOSS_KEYS`) and the notes (:meth:`notes`).

    Attributes
    ----------
    what : str
        The frames, for messages: ``scans on '/scan'``, ``laser lines``, ``PCD files``.
    n_read : int
        Frames seen.
    skipped : list of int
        Ordinals of the skipped frames (0-based, in reading order).
    """

    what: str
    n_read: int = 0
    n_bad: int = 0
    n_no_points: int = 0
    first_bad: FrameError | None = None
    first_no_points: FrameError | None = None
    skipped: list[int] = dataclasses.field(default_factory=list)

    #: More than this fraction of broken frames is not a recording with a few bad frames.
    MAX_BAD_FRACTION = 0.5

    def skip(self, ordinal: int, error: FrameError) -> None:
        """Count frame ``ordinal`` as skipped for ``error``.

        Parameters
        ----------
        ordinal : int
            The frame's ordinal, 0-based, in reading order.
        error : FrameError
            Why; its ``loss`` ``"no_points"`` counts as no valid return, any other as broken.
        """
        self.skipped.append(int(ordinal))
        if error.loss == "no_points":
            self.n_no_points += 1
            self.first_no_points = self.first_no_points or error
        else:
            self.n_bad += 1
            self.first_bad = self.first_bad or error

    def too_many_bad(self, n_total: int) -> bool:
        """Whether the broken frames are already more than :data:`MAX_BAD_FRACTION` of
        ``n_total`` frames.

        Parameters
        ----------
        n_total : int

        Returns
        -------
        bool
        """
        return self.n_bad > self.MAX_BAD_FRACTION * n_total

    def refusal(self, n_total: int) -> InputError:
        """The error for more than half of ``n_total`` frames broken (names the first).

        Parameters
        ----------
        n_total : int

        Returns
        -------
        InputError
            Returned, not raised.
        """
        e = self.first_bad
        return InputError(
            f"{e.where}: {e.what}. At least {self.n_bad} of the {n_total} {self.what} have broken geometry or "
            "cannot be decoded, more than half: the recording is refused (a few such frames are skipped and counted)"
        )

    def check(self, source: str) -> None:
        """Raise when the frames seen leave nothing to use.

        Parameters
        ----------
        source : str
            The recording, for messages.

        Raises
        ------
        InputError
            More than half of the frames broken (:meth:`refusal`), or every frame skipped
            (no valid return, or broken): names the first and what is wrong with it.
        """
        n = self.n_read
        if n and self.too_many_bad(n):
            raise self.refusal(n)
        if n and self.n_bad + self.n_no_points == n:
            if self.n_bad == 0:
                e = self.first_no_points
                raise InputError(
                    f"{e.where}: {e.what}. All {n} {self.what} of {source} have no valid return: "
                    "the recording has no usable data"
                )
            b, p = self.first_bad, self.first_no_points
            raise InputError(
                f"{b.where}: {b.what}. None of the {n} {self.what} of {source} is usable: {self.n_bad} have broken "
                f"geometry or cannot be decoded, {self.n_no_points} have no valid return (the first: {p.where}: {p.what})"
            )

    def detected(self) -> dict[str, str]:
        """The losses for ``Recording.detected``.

        Returns
        -------
        dict of str to str
            ``n_frames_read``, the non-zero ``lost_bad_frames`` / ``lost_no_points`` and
            ``skipped_frames`` (:func:`ordinal_ranges`).
        """
        out = {"n_frames_read": str(self.n_read)}
        if self.n_bad:
            out["lost_bad_frames"] = str(self.n_bad)
        if self.n_no_points:
            out["lost_no_points"] = str(self.n_no_points)
        if self.skipped:
            out["skipped_frames"] = ordinal_ranges(self.skipped)
        return out

    def notes(self) -> list[str]:
        """One line per kind of loss, naming the first frame skipped.

        Returns
        -------
        list of str
            Empty when nothing was skipped.
        """
        out = []
        if self.n_bad:
            e = self.first_bad
            out.append(
                f"skipped {self.n_bad} of {self.n_read} {self.what}: broken geometry or cannot be decoded "
                f"(lost_bad_frames); the first: {e.where}: {e.what}"
            )
        if self.n_no_points:
            e = self.first_no_points
            out.append(
                f"skipped {self.n_no_points} of {self.n_read} {self.what}: no valid return (lost_no_points); "
                f"the first: {e.where}: {e.what}"
            )
        return out

    def report(self, detected: dict, notes: list[str], source: str) -> None:
        """Check (:meth:`check`), then put the counts into ``detected`` and the notes into
        ``notes`` (both in place) and log each note as a warning.

        Parameters
        ----------
        detected : dict
            ``Recording.detected``; gets :meth:`detected`.
        notes : list of str
            The recording's notes; gets :meth:`notes`.
        source : str
            The recording, for messages.

        Raises
        ------
        InputError
            As :meth:`check`.
        """
        self.check(source)
        detected.update(self.detected())
        for line in self.notes():
            notes.append(line)
            log.warning("%s", line)


#: A scan's angles may span a full turn and this much more (radians: a tenth of a turn)
#: before they are taken to be degrees. A 360 degree scanner often reports a few beams
#: past the full turn (its first directions measured again); a span in degrees this
#: small (under 6.91) would be a field of view of under 7 degrees, which no floor
#: scanner has.
ANGLE_SPAN_TOLERANCE_RAD = 0.2 * math.pi


def angle_span_problem(span: float, what: str) -> str | None:
    """A field of view wider than a full turn (plus
    :data:`ANGLE_SPAN_TOLERANCE_RAD`): angles in degrees?

    Parameters
    ----------
    span : float
        Field of view, radians.
    what : str
        The field, for the message.

    Returns
    -------
    str or None
        The message, or None when the span is plausible.
    """
    if abs(span) > 2.0 * math.pi + ANGLE_SPAN_TOLERANCE_RAD:
        return (
            f"{what} is {span:g}; expected at most 2 pi = {2 * math.pi:.4f} rad "
            f"(angles in degrees? {span:g} degrees would be {math.radians(span):.4f} rad)"
        )
    return None

