"""Number fields of the text formats: a CARMEN log, an ascii PCD, the locations CSV.

Every text reader reads a number the same way: :func:`parse_number` one field,
:func:`parse_numbers` many in one numpy call. Both read what Python's ``float`` reads
(``nan`` and ``inf`` included, for the caller to judge) except ``1_0``, and return None
for a field that is not a number, so the caller can name it in its message.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


def parse_number(text: str) -> float | None:
    """A number field of a text recording, or None when ``text`` is not a number.

    Python's ``float`` (``nan`` and ``inf`` included, for the caller to judge), except
    for ``1_0``: Python reads 10, the C readers of these formats (``strtod``) read 1.
    """
    if "_" in text:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def parse_numbers(texts: Sequence[str]) -> np.ndarray | None:
    """:func:`parse_number` of every text as a (N,) float64 ndarray, parsed by numpy in
    one call (it reads what ``float`` reads); None when one of them is not a number
    (the caller finds which, one by one, for its message)."""
    if "_" in "".join(texts):
        return None
    try:
        return np.array(texts, dtype=np.float64)
    except ValueError:
        return None
