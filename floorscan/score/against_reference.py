"""A floor plan against a reference map, in the ISPRS indoor benchmark's terms.

The ISPRS benchmark on indoor modelling (Khoshelham et al., ISPRS Annals IV-2/W4,
2017) scores a model against a reference by *completeness* (the fraction of the
reference that lies within a tolerance tau of the model), *correctness* (the fraction
of the model that lies within tau of the reference) and their harmonic mean. Here the
model is the floor plan's wall faces (the lines the scanner sees; ``kind`` "face" of
the GeoJSON) and the reference is the structure of the occupancy grid
(:mod:`floorscan.score.reference`): occupied cells hit by at least two scans.

- completeness (recall) at tau: structure cells whose centre is within tau of a face
  (of its samples every ``sample_m``, 2 cm: within :func:`within_bound`, 1 mm more);
- correctness (precision) at tau: face length (sampled every ``sample_m``) within tau
  of a structure cell's centre. A wall drawn through free space is far from any
  structure and lowers it;
- F1 = 2 P R / (P + R); the median distance of the face samples to the structure;
- ``free_fraction``: face length over cells the reference map calls free and farther
  than the largest tau from structure (a wall drawn where scans saw through), the part
  of the incorrect length that the scans contradict; the rest lies in unknown space.

Cell centres quantise the structure to the grid: a wall surface lies within half a
cell (2.5 cm at 5 cm cells) of its cells' centres across the wall, so tau below that
is not meaningful.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import sample_segments, segment_weights
from floorscan.score.reference import OccupancyGrid

if TYPE_CHECKING:
    import pandas as pd


class Structure:
    """The reference map's structure, prepared once for scoring many plans.

    Attributes
    ----------
    grid : OccupancyGrid
    xy : (S, 2) float64 ndarray
        Centres of the structure cells, metres.
    tree : scipy.spatial.cKDTree
        Of ``xy``.
    free : (H, W) bool ndarray
        The grid's free cells.

    Raises
    ------
    ValueError
        When the reference map has no structure cell.
    """

    def __init__(self, grid: OccupancyGrid):
        self.grid = grid
        self.xy = grid.cell_centres(grid.structure())
        if len(self.xy) == 0:
            raise ValueError("the reference map has no structure cell (occupied and hit by enough scans)")
        self.tree = cKDTree(self.xy)
        self.free = grid.free()


def within_bound(tau_m: float, sample_m: float) -> float:
    """Distance to the nearest sample of a segment sampled every ``sample_m`` below
    which a point is within ``tau_m`` of the segment, up to ``sample_m**2 / (8 tau)``:
    ``sqrt(tau**2 + (sample_m / 2)**2)`` (a point at ``tau`` from the segment has a
    sample within half a spacing along it)."""
    return math.hypot(tau_m, 0.5 * sample_m)


def plan_against_reference(
    faces: np.ndarray,
    reference: OccupancyGrid | Structure,
    taus_m: tuple[float, ...] = (0.05, 0.10),
    sample_m: float = 0.02,
) -> dict[str, float]:
    """Completeness, correctness, F1 and median distance of a plan's faces against
    the reference map's structure (see the module docstring).

    Parameters
    ----------
    faces : (F, 4) float ndarray
        The plan's wall faces, x0, y0, x1, y1 in the map frame, metres.
    reference : OccupancyGrid or Structure
        The reference map (a :class:`Structure` when scoring many plans).
    taus_m : tuple of float
        Tolerances, metres; the keys carry them in cm (``completeness_5cm``).
    sample_m : float
        Spacing of the face samples, metres (completeness within
        :func:`within_bound` of tau).

    Returns
    -------
    dict of str to float
        ``completeness_<t>cm``, ``correctness_<t>cm``, ``f1_<t>cm`` per tau,
        ``median_distance_m``, ``free_fraction``, ``plan_length_m``,
        ``n_structure_cells``. Completeness is 0 and the others NaN for a plan
        without faces.

    Raises
    ------
    ValueError
        When the reference map has no structure cell.
    """
    ref = reference if isinstance(reference, Structure) else Structure(reference)
    structure = ref.xy
    seg = np.asarray(faces, dtype=np.float64).reshape(-1, 4)
    out: dict[str, float] = {"n_structure_cells": float(len(structure))}
    samples = sample_segments(seg, sample_m)
    weights = segment_weights(seg, sample_m)
    total = float(weights.sum())
    out["plan_length_m"] = total
    if len(samples) == 0 or total <= 0:
        for tau in taus_m:
            key = _cm(tau)
            out[f"completeness_{key}"], out[f"correctness_{key}"], out[f"f1_{key}"] = 0.0, math.nan, math.nan
        out["median_distance_m"], out["free_fraction"] = math.nan, math.nan
        return out
    d_plan, _ = ref.tree.query(samples, k=1, distance_upper_bound=max(taus_m) * 10)
    # an unbalanced tree: built for one query, faster to build, the same distances
    samples_tree = cKDTree(samples, balanced_tree=False, compact_nodes=False)
    d_ref, _ = samples_tree.query(structure, k=1, distance_upper_bound=within_bound(max(taus_m), sample_m))
    for tau in taus_m:
        key = _cm(tau)
        correctness = float(weights[d_plan <= tau].sum() / total)
        completeness = float(np.mean(d_ref <= within_bound(tau, sample_m)))
        f1 = 2 * correctness * completeness / (correctness + completeness) if correctness + completeness > 0 else 0.0
        out[f"completeness_{key}"], out[f"correctness_{key}"], out[f"f1_{key}"] = completeness, correctness, f1
    out["median_distance_m"] = float(np.median(d_plan))
    rows, cols, inside = ref.grid.cells_of(samples)
    on_free = np.zeros(len(samples), dtype=bool)
    on_free[inside] = ref.free[rows[inside], cols[inside]]
    # beside a wall the free cells begin within a cell of its face: only samples beyond
    # the largest tolerance from structure are a wall drawn through free space
    on_free &= d_plan > max(taus_m)
    out["free_fraction"] = float(weights[on_free].sum() / total)
    return out


def _cm(tau_m: float) -> str:
    return f"{round(tau_m * 100):d}cm"


def score_plans(runs: list[dict], grid: OccupancyGrid, taus_m: tuple[float, ...], faces_of) -> "pd.DataFrame":
    """:func:`plan_against_reference` of every run's floor plan.

    Parameters
    ----------
    runs : list of dict
        ``ordering``, ``extractor``, ``k`` (label) and ``floorplan`` (a GeoJSON path).
    grid : OccupancyGrid
    taus_m : tuple of float
    faces_of : callable
        Path -> (F, 4) faces of the plan (:func:`floorscan.score.geojson.floorplan_faces`).

    Returns
    -------
    pandas.DataFrame
        ``ordering``, ``extractor``, ``k`` and the metrics prefixed ``map_``, a row per run.
    """
    import pandas as pd

    structure = Structure(grid)
    rows, seen = [], {}
    for run in runs:
        faces = np.ascontiguousarray(faces_of(run["floorplan"]), dtype=np.float64)
        plan_key = faces.tobytes()  # k = 100, 200, 500 and all are often the same plan
        if plan_key not in seen:
            seen[plan_key] = plan_against_reference(faces, structure, tuple(taus_m))
        m = seen[plan_key]
        rows.append({"ordering": run["ordering"], "extractor": run["extractor"], "k": str(run["k"]),
                     **{f"map_{key}": value for key, value in m.items()}})
    return pd.DataFrame(rows)


def reference_against_ground_truth(
    grid: OccupancyGrid, faces: np.ndarray, observed: np.ndarray | None = None, taus_m: tuple[float, ...] = (0.05, 0.10)
) -> dict[str, float]:
    """How good the reference map is, on a synthetic recording: its structure against
    the simulator's true wall faces.

    Parameters
    ----------
    grid : OccupancyGrid
    faces : (F, 4) float ndarray
        All true wall faces, metres (``kind`` "face" of ``sim/walls.geojson``).
    observed : (G, 4) float ndarray, optional
        The parts of the faces the recording saw (``observed_face``); default ``faces``.
    taus_m : tuple of float

    Returns
    -------
    dict of str to float
        ``correctness_<t>cm``: structure cells within tau of a true face;
        ``completeness_<t>cm``: observed face length within tau of structure.
    """
    out: dict[str, float] = {}
    structure = Structure(grid)
    all_faces = plan_against_reference(faces, structure, taus_m)
    seen = all_faces if observed is None else plan_against_reference(observed, structure, taus_m)
    for tau in taus_m:
        key = _cm(tau)
        out[f"correctness_{key}"] = all_faces[f"completeness_{key}"]
        out[f"completeness_{key}"] = seen[f"correctness_{key}"]
    return out
