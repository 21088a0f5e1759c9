"""Units of a recording's ranges and headings: metres and radians, else one error naming the field.

A recording written in millimetres or centimetres, or with its headings in degrees, is
made of well-formed numbers: nothing in a single line or file is wrong, and the stages
after ingest fail far from the cause (registration "below its fitness thresholds", an
occupancy grid of 26 GiB) or, worse, run to a wrong plan. Ingest looks at the whole
recording instead:

- ranges (:func:`range_units_problem`): the median return over the recording's scans
  (:class:`MedianReturn`, each scan's median horizontal distance from the scanner, then
  the median over scans) beyond :data:`MAX_MEDIAN_RANGE_M` is not metres; from its size
  the message says millimetres or centimetres, with the median in each. The ingest
  writer (:func:`floorscan.ingest.writer.write_recording`) checks every format's scans;
  the CARMEN reader checks a log's readings before its no-return limit
  (:mod:`floorscan.ingest.carmen_ranges`) would drop every reading in millimetres.
- headings (:func:`yaw_units_problem`): a CARMEN ``theta`` or a PCD folder's ``yaw``
  (written numbers; a bag's headings are quaternions) is not radians when it lies beyond
  a full turn (:data:`MAX_YAW_RAD`) and is not an unwrapped heading (one starts within a
  turn and never steps by more than half a turn between poses), or when a tenth of its
  steps between poses under :data:`MAX_STEP_DT_S` apart turn faster than any robot does
  (:data:`MAX_TURN_RATE_RAD_S`; :data:`MIN_FAST_SHARE`).

The readers prefix the message with the file and the field (``locations.csv: column
'yaw' ...``, ``log: the theta of the FLASER lines ...``) and raise
:class:`~floorscan.core.io.InputError`.
"""

from __future__ import annotations

import math

import numpy as np

#: No LIDAR's median return over a whole recording is beyond this, metres. Half of a
#: scan's returns land on the walls, floor and things around the scanner: the shared
#: recordings' medians are 1.8 to 8.0 m (the largest acapulco's, a 100 m x 45 m hall;
#: measured, see benchmarks/README.md), and even a long-range 3D scanner outdoors (Velodyne HDL-64,
#: Ouster OS2: 120-240 m at most) has most of its beams on the ground and the street
#: near it. In centimetres a median of 0.5 m is 50 "m" already, in millimetres 0.05 m.
MAX_MEDIAN_RANGE_M = 50.0
#: A median beyond :data:`MAX_MEDIAN_RANGE_M` is called millimetres from this value on,
#: centimetres below it: 1 m in millimetres, 10 m in centimetres (a median return of 1 to
#: 10 m covers rooms to halls, so the geometric middle of the two readings decides).
MILLIMETRES_FROM = 1000.0
#: Scans after which the writer checks the median return once before the end (a long
#: recording in millimetres is refused without reading all of it).
EARLY_CHECK_SCANS = 200
#: Points per scan the median return looks at (every k-th point of a larger scan).
MEDIAN_SAMPLE_POINTS = 1024

#: A heading in radians lies within a turn: [-pi, pi] or [0, 2 pi), plus a tenth of a
#: turn for rounding and conventions (the same tolerance as a scan's angular span,
#: :data:`floorscan.ingest.points.ANGLE_SPAN_TOLERANCE_RAD`). An unwrapped heading may
#: go beyond it, by turning; one that starts beyond it, or steps by more than half a
#: turn between poses (a wrap: in degrees, from 180 to -180), is not unwrapped radians.
MAX_YAW_RAD = 2.2 * math.pi
#: No robot or person carrying a scanner turns faster than this, radians per second:
#: two turns a second, over twice the fastest mobile base's limit (Pioneer 3-DX 300
#: deg/s, Kobuki 180 deg/s, iRobot Create 3 about 110 deg/s). A heading in degrees read
#: as radians turns at its degrees per second in "radians" per second: any turn faster
#: than 12.6 deg/s shows.
MAX_TURN_RATE_RAD_S = 4.0 * math.pi
#: A step faster than :data:`MAX_TURN_RATE_RAD_S` is counted only between poses at most
#: this far apart, seconds: a step is measured wrapped into [-pi, pi), so over a longer
#: interval every step is a possible turn.
MAX_STEP_DT_S = math.pi / MAX_TURN_RATE_RAD_S
#: ... and at least this far apart, seconds: the fastest scanners sweep at 100 Hz, so
#: poses closer in time than a millisecond are stamps that do not measure time (made up,
#: or a simulator's counter), not a turn rate.
MIN_STEP_DT_S = 1e-3
#: Steps faster than any robot turns make a heading degrees when they are at least this
#: share of all the steps between poses. A few are stamps, not turns: the shared intel log
#: has 8 of 909 (lines written late, 0.01 s apart after sorting), belgioioso 2 of 394 and
#: orebro 1 of 236 (stamps made up at 0.1 s for lines logged farther apart); a localizer
#: that relocalises turns its heading at a stroke once or twice. A heading in degrees turns
#: "faster" at every step of every turn.
MIN_FAST_SHARE = 0.1
#: ... and at least this many.
MIN_FAST_STEPS = 3


class MedianReturn:
    """The median return of a recording's scans, accumulated scan by scan.

    :meth:`add` takes a scan's points (scanner frame) and keeps that scan's median
    horizontal distance (of at most :data:`MEDIAN_SAMPLE_POINTS` points); :attr:`value`
    is the median over the scans added.
    """

    def __init__(self) -> None:
        self.medians: list[float] = []

    def add(self, points: np.ndarray) -> None:
        """Add one scan.

        Parameters
        ----------
        points : (N, >=2) float ndarray
            The scan's valid returns in the scanner frame, metres; empty adds nothing.
        """
        p = np.asarray(points)
        if not len(p):
            return
        p = p[:: max(1, len(p) // MEDIAN_SAMPLE_POINTS)]
        self.add_distances(np.hypot(p[:, 0].astype(np.float64), p[:, 1].astype(np.float64)))

    def add_distances(self, distances: np.ndarray) -> None:
        """Add one scan given as its returns' horizontal distances (a planar scan's
        ranges), metres; the non-finite ones are left out, none adds nothing."""
        d = np.asarray(distances, dtype=np.float64)
        d = d[np.isfinite(d)]
        if len(d):
            self.medians.append(float(np.median(d)))

    @property
    def n_scans(self) -> int:
        return len(self.medians)

    @property
    def value(self) -> float:
        """The median over the scans of each scan's median return, metres (NaN: none)."""
        return float(np.median(self.medians)) if self.medians else math.nan


def range_units_problem(median_m: float, n_scans: int) -> str | None:
    """What the median return says of the ranges' unit, for a message.

    Parameters
    ----------
    median_m : float
        The recording's median return as read, "metres" (:class:`MedianReturn`).
    n_scans : int
        The scans it was taken over (for the message).

    Returns
    -------
    str or None
        ``look like millimetres (median return 1800 m over 30 scans: 1.80 m in
        millimetres, 18.0 m in centimetres; expected metres ...)``; None when the median
        is at most :data:`MAX_MEDIAN_RANGE_M` (or NaN).
    """
    if not median_m > MAX_MEDIAN_RANGE_M:
        return None
    unit = "millimetres" if median_m >= MILLIMETRES_FROM else "centimetres"
    return (
        f"look like {unit} (median return {median_m:.6g} m over {n_scans} scans: {median_m / 1000:.3g} m in "
        f"millimetres, {median_m / 100:.3g} m in centimetres); expected metres: no LIDAR's median return over a "
        f"recording is beyond {MAX_MEDIAN_RANGE_M:g} m. Convert the recording to metres"
    )


def yaw_units_problem(t_ns: np.ndarray, yaw: np.ndarray) -> str | None:
    """Whether a series of headings is not radians (see the module docstring), for a message.

    Parameters
    ----------
    t_ns : (N,) int ndarray
        Stamps of the poses, nanoseconds, in time order.
    yaw : (N,) float ndarray
        The headings as read, "radians".

    Returns
    -------
    str or None
        ``looks like degrees (values up to 179.5, steps of 10 between poses 0.1 s apart;
        expected radians)``; None when the headings can be radians.
    """
    y = np.asarray(yaw, dtype=np.float64)
    t = np.asarray(t_ns, dtype=np.int64)
    if len(y) == 0:
        return None
    top = float(np.abs(y).max())
    raw = np.diff(y)
    dt = np.diff(t) * 1e-9
    step = np.abs((raw + math.pi) % (2.0 * math.pi) - math.pi)  # wrapped into [0, pi]
    rate = step / np.where(dt > 0, dt, np.inf)
    fast = (dt >= MIN_STEP_DT_S) & (dt <= MAX_STEP_DT_S) & (rate > MAX_TURN_RATE_RAD_S)
    n_fast = int(np.count_nonzero(fast))
    jumps = np.flatnonzero(np.abs(raw) > math.pi)
    # beyond a turn, and not unwrapped: it starts beyond a turn, or jumps by half a turn or more
    beyond = top > MAX_YAW_RAD and (abs(float(y[0])) > MAX_YAW_RAD or jumps.size > 0)
    too_fast = n_fast >= max(MIN_FAST_STEPS, MIN_FAST_SHARE * len(raw))
    if not (beyond or too_fast):
        return None
    unit = "degrees" if top <= 1.1 * 360.0 else "neither radians nor degrees"
    parts = [f"values up to {top:.4g}"]
    if abs(float(y[0])) > MAX_YAW_RAD:
        parts.append(f"the first {float(y[0]):.4g}")
    if too_fast:
        parts.append(
            f"steps of {float(np.median(np.abs(raw[fast]))):.3g} between poses {float(np.median(dt[fast])):.3g} s apart "
            f"at {n_fast} of {len(raw)} steps, a turn of {float(np.median(rate[fast])):.3g} rad/s if radians"
        )
    elif jumps.size:
        k = int(jumps[np.argmax(np.abs(raw[jumps]))])
        parts.append(f"a step of {float(raw[k]):.4g} between poses {k} and {k + 1}, {float(dt[k]):.3g} s apart")
    return (
        f"looks like {unit} ({', '.join(parts)}); expected radians: a heading within a turn ([-pi, pi] or "
        f"[0, 2 pi)), or unwrapped from there, turning at most {MAX_TURN_RATE_RAD_S:.3g} rad/s (two turns a "
        "second). Convert the headings to radians"
    )
