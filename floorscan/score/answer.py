"""How good the answer is: the recommended floor plan (``plan_tables/``, the Parquet
tables of ``floorplan.geojson``) and the plan of all kept scans by the map extractor
(``evaluation/plans/all_scans_map/``), scored as plans a person opens (rule
``score_answer``). Plans are read as the floorplan stage passes them, Parquet tables
(:mod:`floorscan.core.plan_tables`: the numbers of the GeoJSON export).

Per plan (:func:`score_answer_plan`):

- against the reference map (all kept scans' occupancy grid,
  :func:`floorscan.score.against_reference.plan_against_reference`): completeness,
  correctness and F1 of the wall faces at 5 and 10 cm, and completeness of the walls and
  clutter together (``map_completeness_all_<t>cm``: the reference map counts furniture
  as structure);
- on a synthetic recording, against the simulator's true walls
  (:func:`floorscan.score.tolerance.tolerance_metrics`): precision of the wall faces
  against all true faces, recall against the observed faces (thesis 5.2), F1; the number
  of walls against the true count of observed wall pieces (:func:`true_wall_pieces`);
  the share of the observed true corners that are junctions of the plan
  (:func:`true_corners`, within ``corner_tolerance_m``);
- the plan's own shape: walls, clutter pieces, junctions, the share of walls shorter
  than 0.5 m, and the pairs of walls that cross away from a junction
  (:func:`crossings`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.core.plan_tables import read_plan_tables
from floorscan.score.geojson import feature_collection, wall_faces
from floorscan.core.segments import as_segments

#: Plans a person should not see: walls shorter than this, metres.
SHORT_WALL_M = 0.5


def plan_parts(folder) -> dict[str, np.ndarray]:
    """The parts of a plan folder (:func:`floorscan.core.plan_tables.read_plan_tables`)
    the answer's scores use, in the tables' order (the GeoJSON export's).

    Parameters
    ----------
    folder : path
        A plan folder, e.g. ``results/<dataset>/plan_tables``.

    Returns
    -------
    dict of str to ndarray
        ``faces`` (merged faces), ``axes`` (wall axes), ``clutter``: (N, 4) float64
        ``x0, y0, x1, y1``, map metres, rows with a non-finite coordinate dropped
        (:func:`floorscan.core.segments.as_segments`, as the GeoJSON reader does);
        ``junctions``: (J, 2) float64, map metres.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    xy = ["x0", "y0", "x1", "y1"]
    t = read_plan_tables(folder, ("walls", "faces", "clutter", "junctions"),
                         {"walls": xy, "faces": xy, "clutter": xy, "junctions": ["x", "y"]})  # fmt: skip
    return {
        "faces": as_segments(t["faces"]), "axes": as_segments(t["walls"]), "clutter": as_segments(t["clutter"]),
        "junctions": t["junctions"][["x", "y"]].to_numpy(np.float64).reshape(-1, 2),
    }  # fmt: skip


def crossings(axes: np.ndarray, junctions: np.ndarray, tolerance_m: float = 0.05) -> int:
    """Pairs of wall axes that cross at a point farther than ``tolerance_m`` from every
    junction and from both walls' ends: walls drawn through each other.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes, metres.
    junctions : (J, 2) float ndarray
        Metres.
    tolerance_m : float
        Metres.

    Returns
    -------
    int
    """
    import shapely

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    if len(axes) < 2:
        return 0
    lines = shapely.linestrings(axes.reshape(-1, 2, 2))
    i, j = shapely.STRtree(lines).query(lines, predicate="crosses")
    keep = i < j
    i, j = i[keep], j[keep]
    n = 0
    for a, b in zip(i.tolist(), j.tolist()):
        x = shapely.get_coordinates(shapely.intersection(lines[a], lines[b]))
        if len(x) == 0:
            continue
        p = x[0]
        ends = axes[[a, a, b, b]].reshape(4, 2, 2)[[0, 1, 2, 3], [0, 1, 0, 1]]
        if np.hypot(*(ends - p).T).min() <= tolerance_m:
            continue
        if len(junctions) and np.hypot(*(junctions - p).T).min() <= tolerance_m:
            continue
        n += 1
    return n


def true_wall_pieces(truth: dict, gap_m: float = 0.3) -> np.ndarray:
    """The observed wall pieces of a synthetic building: each true axis cut where
    neither of its faces was observed over more than ``gap_m`` (an opening or an unseen
    stretch).

    Parameters
    ----------
    truth : dict
        :func:`read_truth`.
    gap_m : float
        Metres.

    Returns
    -------
    (P, 4) float64 ndarray
        Pieces along the axes, metres.
    """
    axes, observed = truth["axis"], truth["observed_face"]
    pieces = []
    for a in axes:
        d = a[2:] - a[:2]
        length = float(np.hypot(*d))
        if length <= 0:
            continue
        u = d / length
        n = np.array([-u[1], u[0]])
        rel0, rel1 = observed[:, :2] - a[:2], observed[:, 2:] - a[:2]
        off = np.maximum(np.abs(rel0 @ n), np.abs(rel1 @ n))
        par = np.abs((observed[:, 2:] - observed[:, :2]) @ n) < 1e-6 + 0.05 * np.hypot(*(observed[:, 2:] - observed[:, :2]).T)
        near = par & (off <= truth["thickness"].get(tuple(a), 0.3) / 2 + 0.02)
        iv = np.sort(np.column_stack([rel0[near] @ u, rel1[near] @ u]), axis=1)
        iv = iv[np.argsort(iv[:, 0])]
        start, end = None, None
        for lo, hi in np.clip(iv, 0, length).tolist():
            if start is None:
                start, end = lo, hi
            elif lo - end > gap_m:
                pieces.append(np.r_[a[:2] + start * u, a[:2] + end * u])
                start, end = lo, hi
            else:
                end = max(end, hi)
        if start is not None and end - start > gap_m:
            pieces.append(np.r_[a[:2] + start * u, a[:2] + end * u])
    return np.array(pieces, dtype=np.float64).reshape(-1, 4)


def true_corners(truth: dict, near_observed_m: float = 0.4) -> np.ndarray:
    """The observed corners of a synthetic building: the ends of the true axes that lie
    on another axis (L and T junctions, within 0.02 m), kept when an observed face passes
    within ``near_observed_m``.

    Parameters
    ----------
    truth : dict
        :func:`read_truth`.
    near_observed_m : float
        Metres.

    Returns
    -------
    (C, 2) float64 ndarray
        Metres, unique to the millimetre.
    """
    import shapely

    from floorscan.score.nearest import nearest_distances

    axes = np.asarray(truth["axis"], dtype=np.float64).reshape(-1, 4)
    ends = axes.reshape(-1, 2)  # the ends of axis k are rows 2k and 2k + 1
    end, axis = shapely.STRtree(shapely.linestrings(axes.reshape(-1, 2, 2))).query(
        shapely.points(ends), predicate="dwithin", distance=0.02)
    on_another = np.unique(end[axis != end // 2])
    if not len(on_another):
        return np.empty((0, 2))
    pts = np.unique(np.round(ends[on_another], 3), axis=0)
    obs = truth["observed_face"]
    if not len(obs):
        return np.empty((0, 2))
    return pts[nearest_distances(pts, obs) <= near_observed_m].astype(np.float64)


def read_truth(path) -> dict:
    """The simulator's ``walls.geojson``.

    Parameters
    ----------
    path : path

    Returns
    -------
    dict
        ``face``, ``observed_face``, ``axis``: (N, 4) float64, metres; ``thickness``:
        axis row tuple -> metres (0.3 when the feature has none); ``pieces``
        (:func:`true_wall_pieces`) and ``corners`` (:func:`true_corners`), derived once
        for every plan scored against them.

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a GeoJSON FeatureCollection.
    """
    doc = feature_collection(path)
    out = {kind: wall_faces(doc, kind) for kind in ("face", "observed_face", "axis")}
    out["thickness"] = {}
    for f in doc.get("features", []):
        p = f.get("properties") or {}
        if p.get("kind") == "axis" and f["geometry"]["type"] == "LineString":
            c = f["geometry"]["coordinates"]
            out["thickness"][tuple(np.asarray([*c[0][:2], *c[1][:2]], dtype=np.float64))] = float(p.get("thickness_m", 0.3))
    out["pieces"] = true_wall_pieces(out)
    out["corners"] = true_corners(out)
    return out


def score_answer_plan(folder, reference=None, truth: dict | None = None, taus_m=(0.05, 0.10),
                      corner_tolerance_m: float = 0.3) -> dict:  # fmt: skip
    """The scores of one plan (see the module docstring).

    Parameters
    ----------
    folder : path
        The plan folder (:func:`plan_parts`).
    reference : OccupancyGrid or Structure, optional
        The reference map.
    truth : dict, optional
        :func:`read_truth` of a synthetic recording.
    taus_m : tuple of float
        Tolerances, metres.
    corner_tolerance_m : float
        A true corner is a junction of the plan when one lies within this, metres.

    Returns
    -------
    dict
        Counts (``n_walls``, ``n_clutter``, ``n_junctions``, ``short_wall_share``,
        ``n_crossings``), ``map_*`` against the reference map, ``gt_*`` against the
        truth.

    Raises
    ------
    FileNotFoundError
        When ``folder`` is not a plan folder.
    """
    from floorscan.score.against_reference import plan_against_reference
    from floorscan.score.tolerance import tolerance_metrics

    parts = plan_parts(folder)
    faces, axes, clutter, junctions = parts["faces"], parts["axes"], parts["clutter"], parts["junctions"]
    length = np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1])
    out = {
        "n_walls": len(axes), "n_clutter": len(clutter), "n_junctions": len(junctions),
        "short_wall_share": float((length < SHORT_WALL_M).mean()) if len(axes) else 0.0,
        "n_crossings": crossings(axes, junctions),
    }  # fmt: skip
    if reference is not None:
        walls_only = plan_against_reference(faces, reference, tuple(taus_m))
        both = plan_against_reference(np.r_[faces, clutter].reshape(-1, 4), reference, tuple(taus_m))
        for key, value in walls_only.items():
            out[f"map_{key}"] = value
        for tau in taus_m:
            cm = f"{round(tau * 100):d}cm"
            out[f"map_completeness_all_{cm}"] = both[f"completeness_{cm}"]
    if truth is not None:
        precision = tolerance_metrics(faces, truth["face"], taus_m)
        recall = tolerance_metrics(faces, truth["observed_face"], taus_m)
        for tau in taus_m:
            cm = f"{round(tau * 100):d}cm"
            p, r = precision[f"precision_{cm}"], recall[f"recall_{cm}"]
            out[f"gt_precision_{cm}"], out[f"gt_recall_{cm}"] = p, r
            out[f"gt_f1_{cm}"] = 2 * p * r / (p + r) if p + r > 0 else 0.0
        pieces, corners = truth["pieces"], truth["corners"]
        out["gt_n_walls"] = len(pieces)
        if len(corners):
            if len(junctions):
                d = np.hypot(*(corners[:, None, :] - junctions[None, :, :]).transpose(2, 0, 1)).min(axis=1)
            else:
                d = np.full(len(corners), np.inf)
            out["gt_corners_as_junctions"] = float((d <= corner_tolerance_m).mean())
        out["gt_n_corners"] = len(corners)
    return out


def score_answer(plans: dict, reference_path=None, truth_path=None) -> pd.DataFrame:
    """:func:`score_answer_plan` of every plan.

    Parameters
    ----------
    plans : dict of str to path
        Name (``recommended``, ``all_scans_map``) -> the plan's folder (:func:`plan_parts`).
    reference_path : path, optional
        ``reference/occupancy.parquet`` (:func:`floorscan.core.occupancy.read_grid`).
    truth_path : path, optional
        The simulator's ``walls.geojson``.

    Returns
    -------
    pandas.DataFrame
        One row per plan, ``plan`` its name, then :func:`score_answer_plan`'s keys.

    Raises
    ------
    FileNotFoundError
        When a plan's folder is not a plan folder.
    """
    from floorscan.score.against_reference import Structure, read_reference

    reference = None if reference_path is None else Structure(read_reference(reference_path))
    truth = None if truth_path is None else read_truth(truth_path)
    rows = [{"plan": name, **score_answer_plan(folder, reference, truth)} for name, folder in plans.items()]
    return pd.DataFrame(rows)
