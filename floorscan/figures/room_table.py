"""The rooms of a floor plan on the front page (:mod:`floorscan.figures.report`): read
from the plan's Parquet tables (:func:`read_plan_rooms`: the plan folder the score
stage reads too, :mod:`floorscan.core.plan_tables`), which the front pages' template
shows as a table of name, kind and area with the total floor area
(``templates/_front_base.html.j2``, macro ``rooms_table``); the room scores joined to
the answer's table (:func:`with_room_scores`).
"""

from __future__ import annotations

import os


def read_plan_rooms(folder: str | os.PathLike) -> list[dict]:
    """The rooms of a plan folder, in the tables' order (the GeoJSON export's), as the
    scorer reads them (:func:`floorscan.core.plan_tables.plan_rooms`: a room without a
    polygon, which the export skips, is skipped).

    Parameters
    ----------
    folder : path
        A plan folder, e.g. ``results/<dataset>/plan_tables``.

    Returns
    -------
    list of dict
        One per room: ``room_id`` (int), ``name`` (str), ``kind`` (``room``,
        ``corridor`` or ``space``) and ``area_m2`` (float, square metres). Empty for a
        plan without rooms.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    from floorscan.core.plan_tables import plan_rooms

    rooms, _ = plan_rooms(folder)
    return [{k: room[k] for k in ("room_id", "name", "kind", "area_m2")} for room in rooms]


def with_room_scores(answer, room_scores):
    """The answer's table (``evaluation/answer_scores.csv``; a path or None) with the
    columns of the room scores (``evaluation/room_scores.csv``,
    :mod:`floorscan.score.rooms`) joined by plan, so that "How good the plan is" shows
    the rooms and doors against the truth; the answer as it was when either is None.

    Parameters
    ----------
    answer : path or None
    room_scores : path or None

    Returns
    -------
    pandas.DataFrame, path or None
    """
    if answer is None or room_scores is None:
        return answer
    import pandas as pd

    table = pd.read_csv(answer)
    rooms = pd.read_csv(room_scores)
    cols = ["plan"] + [c for c in rooms.columns if c not in table.columns]
    return table.merge(rooms[cols], on="plan", how="left")
