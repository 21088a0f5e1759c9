"""The rooms and doors of a floor plan scored against true ones, as room segmentation
is scored (Bormann et al., "Room segmentation: survey, implementation, and analysis",
ICRA 2016): plan rooms matched one-to-one to true rooms by their overlap.

- :func:`read_plan_folder_rooms`: the rooms and doors of a plan folder, the Parquet
  tables a plan passes between stages in (:mod:`floorscan.core.plan_tables`; the
  floorplan stage's ``plan_tables/`` and ``evaluation/plans/all_scans_map/``).
- :func:`read_rooms`: the same of a GeoJSON: the ``room`` (Polygon) and ``door``
  (LineString) features of the simulator's ``walls.geojson``
  (:func:`floorscan.sim.ground_truth.true_rooms`, :func:`~floorscan.sim.ground_truth.true_doors`)
  or of a floor plan's GeoJSON export.
- :func:`room_seen_share`: the share of a true room the recording saw (within the free
  space of the reference map, :func:`floorscan.score.drawn.seen_by_recording`); only
  rooms seen for at least :data:`SEEN_SHARE` of their area count: no method finds a
  room it never saw (a drawing may hold rooms the robot never entered).
- :func:`~floorscan.score.segmentation.segmentation_scores` (the one room scorer, in
  :mod:`floorscan.score.segmentation`): from the intersection areas of true and plan
  rooms, the one-to-one matching of the pairs whose IoU is at least
  :data:`~floorscan.score.segmentation.ROOM_IOU` (:func:`match_rooms`): room precision
  (matched / plan rooms), recall (matched / counted true rooms) and the mean IoU of the
  matched pairs, a plan room lying for at least
  :data:`~floorscan.score.segmentation.LEFT_OUT_SHARE` of its area in true rooms that
  do not count left out of precision; and Bormann's per-room mean and pooled
  precision and recall on the same rooms.
- :func:`match_doors`: each counted true door (not leading outside, between two counted
  rooms) matched one-to-one to a plan door centre within :data:`DOOR_TOLERANCE_M`
  (least summed distance): door recall, precision and mean centre error.
- :func:`score_room_plans`: every plan against the simulator's rooms and doors (IoU on
  shapely polygons), one row per plan, :data:`ROOM_SCORE_COLUMNS`. Rooms drawn by
  people are scored on the drawing's pixels by :mod:`floorscan.score.drawn_rooms`.

A new room metric is a key of :func:`~floorscan.score.segmentation.segmentation_scores`,
a new door metric one of :func:`match_doors`, and a name in :data:`ROOM_SCORE_COLUMNS`.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

# match_rooms and its constants are read from here too
from floorscan.score.segmentation import (  # noqa: F401
    LEFT_OUT_SHARE, MIN_REGION_PX, ROOM_ERROR_KEYS, ROOM_IOU, match_rooms, segmentation_scores,
)

#: A true room counts when the recording saw at least this share of its area.
SEEN_SHARE = 0.5
#: A plan door matches a true door when their centres are at most this far apart, m.
DOOR_TOLERANCE_M = 0.2
#: A point is seen when it lies this close to the reference map's free space, metres
#: (at least one cell: the cells of a room along its walls are the walls' returns).
SEEN_WITHIN_M = 0.05

#: Columns of ``room_scores.csv``: ``truth`` is ``ground_truth`` (the simulator's),
#: ``drawn`` (a segmentation drawn by people) or ``none``; scores without a truth, and
#: door scores without true doors, are NaN. ``seg_*`` are Bormann's per-room mean and
#: pooled precision and recall (:func:`floorscan.score.segmentation.bormann_scores`);
#: :data:`~floorscan.score.segmentation.ROOM_ERROR_KEYS` why the rooms left unmatched
#: are (:func:`floorscan.score.segmentation.room_errors`).
ROOM_SCORE_COLUMNS = [
    "plan", "truth", "room_precision", "room_recall", "room_mean_iou", "n_true_rooms", "n_true_rooms_all",
    "n_plan_rooms", "n_plan_rooms_scored", "n_matched_rooms", *ROOM_ERROR_KEYS, "door_recall", "door_precision",
    "door_centre_error_m", "n_true_doors", "n_plan_doors", "n_plan_doors_scored", "n_matched_doors",
    "seg_precision_mean", "seg_precision_pooled", "seg_recall_mean", "seg_recall_pooled",
]  # fmt: skip


#: Columns of the rooms and doors of :func:`read_rooms` and :func:`read_plan_folder_rooms`.
ROOM_COLUMNS = ["room_id", "name", "kind", "area_m2", "perimeter_m", "polygon"]
DOOR_COLUMNS = ["door_id", "x0", "y0", "x1", "y1", "x", "y", "width_m", "wall_id", "room_a", "room_b", "exterior"]


def _rooms_frames(rooms: list[dict], doors: list[dict]) -> tuple[pd.DataFrame, pd.DataFrame]:
    floats = {c: np.float64 for c in ("x0", "y0", "x1", "y1", "x", "y", "width_m")}
    return (pd.DataFrame(rooms, columns=ROOM_COLUMNS).astype({"area_m2": np.float64, "perimeter_m": np.float64}),
            pd.DataFrame(doors, columns=DOOR_COLUMNS).astype(floats | {"exterior": bool}))  # fmt: skip


def _scored_polygon(poly):
    """A room polygon as scored: a ring drawn by another tool, or rounded, made valid."""
    import shapely

    return poly if poly.is_valid else shapely.make_valid(poly)


def read_plan_folder_rooms(folder) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rooms and doors of a plan folder (:func:`floorscan.core.plan_tables.plan_rooms`),
    as :func:`read_rooms` reads them from the plan's GeoJSON export: the same rows, in
    the same order, with the same numbers.

    A room without a polygon (missing or empty), which the export skips, is skipped; a
    polygon that is not valid (rounded to 10 micrometres) is made valid. The tables hold
    no ``exterior`` flag, nor does the export: False.

    Parameters
    ----------
    folder : path
        A plan folder, e.g. ``results/<dataset>/plan_tables``.

    Returns
    -------
    rooms : pandas.DataFrame
        ``room_id``, ``name``, ``kind``, ``area_m2`` (m2), ``perimeter_m`` (metres),
        ``polygon`` (shapely, map metres).
    doors : pandas.DataFrame
        ``door_id``, ``x0, y0, x1, y1`` (the opening's ends, map metres), ``x, y`` (its
        centre), ``width_m``, ``wall_id``, ``room_a``, ``room_b``, ``exterior`` (False).

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    from floorscan.core.plan_tables import plan_rooms

    rooms, d = plan_rooms(folder)
    rooms = [{**room, "polygon": _scored_polygon(room["polygon"])} for room in rooms]
    doors = [
        {"door_id": int(door_id), "x0": x0, "y0": y0, "x1": x1, "y1": y1, "x": (x0 + x1) / 2, "y": (y0 + y1) / 2,
         "width_m": float(width), "wall_id": int(wall_id), "room_a": int(a), "room_b": int(b), "exterior": False}
        for door_id, x0, y0, x1, y1, width, wall_id, a, b in zip(
            *(d[c].tolist() for c in ("door_id", "x0", "y0", "x1", "y1", "width_m", "wall_id", "room_a", "room_b"))
        )
    ]  # fmt: skip
    return _rooms_frames(rooms, doors)


def read_rooms(path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rooms and doors of a floor plan's (or the ground truth's) GeoJSON.

    Features are selected by their property ``kind``: ``room`` (Polygon or
    MultiPolygon, map metres; ``room_id``, ``name``, ``room_kind``, ``area_m2``,
    ``perimeter_m``) and ``door`` (LineString: the opening in its wall's line;
    ``door_id``, ``width_m``, ``wall_id``, ``room_a``, ``room_b``, ``exterior``).

    Parameters
    ----------
    path : path

    Returns
    -------
    rooms : pandas.DataFrame
        ``room_id``, ``name``, ``kind``, ``area_m2``, ``perimeter_m`` (the polygon's
        area and length when the feature has none) and ``polygon`` (shapely).
    doors : pandas.DataFrame
        ``door_id``, ``x0, y0, x1, y1`` (the segment's ends), ``x, y`` (its centre),
        ``width_m`` (metres), ``wall_id``, ``room_a``, ``room_b``, ``exterior`` (bool,
        False when absent).

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a GeoJSON FeatureCollection.
    """
    import shapely.geometry

    from floorscan.score.geojson import feature_collection

    rooms, doors = [], []
    for feat in feature_collection(path).get("features", []):
        props, geom = feat.get("properties") or {}, feat.get("geometry") or {}
        if props.get("kind") == "room" and geom.get("type") in ("Polygon", "MultiPolygon"):
            poly = _scored_polygon(shapely.geometry.shape(geom))
            rooms.append({
                "room_id": props.get("room_id", len(rooms)), "name": str(props.get("name", "")),
                "kind": str(props.get("room_kind", "room")), "area_m2": float(props.get("area_m2", poly.area)),
                "perimeter_m": float(props.get("perimeter_m", poly.length)), "polygon": poly,
            })  # fmt: skip
        elif props.get("kind") == "door" and geom.get("type") == "LineString" and len(geom["coordinates"]) >= 2:
            (x0, y0), (x1, y1) = (c[:2] for c in (geom["coordinates"][0], geom["coordinates"][-1]))
            doors.append({
                "door_id": props.get("door_id", len(doors)), "x0": x0, "y0": y0, "x1": x1, "y1": y1,
                "x": (x0 + x1) / 2, "y": (y0 + y1) / 2, "width_m": float(props.get("width_m", math.hypot(x1 - x0, y1 - y0))),
                "wall_id": props.get("wall_id"), "room_a": props.get("room_a"), "room_b": props.get("room_b"),
                "exterior": bool(props.get("exterior", False)),
            })  # fmt: skip
    return _rooms_frames(rooms, doors)


def room_seen_share(polygons, grid, within_m: float = SEEN_WITHIN_M) -> np.ndarray:
    """The share of each room's area the recording saw.

    Each polygon is sampled at the centres of the reference grid's cells inside it;
    a sample is seen when it lies within ``within_m`` of the grid's free space
    (:func:`floorscan.score.drawn.seen_by_recording`, once for the samples of all
    the polygons).

    Parameters
    ----------
    polygons : sequence of shapely Polygon
        Rooms, map metres.
    grid : floorscan.core.occupancy.OccupancyGrid
        The reference map.
    within_m : float

    Returns
    -------
    (N,) float64 ndarray
        In [0, 1]; 0 for a room with no cell centre inside.
    """
    import shapely

    from floorscan.score.drawn import seen_by_recording

    r, (ox, oy) = grid.resolution_m, grid.origin_xy
    samples, owner = [np.empty((0, 2))], [np.empty(0, np.int64)]
    for i, poly in enumerate(polygons):
        x0, y0, x1, y1 = poly.bounds
        xs = ox + (np.arange(math.floor((x0 - ox) / r), math.ceil((x1 - ox) / r)) + 0.5) * r
        ys = oy + (np.arange(math.floor((y0 - oy) / r), math.ceil((y1 - oy) / r)) + 0.5) * r
        xx, yy = (a.ravel() for a in np.meshgrid(xs, ys))
        inside = shapely.contains_xy(poly, xx, yy)
        samples.append(np.column_stack([xx[inside], yy[inside]]))
        owner.append(np.full(int(inside.sum()), i, dtype=np.int64))
    xy, owner = np.concatenate(samples), np.concatenate(owner)
    if not len(xy):
        return np.zeros(len(polygons))
    n = np.bincount(owner, minlength=len(polygons)).astype(np.float64)
    seen = np.bincount(owner, weights=seen_by_recording(xy, grid, within_m), minlength=len(polygons))
    return np.divide(seen, n, out=np.zeros(len(polygons)), where=n > 0)


def match_doors(
    true_xy: np.ndarray, counted: np.ndarray, plan_xy: np.ndarray, tolerance_m: float = DOOR_TOLERANCE_M,
) -> tuple[dict, dict]:  # fmt: skip
    """Door recall, precision and centre error of a one-to-one matching of door centres.

    Each counted true door is matched to at most one plan door whose centre lies within
    ``tolerance_m``, the matching of least summed distance (``linear_sum_assignment``).
    An unmatched plan door within ``tolerance_m`` of a true door that does not count
    (leading outside, or into a room that does not count) is left out of precision.

    Parameters
    ----------
    true_xy : (D, 2) float ndarray
        True door centres, metres.
    counted : (D,) bool ndarray
    plan_xy : (Q, 2) float ndarray
        Plan door centres, metres.
    tolerance_m : float

    Returns
    -------
    scores : dict
        ``door_recall`` (matched / counted true doors), ``door_precision`` (matched /
        plan doors scored), ``door_centre_error_m`` (mean over matched pairs), NaN when
        undefined; ``n_true_doors`` (counted), ``n_plan_doors``,
        ``n_plan_doors_scored``, ``n_matched_doors``.
    detail : dict
        ``pairs`` (K, 2) int (true, plan index), ``distance_m`` (K,), ``left_out`` (Q,) bool.
    """
    from scipy.optimize import linear_sum_assignment

    t = np.asarray(true_xy, dtype=np.float64).reshape(-1, 2)
    p = np.asarray(plan_xy, dtype=np.float64).reshape(-1, 2)
    counted = np.asarray(counted, dtype=bool)
    d = np.hypot(*(t[:, None, :] - p[None, :, :]).transpose(2, 0, 1)).reshape(len(t), len(p))
    ti = np.flatnonzero(counted)
    sub = d[ti]
    big = 1e6 * (1.0 + tolerance_m)
    rows, cols = linear_sum_assignment(np.where(sub <= tolerance_m, sub, big))
    keep = sub[rows, cols] <= tolerance_m
    pairs = np.column_stack([ti[rows[keep]], cols[keep]]).astype(np.int64).reshape(-1, 2)
    dist = d[pairs[:, 0], pairs[:, 1]]
    left_out = np.zeros(len(p), dtype=bool)
    if (~counted).any() and len(p):
        left_out = (d[~counted] <= tolerance_m).any(axis=0)
    left_out[pairs[:, 1]] = False
    k, n_scored = len(pairs), int((~left_out).sum())
    scores = {
        "door_recall": k / len(ti) if len(ti) else math.nan,
        "door_precision": k / n_scored if n_scored else math.nan,
        "door_centre_error_m": float(dist.mean()) if k else math.nan,
        "n_true_doors": len(ti), "n_plan_doors": len(p), "n_plan_doors_scored": n_scored, "n_matched_doors": k,
    }  # fmt: skip
    return scores, {"pairs": pairs, "distance_m": dist, "left_out": left_out}


def score_row(name: str, truth: str, *parts: dict) -> dict:
    """A row of ``room_scores.csv``: every :data:`ROOM_SCORE_COLUMNS` NaN but the plan's
    ``name``, the ``truth`` and the keys of ``parts``.

    Parameters
    ----------
    name : str
    truth : str
    *parts : dict
        Score dicts, applied in order.

    Returns
    -------
    dict
    """
    row = {c: math.nan for c in ROOM_SCORE_COLUMNS}
    row.update({"plan": name, "truth": truth})
    for part in parts:
        row.update(part)
    return row


def score_room_plans(plans: dict, grid, truth_path=None) -> tuple[pd.DataFrame, dict]:
    """Rule ``score_rooms``: every plan's rooms and doors against the simulator's.

    Parameters
    ----------
    plans : dict
        ``{name: folder}`` of plan folders (:func:`read_plan_folder_rooms`).
    grid : floorscan.core.occupancy.OccupancyGrid
        The reference map (what the recording saw).
    truth_path : path, optional
        The simulator's ``walls.geojson`` with ``room`` and ``door`` features
        (:func:`floorscan.sim.ground_truth.ground_truth_walls`); without it (a real
        recording without a drawn segmentation) only the plan's counts are filled.

    Returns
    -------
    table : pandas.DataFrame
        One row per plan, :data:`ROOM_SCORE_COLUMNS`.
    overlay : dict
        What :func:`floorscan.figures.rooms.rooms_overlay_figure` draws.

    Raises
    ------
    floorscan.core.io.InputError
        When ``truth_path`` holds no room (written before the truth had rooms: rerun
        the simulate stage).
    FileNotFoundError
        When a plan's folder is not a plan folder.
    """
    import shapely

    from floorscan.core.io import InputError

    overlay = {"truth": "none", "true_rooms": [], "counted": np.zeros(0, bool), "true_doors_xy": np.empty((0, 2)),
               "true_doors_counted": np.zeros(0, bool), "structure": grid.cell_centres(grid.structure()), "plans": {}}  # fmt: skip
    if truth_path is not None:
        true_rooms, true_doors = read_rooms(truth_path)
        if not len(true_rooms):
            raise InputError(f"{truth_path}: no feature of kind 'room'; rerun the simulate stage (-R simulate)")
        polys = np.array(list(true_rooms["polygon"]), dtype=object)
        counted = room_seen_share(polys, grid) >= SEEN_SHARE
        ok_ids = set(true_rooms["room_id"].to_numpy()[counted].tolist())
        door_counted = (~true_doors["exterior"].to_numpy(bool)
                        & true_doors["room_a"].isin(ok_ids).to_numpy() & true_doors["room_b"].isin(ok_ids).to_numpy())  # fmt: skip
        overlay.update(truth="ground_truth", true_rooms=list(polys), counted=counted,
                       true_doors_xy=true_doors[["x", "y"]].to_numpy(np.float64), true_doors_counted=door_counted)  # fmt: skip
    rows = []
    for name, folder in plans.items():
        rooms, doors = read_plan_folder_rooms(folder)
        plan_polys = np.array(list(rooms["polygon"]), dtype=object)
        entry = {"rooms": list(plan_polys), "doors_xy": doors[["x", "y"]].to_numpy(np.float64)}
        if truth_path is None:
            rows.append(score_row(name, "none", {"n_plan_rooms": len(rooms), "n_plan_doors": len(doors)}))
        else:
            inter = shapely.area(shapely.intersection(polys[:, None], plan_polys[None, :]))  # (T, P), P may be 0
            r_scores, r_detail = segmentation_scores(inter, shapely.area(polys), shapely.area(plan_polys), counted,
                                                     MIN_REGION_PX * grid.resolution_m**2)  # fmt: skip
            d_scores, d_detail = match_doors(overlay["true_doors_xy"], door_counted, entry["doors_xy"])
            rows.append(score_row(name, "ground_truth", r_scores, d_scores))
            entry.update(rooms_detail=r_detail, doors_detail=d_detail)
        overlay["plans"][name] = entry
    table = pd.DataFrame(rows, columns=ROOM_SCORE_COLUMNS)
    overlay["scores"] = table
    return table, overlay
