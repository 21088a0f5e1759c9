"""The rooms of a floor plan on the front page (:mod:`floorscan.figures.report`): read
from the plan's GeoJSON (:func:`read_plan_rooms`: its ``room`` features,
:func:`floorscan.floorplan.geojson.floorplan_geojson`) and shown as a table of name,
kind and area with the total floor area (:func:`rooms_table_html`); the room scores
joined to the answer's table (:func:`with_room_scores`).
"""

from __future__ import annotations

import html
import os


def read_plan_rooms(path: str | os.PathLike) -> list[dict]:
    """The rooms of a floor plan's GeoJSON, in the file's order, as the scorer reads
    them (:func:`floorscan.score.rooms.read_rooms`).

    Parameters
    ----------
    path : path
        A plan's ``.geojson`` (floorplan stage).

    Returns
    -------
    list of dict
        One per feature of ``kind`` ``room``: ``room_id`` (int), ``name`` (str),
        ``kind`` (its ``room_kind``: ``room``, ``corridor`` or ``space``) and
        ``area_m2`` (float, square metres). Empty for a plan without rooms.

    Raises
    ------
    OSError, ValueError
        When the file cannot be read or is not JSON; floorscan.core.io.InputError
        when it is not a GeoJSON FeatureCollection.
    """
    from floorscan.score.rooms import read_rooms

    rooms, _ = read_rooms(path)
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
