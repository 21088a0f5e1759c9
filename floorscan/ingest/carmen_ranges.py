"""The no-return range of a CARMEN log: the range at or beyond which readings are dropped.

FLASER carries no range limits: a scanner logs "no return" as a fixed
value at the top of its range (SICK LMS 81.91 m, with error codes from 81.83 m; others
32.767 m, the largest signed 16-bit millimetre count, with codes a few millimetres
below; a log clipped to a round limit), repeated in many scans, while the farthest
genuine wall of a log is read a few times at most. Unless ``ingest.carmen_max_range_m``
is set, the no-return value is detected (:func:`no_return_range`): the log's largest
reading, when that exact value carries at least ``NO_RETURN_MIN_FRACTION`` of all
readings (and at least ``NO_RETURN_MIN_COUNT``), and some reading is not that value;
readings within ``NO_RETURN_BAND_M`` below it are the same code family and are dropped
with it. Without such a value (a log whose every reading is one value is read as
returns: dropping them all would leave nothing) the SICK LMS limit
``FALLBACK_MAX_RANGE_M`` applies. Returns at or beyond the limit, or at
or below zero, are dropped and counted.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np


#: A log's largest reading is its no-return value when that exact value carries at
#: least this fraction of all its readings ...
NO_RETURN_MIN_FRACTION = 0.001
#: ... and at least this many readings.
NO_RETURN_MIN_COUNT = 10
#: Readings this close below the no-return value (metres) are dropped with it: a
#: scanner's no-return and error codes sit together at the top of its range.
NO_RETURN_BAND_M = 0.1
#: Drop limit of a log without a frequent largest reading: SICK LMS report no return
#: at 81.91 m or 80 m; no indoor wall is that far.
FALLBACK_MAX_RANGE_M = 80.0


@dataclasses.dataclass(frozen=True)
class NoReturn:
    """The range limit of a CARMEN log and how it was chosen.

    Attributes
    ----------
    max_range_m : float
        Returns at or beyond this are dropped, metres.
    how : str
        ``"detected"``, ``"fallback"`` (no frequent largest reading) or ``"configured"``.
    value_m : float
        The log's largest finite reading, metres (NaN for an empty log).
    count : int
        Readings exactly at ``value_m``.
    fraction : float
        ``count`` over all readings.
    n_dropped : int
        Readings at or beyond ``max_range_m``.
    """

    max_range_m: float
    how: str
    value_m: float
    count: int
    fraction: float
    n_dropped: int

    def note(self) -> str:
        """One line for the stage log: the limit and why.

        Returns
        -------
        str
        """
        head = f"largest reading {self.value_m:g} m carries {self.count} of the readings ({100 * self.fraction:.2f} %)"
        if self.how == "configured":
            why = f"ingest.carmen_max_range_m {self.max_range_m:g} m (configured; {head})"
        elif self.how == "detected":
            why = (
                f"no-return value detected: {head}, at least {100 * NO_RETURN_MIN_FRACTION:g} % and "
                f"{NO_RETURN_MIN_COUNT}; readings from {self.max_range_m:g} m ({NO_RETURN_BAND_M:g} m below it) "
                "on are no return"
            )
        else:
            why = (
                f"no frequent largest reading ({head}, under {100 * NO_RETURN_MIN_FRACTION:g} % or "
                f"{NO_RETURN_MIN_COUNT}): the SICK LMS limit {self.max_range_m:g} m applies"
            )
        return f"max range {self.max_range_m:g} m: {why}; {self.n_dropped} readings dropped at or beyond it"


def no_return_range(ranges: Sequence[np.ndarray] | np.ndarray, max_range_m: float | None = None) -> NoReturn:
    """The range at or beyond which a log's readings are "no return".

    Parameters
    ----------
    ranges : sequence of (B,) float ndarray, or (R,) float ndarray
        The range readings of the log's laser lines, metres.
    max_range_m : float, optional
        A limit set by the user (``ingest.carmen_max_range_m``): used as it is.

    Returns
    -------
    NoReturn
        The limit: ``max_range_m`` when given; else the largest reading minus
        ``NO_RETURN_BAND_M`` when that exact value carries at least
        ``NO_RETURN_MIN_FRACTION`` of the readings and ``NO_RETURN_MIN_COUNT`` of them,
        but not every finite one; else ``FALLBACK_MAX_RANGE_M``.
    """
    r = np.concatenate([np.asarray(a, dtype=np.float64).ravel() for a in ranges]) if len(ranges) else np.zeros(0)
    finite = r[np.isfinite(r)]
    total = max(int(r.size), 1)
    value = float(finite.max()) if finite.size else math.nan
    count = int(np.count_nonzero(finite == value)) if finite.size else 0
    fraction = count / total
    if max_range_m is not None:
        limit, how = float(max_range_m), "configured"
    elif count >= NO_RETURN_MIN_COUNT and fraction >= NO_RETURN_MIN_FRACTION and count < finite.size:
        limit, how = round(value - NO_RETURN_BAND_M, 6), "detected"
    else:
        limit, how = FALLBACK_MAX_RANGE_M, "fallback"
    return NoReturn(limit, how, value, count, fraction, int(np.count_nonzero(finite >= limit)))
