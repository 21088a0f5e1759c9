"""The answer's plans of the first k scans (stage ``floorplan``, rule ``answer_floorplans``):
the plan the answer is made with (the map extractor's walls and the structure passes) of
the first k scans of the default ordering, for k on a geometric grid
(:func:`floorscan.core.selection.curve_ks`), each written as plan tables
(``evaluation/answer_plans/k<k>/``, :func:`~floorscan.floorplan.scans.write_plan`). The
score stage scores their walls against the reference map (:mod:`floorscan.score.answer_curve`):
the answer's quality curve, whose k95 and k99 the automatic k is measured against. The
walls depend on the rooms only where a wall bounds none (a facade seen through a window,
clutter of the plan with rooms), so these plans are built without them.

The occupancy grids of the first k scans are built incrementally
(:func:`floorscan.core.prefix_grids.prefix_grids`: each scan is cast once, the grid of k + dk
scans is the counts of k plus dk scans), and each k's plan is built once, by the one
plan builder (:class:`~floorscan.floorplan.scans.ScanPlans`) from the map extractor's
segments of those scans. The map extractor belongs to the walls stage, which this
package does not import: the stage's script hands it in (``segments_of``).

The plans are built in :data:`ANSWER_PLAN_PARTS` jobs (rule ``answer_floorplans_part``),
each a share of the k grid (:func:`answer_plan_ks`), so that they run on two cores; a
plan does not depend on the other ks built beside it (each grid is that of its first k
scans). The last k, all the kept scans, is not built there: its plan is the
evaluation's plan of all kept scans (rule ``all_scans_floorplan``: the same map
extractor, structure passes and grid of the same scans), built once. Rule
``answer_floorplans`` moves the parts' plan folders into one and copies that plan in
as the last k (:func:`merge_answer_plans`).
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Callable, Iterable, Iterator, Mapping

import numpy as np
import pandas as pd

from floorscan.core.memory import JobMemory
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams
from floorscan.core.plan_tables import N_WALL_POINTS
from floorscan.core.prefix_grids import prefix_grids
from floorscan.core.ray_casting import COUNTS_BYTES_PER_CELL
from floorscan.core.selection import curve_ks
from floorscan.core.wall_points import ScanParams
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import PLAN_MEMORY, FloorPlan, plan_of_segments
from floorscan.floorplan.scans import ScanPlans, write_plan

log = logging.getLogger(__name__)

#: What the job takes a cell of the grid of all the scans (the counts being built,
#: :data:`floorscan.core.ray_casting.COUNTS_BYTES_PER_CELL`, a grid's window copied out of
#: them, int32 counts, and the plan built on it, :data:`~floorscan.floorplan.plan.PLAN_MEMORY`)
#: and a wall point (the points of the first k scans concatenated, float64 x 2, and the
#: map extractor's work on them, 40: ``floorscan.walls.map_stage.MAP_MEMORY``).
ANSWER_PLANS_MEMORY = JobMemory(COUNTS_BYTES_PER_CELL + 8 + PLAN_MEMORY.bytes_per_cell, "walls.map.support_cell_m",
                                bytes_per_point=16 + 40)

#: The jobs the answer's plans are built in (rule ``answer_floorplans_part``).
ANSWER_PLAN_PARTS = 2


def answer_plan_ks(n_scans: int, n_points: int = 24, part: int = 0, parts: int = 1, all_scans: bool = True) -> list[int]:
    """The ks of :func:`~floorscan.core.selection.curve_ks` that job ``part`` of ``parts``
    builds: from the largest k down, each to the job with the fewest scans summed over
    its ks so far (longest processing time first: a plan's cost grows with its scans).

    Parameters
    ----------
    n_scans : int
        The ordering's kept scans.
    n_points : int
        Size of the k grid.
    part, parts : int
        The job, ``0 <= part < parts``.
    all_scans : bool
        Whether the last k, ``n_scans``, is built (False: the plan of all kept scans
        is made elsewhere, :func:`merge_answer_plans`).

    Returns
    -------
    list of int
        Increasing; the parts' ks are disjoint and together the whole k grid (without
        its last k when ``all_scans`` is False).

    Raises
    ------
    ValueError
        When ``part`` is not in ``0 .. parts - 1``.
    """
    if not 0 <= part < parts:
        raise ValueError(f"answer plans: part {part} of {parts} does not exist")
    load = [0] * parts
    mine = []
    ks = curve_ks(n_scans, n_points)
    for k in sorted(ks if all_scans else ks[:-1], reverse=True):
        j = min(range(parts), key=lambda i: (load[i], i))
        load[j] += k
        if j == part:
            mine.append(k)
    return sorted(mine)


def first_k_scans_points(
    registered_path: str | os.PathLike, registration: pd.DataFrame, ordering: pd.DataFrame, scan_params: ScanParams
) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """The kept scans of an ordering, in rank order, as the answer's plans take them.

    Parameters
    ----------
    registered_path : path
        ``registered.parquet`` (kept scans' points in the map frame, metres).
    registration : pandas.DataFrame
        ``registration.parquet`` (``scan_id``, ``kept``, ``x_m``, ``y_m``).
    ordering : pandas.DataFrame
        ``orderings/<ordering>.parquet``: ``rank`` and ``scan_id``.
    scan_params : ScanParams
        How a scan becomes wall points (the ``walls`` section's height band and grid).

    Returns
    -------
    list of (scan_id, origin, points)
        Per ranked scan with points in ``registered_path``: its id, the scanner's
        position ((2,) float64, map metres) and its wall points ((N, 2) float64, map
        metres; N may be 0).
    """
    from floorscan.core.io import iter_scans
    from floorscan.core.wall_points import scan_points_2d

    reg = registration[registration["kept"]].set_index("scan_id")
    points = {}
    for sid, xyz in iter_scans(registered_path):
        if sid in reg.index:
            points[sid] = scan_points_2d(xyz, scan_params)[0]
    order = ordering.sort_values("rank")["scan_id"].to_numpy(np.int64)
    order = order[np.isin(order, list(points))]
    origins = reg.loc[order, ["x_m", "y_m"]].to_numpy(np.float64)
    return [(int(s), origins[i], points[s]) for i, s in enumerate(order)]


def answer_plans(
    scans: list[tuple[int, np.ndarray, np.ndarray]],
    segments_of: Callable[[np.ndarray, OccupancyGrid], pd.DataFrame],
    grid_params: OccupancyParams,
    params: FloorplanParams = FloorplanParams(),
    n_points: int = 24,
    what: str = "the occupancy grid of the answer's plans",
    part: int = 0,
    parts: int = 1,
    all_scans: bool = True,
) -> Iterator[tuple[int, int, FloorPlan]]:
    """The answer's plan of the first k scans, for k in :func:`~floorscan.core.selection.curve_ks`
    (those of job ``part`` of ``parts``: :func:`answer_plan_ks`).

    Parameters
    ----------
    scans : list of (scan_id, origin, points)
        :func:`first_k_scans_points`, in rank order.
    segments_of : callable
        ``segments_of(points, grid)``: the wall segments (``x0, y0, x1, y1``, metres,
        optional ``n_inliers``) of wall points ((N, 2) float64, map metres) on their
        occupancy grid; the map extractor
        (:func:`floorscan.walls.map_lines.map_segments`) in the workflow.
    grid_params : OccupancyParams
        The occupancy grid of the scans (the map extractor's: cells of
        ``walls.map.support_cell_m``).
    params : FloorplanParams
    n_points : int
        Size of the k grid.
    what : str
        The grid and whose scans, for the error of a grid too large or of memory.
    part, parts : int
        The share of the k grid (:func:`answer_plan_ks`); by default all of it.
    all_scans : bool
        Whether the plan of all the scans (the last k) is built (:func:`answer_plan_ks`).

    Yields
    ------
    (k, n_wall_points, FloorPlan)
        In increasing k; a plan without walls when the first k scans have no wall point.
        Without rooms and doors: the answer curve scores the walls
        (:mod:`floorscan.score.answer_curve`), which depend on them only where a wall
        bounds no room.

    Raises
    ------
    floorscan.core.io.InputError
        Before the first grid, when the grid of all the scans would be too large
        (:func:`floorscan.core.grid.check_raster_size`) or the job's rasters
        (:data:`ANSWER_PLANS_MEMORY`) would not fit in the memory free on the machine.
    """
    ks = answer_plan_ks(len(scans), n_points, part, parts, all_scans)
    pairs = [(o, p) for _, o, p in scans]
    wall_points = np.cumsum([len(p) for _, p in pairs])  # of the first k scans, at k - 1
    points = np.concatenate([p.reshape(-1, 2) for _, p in pairs]) if pairs else np.empty((0, 2))  # rank order
    for k, grid in prefix_grids(pairs, ks, grid_params, what, ANSWER_PLANS_MEMORY):
        n = int(wall_points[k - 1])
        if grid is None:
            yield k, n, plan_of_segments(np.empty((0, 4)), None, params)
            continue
        yield k, n, ScanPlans(segments_of(points[:n], grid), params).plan(None, grid, with_rooms=False)


def write_answer_plans(
    scans: list[tuple[int, np.ndarray, np.ndarray]],
    segments_of: Callable[[np.ndarray, OccupancyGrid], pd.DataFrame],
    grid_params: OccupancyParams,
    params: FloorplanParams,
    folder: str | os.PathLike,
    metadata: Mapping[str, str] | None = None,
    n_points: int = 24,
    part: int = 0,
    parts: int = 1,
    all_scans: bool = True,
) -> list[dict]:
    """Write the plans of :func:`answer_plans` into ``folder``, one plan folder
    ``k<k>/`` each (:func:`~floorscan.floorplan.scans.write_plan`, the numbers as
    computed: these plans are scored, not exported), written whole or not at all.

    Parameters
    ----------
    scans, segments_of, grid_params, params, n_points, part, parts, all_scans
        As :func:`answer_plans`.
    folder : path
        ``evaluation/answer_plans``, or a job's share of it (replaced when it exists).
    metadata : mapping of str to str, optional
        What the plans are of (dataset, ordering), in every file; each plan adds
        ``k``, ``n_scans`` and :data:`N_WALL_POINTS`.

    Returns
    -------
    list of dict
        Per k: ``k``, ``n_wall_points``, ``n_walls``, ``n_faces``.
    """
    from floorscan.core.files import staged_path

    done = []
    dataset = (metadata or {}).get("dataset")
    what = f"the grids of the answer's plans of the first k of {len(scans)} scans" + (
        f" of dataset {dataset!r}" if dataset else "")
    with staged_path(folder) as tmp:
        tmp.mkdir()
        for k, n, plan in answer_plans(scans, segments_of, grid_params, params, n_points, what, part, parts, all_scans):
            write_plan(plan, Path(tmp) / f"k{k}", {**(metadata or {}), "extractor": "map", "k": str(k),
                                                   "n_scans": str(k), N_WALL_POINTS: str(n),
                                                   "rooms": "not segmented (the curve scores the walls)"},
                       rounded=False)  # fmt: skip
            done.append({"k": k, "n_wall_points": n, "n_walls": len(plan.walls), "n_faces": len(plan.faces)})
            log.info("the answer's plan of the first %d scans: %d wall points, %d walls, %d faces",
                     k, n, len(plan.walls), len(plan.faces))
    return done


def merge_answer_plans(
    parts: Iterable[str | os.PathLike], folder: str | os.PathLike, all_scans: str | os.PathLike | None = None
) -> list[int]:
    """Move the plan folders ``k<k>/`` of the jobs' shares (:func:`write_answer_plans`
    with ``part``) into ``folder``, and copy in the plan of all the scans as its last k,
    whole or not at all; the files are not rewritten.

    Parameters
    ----------
    parts : iterable of path
        The shares' folders; they are left without their plan folders.
    folder : path
        ``evaluation/answer_plans`` (replaced when it exists).
    all_scans : path, optional
        The plan folder of all the kept scans (rule ``all_scans_floorplan``,
        :func:`~floorscan.floorplan.scans.write_plan`), whose metadata ``n_scans``
        says how many they are, n: copied as ``k<n>/``. None: the shares hold every k.

    Returns
    -------
    list of int
        The ks, increasing.

    Raises
    ------
    ValueError
        When two shares hold the same k, a share holds a k of at least n, or the plan
        of all the scans does not say n.
    FileNotFoundError
        When the plan of all the scans is not a plan folder.
    """
    import shutil

    from floorscan.core.files import staged_path
    from floorscan.core.io import read_metadata

    plans = {}
    for share in parts:
        for sub in sorted(Path(share).glob("k*")):
            if sub.is_dir():
                if sub.name in plans:
                    raise ValueError(f"answer plans: {sub.name} is in {plans[sub.name].parent} and {share}")
                plans[sub.name] = sub
    if all_scans is not None:
        source = Path(all_scans)
        if not (source / "walls.parquet").is_file():
            raise FileNotFoundError(f"answer plans: {source} is not the plan folder of all the kept scans")
        n = read_metadata(source / "walls.parquet").get("n_scans", "")
        if not n.isdigit():
            raise ValueError(f"answer plans: {source / 'walls.parquet'}, the plan of all kept scans, does not say how "
                             "many they are (metadata n_scans); run rule all_scans_floorplan again")
        n = int(n)
        above = [name for name in plans if int(name[1:]) >= n]
        if above:
            raise ValueError(f"answer plans: {above[0]} in {plans[above[0]].parent} is not below all {n} kept scans")
    with staged_path(folder) as tmp:
        tmp.mkdir()
        for name, sub in plans.items():
            sub.rename(Path(tmp) / name)
        if all_scans is not None:
            shutil.copytree(source, Path(tmp) / f"k{n}", ignore=shutil.ignore_patterns(".*"))  # not Snakemake's marks
            plans[f"k{n}"] = source
    return sorted(int(name[1:]) for name in plans)
