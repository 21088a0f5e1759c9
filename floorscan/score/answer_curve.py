"""The quality curve of the answer's floor plan: the plan the answer is made with (the
map extractor and the structure passes) of the first k scans of the default ordering,
against the reference map, for k on a geometric grid (rule ``answer_curve``).

The thesis's quality curves (thesis Fig. 5.8; :mod:`floorscan.score.curves`) score the
per-scan extractors' plans of every ordering on a dense grid; this curve scores the plan
a user gets, so its k95 and k99 (the first k whose plan reaches 95 / 99 % of the F1 of
the plan of all kept scans) are what the automatic k (``select.k: auto``) is measured
against. The plans are built once, by the floorplan stage
(:mod:`floorscan.floorplan.answer_plans`, ``evaluation/answer_plans/k<k>/``; the last k
is the plan of all kept scans, the one rule ``all_scans_floorplan`` builds); this module
reads their tables and scores them.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.core.plan_tables import N_WALL_POINTS


def plan_folders(folder: str | os.PathLike) -> list[tuple[int, Path]]:
    """The plan folders ``k<k>/`` of ``evaluation/answer_plans``, in increasing k.

    Parameters
    ----------
    folder : path

    Returns
    -------
    list of (int, Path)

    Raises
    ------
    FileNotFoundError
        When ``folder`` is not a folder.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder}: no folder of the answer's plans")
    found = [(int(p.name[1:]), p) for p in folder.iterdir() if p.is_dir() and p.name[:1] == "k" and p.name[1:].isdigit()]
    return sorted(found)


def answer_curve(plans: str | os.PathLike, reference) -> pd.DataFrame:
    """F1, completeness and correctness at 5 cm against the reference map of the
    answer's plan of the first k scans, for every k the floorplan stage built.

    Parameters
    ----------
    plans : path
        ``evaluation/answer_plans`` (:func:`floorscan.floorplan.answer_plans.write_answer_plans`):
        a plan folder ``k<k>/`` per k, with the wall points of its scans in the
        metadata (:data:`N_WALL_POINTS`).
    reference : OccupancyGrid or Structure
        The reference map.

    Returns
    -------
    pandas.DataFrame
        ``k``, ``n_walls``, ``completeness_5cm``, ``correctness_5cm``, ``f1_5cm``, one row
        per k; a k whose scans have no wall point has completeness and F1 0,
        correctness NaN.

    Raises
    ------
    FileNotFoundError
        When ``plans`` is not a folder of plan folders.
    """
    from floorscan.core.io import read_metadata
    from floorscan.core.plan_tables import plan_faces_and_walls
    from floorscan.score.against_reference import Structure, plan_against_reference

    folders = plan_folders(plans)
    structure = reference if isinstance(reference, Structure) else Structure(reference)
    rows = []
    for k, folder in folders:
        if int(read_metadata(folder / "walls.parquet").get(N_WALL_POINTS, "1")) == 0:
            rows.append({"k": k, "n_walls": 0, "completeness_5cm": 0.0, "correctness_5cm": np.nan, "f1_5cm": 0.0})
            continue
        faces, n_walls = plan_faces_and_walls(folder)
        m = plan_against_reference(faces, structure, (0.05,))
        rows.append({"k": k, "n_walls": n_walls, "completeness_5cm": m["completeness_5cm"],
                     "correctness_5cm": m["correctness_5cm"], "f1_5cm": m["f1_5cm"]})  # fmt: skip
    return pd.DataFrame(rows, columns=["k", "n_walls", "completeness_5cm", "correctness_5cm", "f1_5cm"])
