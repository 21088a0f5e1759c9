"""The rooms of a floor plan on the front page (:mod:`floorscan.figures.report`): read
from the plan's Parquet tables (:func:`read_plan_rooms`: the plan folder the score
stage reads too, :mod:`floorscan.core.plan_tables`) and shown as a table of name,
kind and area with the total floor area (:func:`rooms_table_html`); the room scores
joined to the answer's table (:func:`with_room_scores`).
"""

from __future__ import annotations

import html
import os


def read_plan_rooms(folder: str | os.PathLike) -> list[dict]:
    """The rooms of a plan folder, in the tables' order (the GeoJSON export's), as the
    scorer reads them (:func:`floorscan.score.rooms.read_plan_folder_rooms`: a room
    without a polygon, which the export skips, is skipped).

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
    from floorscan.score.rooms import read_plan_folder_rooms

    rooms, _ = read_plan_folder_rooms(folder)
    return rooms[["room_id", "name", "kind", "area_m2"]].to_dict("records")


def rooms_table_html(rooms: list[dict] | None) -> list[str]:
    """The front page's rooms: a heading and a table of name, kind and area (m², one
    decimal), then the total floor area (the rooms' areas summed, m²); nothing for a
    plan without rooms.

    Parameters
    ----------
    rooms : list of dict or None
        :func:`read_plan_rooms`: ``name``, ``kind``, ``area_m2``.

    Returns
    -------
    list of str
        HTML pieces; empty for a plan without rooms.
    """
    if not rooms:
        return []
    esc = html.escape
    rows = "".join(
        f'<tr><td>{esc(r["name"])}</td><td>{esc(r["kind"])}</td><td class="num">{r["area_m2"]:.1f}</td></tr>'
        for r in rooms
    )
    total = sum(r["area_m2"] for r in rooms)
    return [
        f"<h3>Rooms ({len(rooms)})</h3>",
        '<table class="rooms"><thead><tr><th>room</th><th>kind</th><th>area m²</th></tr></thead>'
        f'<tbody>{rows}</tbody><tfoot><tr><th colspan="2">floor area</th><td class="num">{total:.1f}</td></tr>'
        "</tfoot></table>",
    ]


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
