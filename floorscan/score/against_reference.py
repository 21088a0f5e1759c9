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
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import sample_segments, sample_spacing, samples_per_segment
from floorscan.core.memory import JobMemory
from floorscan.core.occupancy import OccupancyGrid, read_grid
from floorscan.score.structure_grid import StructureGrid, nearest_sample_d2

if TYPE_CHECKING:
    import pandas as pd


#: What a cell of the reference map takes a job that scores plans against it: the grid
#: read (int32 counts), its log-odds and their temporaries (float64) for the structure
#: and free masks, and the masks; rounded up (``benchmarks/README.md``).
SCORING_MEMORY = JobMemory(48, "score.reference.resolution_m")


def read_reference(path) -> OccupancyGrid:
    """The reference map (:func:`floorscan.core.occupancy.read_grid`), read when the
    scoring job's rasters (:data:`SCORING_MEMORY`) fit in the memory free on the machine.

    Parameters
    ----------
    path : path
        ``reference/occupancy.parquet``.

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    floorscan.core.memory.MemoryEstimateError
        Before the grid is read, when they would not fit.
    """
    return read_grid(path, SCORING_MEMORY, f"scoring against the reference map {path}")

class Structure:
    """The reference map's structure, prepared once for scoring many plans.

    Plans scored against one Structure share the work per wall face: the distances
    of a face's samples do not depend on the other faces of its plan, and the plans
    of one ordering at growing k, or of several orderings, share most of their faces.
    A face seen before (the same four coordinates, the same ``taus_m`` and
    ``sample_m``) is not sampled or queried again; its plan's metrics are those of
    scoring all its samples at once. Past :data:`CACHE_SAMPLES` samples, the faces
    least recently asked for are dropped down to :data:`CACHE_KEPT` of it: the next
    plans of an ordering, a few scans more, are built mostly of its last plans' faces.

    Attributes
    ----------
    grid : OccupancyGrid
    xy : (S, 2) float64 ndarray
        Centres of the structure cells, metres.
    tree : scipy.spatial.cKDTree
        Of ``xy``.
    cells : floorscan.score.structure_grid.StructureGrid
        The same cells on the grid: the nearest of a point, those near a segment.
    free : (H, W) bool ndarray
        The grid's free cells.

    Raises
    ------
    ValueError
        When the reference map has no structure cell.
    """

    #: Samples the face cache holds at most (with their faces' cells, about 20 bytes
    #: each) ...
    CACHE_SAMPLES = 5_000_000
    #: ... and the share of them it keeps when full, the faces last asked for: half,
    #: so that it sorts its faces once every many plans, not at each.
    CACHE_KEPT = 0.5

    def __init__(self, grid: OccupancyGrid):
        self.grid = grid
        mask = grid.structure()
        self.xy = grid.cell_centres(mask)
        if len(self.xy) == 0:
            raise ValueError("the reference map has no structure cell (occupied and hit by enough scans)")
        self.tree = cKDTree(self.xy)
        self.cells = StructureGrid(grid, mask, self.tree)
        self.free = grid.free()
        self._faces: dict[tuple, dict[bytes, _FaceScore]] = {}
        self._used: dict[tuple, dict[bytes, int]] = {}  # the last call that asked for each face
        self._calls = 0
        self._cached_samples = 0

    def face_scores(self, seg: np.ndarray, taus_m: tuple[float, ...], sample_m: float) -> list[_FaceScore]:
        """The score of each face against the structure cells; faces not seen before are
        computed together and cached.

        Parameters
        ----------
        seg : (F, 4) float64 ndarray
            Faces ``x0, y0, x1, y1``, metres.
        taus_m : tuple of float
            Tolerances, metres.
        sample_m : float
            Spacing of the face samples, metres.

        Returns
        -------
        list of _FaceScore
            One per row of ``seg``, in order.
        """
        if self._cached_samples > self.CACHE_SAMPLES:
            self._drop_least_recent()
        how = (tuple(float(t) for t in taus_m), float(sample_m))
        cache, used = self._faces.setdefault(how, {}), self._used.setdefault(how, {})
        keys = [row.tobytes() for row in seg]
        new = list(dict.fromkeys(k for k in keys if k not in cache))
        if new:
            rows = np.frombuffer(b"".join(new), dtype=np.float64).reshape(-1, 4)
            for key, score in zip(new, _score_faces(self, rows, taus_m, sample_m)):
                cache[key] = score
                self._cached_samples += score.n
        self._calls += 1
        used.update(dict.fromkeys(keys, self._calls))
        return [cache[k] for k in keys]

    def _drop_least_recent(self) -> None:
        """Drop the faces least recently asked for until the cache holds at most
        :data:`CACHE_KEPT` of :data:`CACHE_SAMPLES` samples."""
        last = [(call, how, key) for how, used in self._used.items() for key, call in used.items()]
        last.sort(key=lambda t: t[0])
        for _, how, key in last:
            if self._cached_samples <= self.CACHE_KEPT * self.CACHE_SAMPLES:
                break
            self._cached_samples -= self._faces[how].pop(key).n
            del self._used[how][key]


@dataclass(frozen=True)
class _FaceScore:
    """What one wall face adds to its plan's metrics (:func:`plan_against_reference`).

    Attributes
    ----------
    n : int
        Its samples (:func:`floorscan.core.geometry.samples_per_segment`).
    weight : float
        Metres of face each sample stands for.
    distance : (n,) float64 ndarray
        Each sample's distance to the nearest structure cell centre, metres (inf
        beyond ten times the largest tau).
    on_free : (n,) bool ndarray
        Samples on free cells and beyond the largest tau from structure.
    near : tuple of int32 ndarray
        Per tau, the structure cells (indices into ``Structure.xy``) within
        :func:`within_bound` of a sample.
    """

    n: int
    weight: float
    distance: np.ndarray
    on_free: np.ndarray
    near: tuple[np.ndarray, ...]


def _score_faces(ref: Structure, seg: np.ndarray, taus_m: tuple[float, ...], sample_m: float) -> list[_FaceScore]:
    """:class:`_FaceScore` of each row of ``seg`` ((F, 4) float64): the distances the
    whole-plan queries of :func:`plan_against_reference` give, one face at a time."""
    n = samples_per_segment(seg, sample_m)
    starts = np.r_[0, np.cumsum(n)]
    samples = sample_segments(seg, sample_m)
    weight = sample_spacing(seg, sample_m)  # equal within a face
    distance = ref.cells.nearest(samples, max(taus_m) * 10)  # as ref.tree.query(...)[0]
    # beside a wall the free cells begin within a cell of its face: only samples beyond
    # the largest tolerance from structure are a wall drawn through free space
    far = np.flatnonzero(distance > max(taus_m))
    rows, cols, inside = ref.grid.cells_of(samples[far])
    on_free = np.zeros(len(samples), dtype=bool)
    on_free[far[inside]] = ref.free[rows[inside], cols[inside]]
    near_cell, near_face, near_distance = _cells_near_samples(ref, seg, samples, starts,
                                                              within_bound(max(taus_m), sample_m))
    near, cell_type = [], np.int32 if len(ref.xy) < 2**31 else np.int64
    for tau in taus_m:
        keep = near_distance <= within_bound(tau, sample_m)
        cells, faces = near_cell[keep], near_face[keep]
        near.append(np.split(cells.astype(cell_type), np.searchsorted(faces, np.arange(1, len(seg)))))
    return [
        _FaceScore(int(n[f]), float(weight[f]), distance[starts[f] : starts[f + 1]],
                   on_free[starts[f] : starts[f + 1]], tuple(per_tau[f] for per_tau in near))
        for f in range(len(seg))
    ]  # fmt: skip


def _cells_near_samples(ref: Structure, seg: np.ndarray, samples: np.ndarray, starts: np.ndarray, bound: float):
    """The (structure cell, face) pairs whose nearest face sample lies within
    ``bound`` metres, grouped by face, with that distance.

    ``samples`` are :func:`sample_segments` of ``seg``, face ``f``'s from
    ``starts[f]`` to ``starts[f + 1]``; a cell's nearest sample is measured as the
    whole-plan query measures it (:func:`floorscan.score.structure_grid.nearest_sample_d2`).
    Candidate cells are those within ``bound`` (plus a little) of the face's segment.

    Returns
    -------
    cell, face : (P,) int64 ndarray
        Indices into ``ref.xy`` and into ``seg``: by face, and by cell within a face.
    distance : (P,) float64 ndarray
        Metres.
    """
    from floorscan.core.geometry import point_segment_dist2

    reach = bound * (1 + 1e-6) + 1e-9
    cell, face = ref.cells.segment_cells(seg, reach)
    cx, cy = ref.xy[cell, 0], ref.xy[cell, 1]
    keep = point_segment_dist2(cx, cy, seg[face]) <= reach * reach
    cell, face, cx, cy = cell[keep], face[keep], cx[keep], cy[keep]
    distance = np.sqrt(nearest_sample_d2(cx, cy, face, seg, samples, starts))
    keep = distance <= bound
    return cell[keep], face[keep], distance[keep]


def within_bound(tau_m: float, sample_m: float) -> float:
    """Distance to the nearest sample of a segment sampled every ``sample_m`` below
    which a point is within ``tau_m`` of the segment, up to ``sample_m**2 / (8 tau)``
    (a point at ``tau`` from the segment has a sample within half a spacing along it).

    Parameters
    ----------
    tau_m : float
        Metres.
    sample_m : float
        Metres.

    Returns
    -------
    float
        ``sqrt(tau**2 + (sample_m / 2)**2)``, metres.
    """
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
    seg = np.ascontiguousarray(faces, dtype=np.float64).reshape(-1, 4)
    out: dict[str, float] = {"n_structure_cells": float(len(ref.xy))}
    scores = ref.face_scores(seg, tuple(taus_m), sample_m)
    # the plan's samples, face after face, as sample_segments gives them
    weights = np.repeat(np.array([s.weight for s in scores]), [s.n for s in scores])
    total = float(weights.sum())
    out["plan_length_m"] = total
    if len(weights) == 0 or total <= 0:
        for tau in taus_m:
            key = _cm(tau)
            out[f"completeness_{key}"], out[f"correctness_{key}"], out[f"f1_{key}"] = 0.0, math.nan, math.nan
        out["median_distance_m"], out["free_fraction"] = math.nan, math.nan
        return out
    d_plan = np.concatenate([s.distance for s in scores])
    for t, tau in enumerate(taus_m):
        key = _cm(tau)
        correctness = float(weights[d_plan <= tau].sum() / total)
        complete = np.zeros(len(ref.xy), dtype=bool)
        complete[np.concatenate([s.near[t] for s in scores])] = True
        completeness = float(np.mean(complete))
        f1 = 2 * correctness * completeness / (correctness + completeness) if correctness + completeness > 0 else 0.0
        out[f"completeness_{key}"], out[f"correctness_{key}"], out[f"f1_{key}"] = completeness, correctness, f1
    out["median_distance_m"] = float(np.median(d_plan))
    on_free = np.concatenate([s.on_free for s in scores])
    out["free_fraction"] = float(weights[on_free].sum() / total)
    return out


def _cm(tau_m: float) -> str:
    return f"{round(tau_m * 100):d}cm"


def score_plans(runs: list[dict], grid: OccupancyGrid, taus_m: tuple[float, ...], faces_of) -> "pd.DataFrame":
    """:func:`plan_against_reference` of every run's floor plan.

    Parameters
    ----------
    runs : list of dict
        ``ordering``, ``extractor``, ``k`` (label) and ``floorplan`` (a plan folder, :mod:`floorscan.core.plan_tables`).
    grid : OccupancyGrid
    taus_m : tuple of float
    faces_of : callable
        Path -> (F, 4) faces of the plan (:func:`floorscan.core.plan_tables.plan_faces_and_walls`).

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
