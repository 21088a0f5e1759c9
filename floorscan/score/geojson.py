"""Wall segments from GeoJSON: the simulator's ground truth (``sim/walls.geojson``,
:func:`read_wall_faces`) and the faces and wall count of a floor plan's GeoJSON export
(:func:`read_floorplan`: a plan a person or another tool wrote; between stages a plan
passes as Parquet tables, :mod:`floorscan.core.plan_tables`, which give the same numbers).

(Multi)LineString features are selected by their property ``kind`` (``face``,
``observed_face``, ``axis``, ...) and cut into their straight pieces, ``(M, 4)``
segments in metres.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.segments import as_segments


def read_wall_faces(path, kind: str = "face") -> np.ndarray:
    """Ground-truth wall segments of ``kind`` from a ``walls.geojson`` (simulate stage).

    LineString and MultiLineString features whose property ``kind`` equals ``kind`` are
    split into their straight pieces.

    Parameters
    ----------
    path : path
    kind : str

    Returns
    -------
    (M, 4) float64 ndarray
        ``x0, y0, x1, y1`` in metres.

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a FeatureCollection or has no feature of ``kind``.
    """
    from floorscan.core.io import InputError

    seg = wall_faces(feature_collection(path), kind)
    if not len(seg):
        raise InputError(f"{path}: no LineString feature with property kind={kind!r}")
    return seg


def feature_collection(path) -> dict:
    """A GeoJSON file's FeatureCollection.

    Parameters
    ----------
    path : path

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    floorscan.core.io.InputError
        When the document's ``type`` is not ``FeatureCollection``.
    """
    import json

    from floorscan.core.io import InputError

    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    if doc.get("type") != "FeatureCollection":
        raise InputError(f"{path}: expected a GeoJSON FeatureCollection, got {doc.get('type')!r}")
    return doc


def wall_faces(doc: dict, kind: str) -> np.ndarray:
    """The straight pieces of the (Multi)LineString features of ``kind`` (a z is
    dropped; non-finite rows too, :func:`floorscan.core.segments.as_segments`).

    Parameters
    ----------
    doc : dict
        A FeatureCollection.
    kind : str
        The features' ``kind`` property.

    Returns
    -------
    (M, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres; (0, 4) when none.
    """
    lines: list = []
    for feat in doc.get("features", []):
        if (feat.get("properties") or {}).get("kind") != kind:
            continue
        geom = feat.get("geometry") or {}
        if geom.get("type") == "LineString":
            lines.append(geom["coordinates"])
        elif geom.get("type") == "MultiLineString":
            lines.extend(geom["coordinates"])
    # All vertices at once (x, y of each; a z is dropped), then the pieces between
    # consecutive vertices of a line.
    lines = [line for line in lines if len(line) >= 2]
    if not lines:
        return np.zeros((0, 4))
    xy = np.array([p[:2] for line in lines for p in line], dtype=np.float64).reshape(-1, 2)
    n = np.fromiter((len(line) for line in lines), dtype=np.int64, count=len(lines))
    end = np.cumsum(n)
    start = np.ones(len(xy), dtype=bool)
    start[end - 1] = False  # a line's last vertex starts no piece
    i = np.flatnonzero(start)
    return as_segments(np.column_stack([xy[i], xy[i + 1]]))


#: Kinds of the features that are parts of a wall (a door names the wall it is in).
_WALL_KINDS = ("axis", "footprint", "face", "wall", None)


def _wall_count(doc: dict) -> int:
    props = [feat.get("properties") or {} for feat in doc.get("features", [])]
    ids = {p["wall_id"] for p in props if "wall_id" in p and p.get("kind") in _WALL_KINDS}
    if ids:
        return len(ids)
    return sum(p.get("kind", "wall") in ("axis", "wall") for p in props)


def floorplan_wall_count(path) -> int:
    """Number of walls in a merged floor plan ``.geojson`` (floorplan stage).

    The floor plan has features of kind ``axis`` (centre line) and ``footprint``
    (polygon) per wall, sharing a ``wall_id``: the count is the number of distinct
    ``wall_id`` of those (a ``door`` names its wall too); without that property, the
    features of kind ``axis`` or ``wall`` (or without a kind).

    Parameters
    ----------
    path : path

    Returns
    -------
    int

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a GeoJSON FeatureCollection.
    """
    return _wall_count(feature_collection(path))


def floorplan_faces(path) -> np.ndarray:
    """The merged faces (``kind`` "face") of a floor plan ``.geojson``.

    Parameters
    ----------
    path : path

    Returns
    -------
    (F, 4) float64 ndarray
        Metres; empty when the plan has none (a plan without walls is valid).

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a GeoJSON FeatureCollection.
    """
    return wall_faces(feature_collection(path), "face")


def read_floorplan(path) -> tuple[np.ndarray, int]:
    """:func:`floorplan_faces` and :func:`floorplan_wall_count` of a floor plan
    ``.geojson``, from one read of the file.

    Parameters
    ----------
    path : path

    Returns
    -------
    faces : (F, 4) float64 ndarray
        Metres.
    n_walls : int

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a GeoJSON FeatureCollection.
    """
    doc = feature_collection(path)
    return wall_faces(doc, "face"), _wall_count(doc)
