"""How many scans an ordering needs: the coverage targets of thesis Fig. 5.6.

- :func:`k_for_fraction`: the fewest scans reaching a fraction of the ordering's
  final covered area;
- :func:`first_k`: the first scans of an ordering, by count or by fraction;
- :func:`summarize`: per ordering the k at 90/95/99 % (:data:`TARGET_FRACTIONS`), the
  table ``orderings/summary.parquet`` (:data:`SUMMARY`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import pandas as pd
import pyarrow as pa

#: Coverage fractions of the summary columns ``k_90, k_95, k_99``.
TARGET_FRACTIONS = (0.90, 0.95, 0.99)

#: ``orderings/summary.parquet``: per ordering the number of scans reaching 90/95/99 %
#: of its final covered area. No timing: the same input gives the same file (the time
#: to compute each ordering is in the select stage's log).
SUMMARY = pa.schema(
    [
        ("ordering", pa.string()),
        ("n_scans", pa.int32()),
        ("n_zero_area", pa.int32()),
        ("final_area_m2", pa.float64()),
        ("k_90", pa.int32()),
        ("k_95", pa.int32()),
        ("k_99", pa.int32()),
    ]
)


def k_for_fraction(ordering: pd.DataFrame, fraction: float) -> int:
    """Smallest number of scans whose cumulative covered area reaches ``fraction`` of
    the ordering's final covered area (thesis Fig. 5.6).

    Parameters
    ----------
    ordering : pandas.DataFrame
        ``covered_area_m2`` (cumulative, square metres) in rank order.
    fraction : float
        In (0, 1].

    Returns
    -------
    int
        0 for an empty ordering or zero final area.

    Raises
    ------
    ValueError
        Unless ``0 < fraction <= 1``.
    """
    if not 0 < fraction <= 1:
        raise ValueError(f"fraction must be in (0, 1], got {fraction}")
    cov = ordering["covered_area_m2"].to_numpy(dtype=np.float64)
    if len(cov) == 0 or cov[-1] <= 0:
        return 0
    # cumulative area is non-decreasing; tiny slack for float rounding of the sum
    target = fraction * cov[-1] * (1 - 1e-12)
    return int(np.argmax(cov >= target)) + 1


def first_k(ordering: pd.DataFrame, count: int | None = None, fraction: float | None = None) -> np.ndarray:
    """The first scans of an ordering, by count or by coverage fraction.

    Parameters
    ----------
    ordering : DataFrame
        ``rank, scan_id, covered_area_m2`` (an ``orderings/*.parquet``).
    count : int, optional
        Take this many scans (all when larger than the ordering).
    fraction : float, optional
        Take the fewest scans reaching this fraction of the final covered area.

    Returns
    -------
    (k,) int64 scan ids, in rank order.

    Raises
    ------
    ValueError
        Unless exactly one of ``count`` / ``fraction`` is given, or ``count < 0``.
    """
    if (count is None) == (fraction is None):
        raise ValueError("give exactly one of count or fraction")
    o = ordering.sort_values("rank", kind="stable")
    if count is not None:
        if count < 0:
            raise ValueError(f"count must be >= 0, got {count}")
        k = int(count)
    else:
        k = k_for_fraction(o, fraction)
    return o["scan_id"].to_numpy(dtype=np.int64)[:k]


def summarize(orderings: Mapping[str, pd.DataFrame], seconds: Mapping[str, float] | None = None,
              zero_area: int = 0) -> pd.DataFrame:
    """Per ordering the k reaching 90/95/99 % of its final covered area (thesis
    Fig. 5.6).

    Parameters
    ----------
    orderings : mapping of str to pandas.DataFrame
        Ordering name -> its table (``covered_area_m2`` in rank order).
    seconds : mapping of str to float, optional
        Time to compute each ordering, seconds.
    zero_area : int
        Scans without covered area, the same for every row.

    Returns
    -------
    pandas.DataFrame
        The :data:`SUMMARY` columns and ``seconds`` (NaN when not given), for the log:
        ``write_table(summary, path, schema=SUMMARY)`` leaves it out of the file.
    """
    rows = []
    for name, o in orderings.items():
        cov = o["covered_area_m2"].to_numpy()
        rows.append(
            {
                "ordering": name,
                "n_scans": len(o),
                "n_zero_area": zero_area,
                "final_area_m2": float(cov[-1]) if len(cov) else 0.0,
                **{f"k_{round(f * 100)}": k_for_fraction(o, f) for f in TARGET_FRACTIONS},
                "seconds": float((seconds or {}).get(name, np.nan)),
            }
        )
    return pd.DataFrame(rows, columns=[*SUMMARY.names, "seconds"])
