"""The answer's plans of the first k scans, built once by the floorplan stage and scored by
the score stage (issue 46, item 2): the same curve as building each k's grid and plan
anew from the points."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from floorscan.core.occupancy import OccupancyParams, occupancy_grid
from floorscan.core.plan_tables import read_plan_tables
from floorscan.core.selection import curve_ks
from floorscan.floorplan.answer_plans import answer_plans, write_answer_plans
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import build_floorplan
from floorscan.score.against_reference import Structure, plan_against_reference
from floorscan.score.answer_curve import answer_curve
from floorscan.walls.map_lines import MapParams, map_segments
from test_reference import _scans

MAP = MapParams()
GRID = OccupancyParams(resolution_m=MAP.support_cell_m)
POSES = [(1.5, 1.5, 0.0), (5.0, 1.2, 0.4), (8.5, 3.0, 2.0), (3.0, 3.5, -1.0), (8.0, 5.0, 3.0), (6.5, 4.0, 1.2),
         (2.5, 2.0, 2.5), (9.0, 1.0, -2.0)]


def segments_of(points, grid):
    return map_segments(points, grid, MAP, seed=0)


@pytest.fixture(scope="module")
def scans():
    """(scan_id, origin, points) in rank order: the first scan without a wall point, the
    second seeing the right part of the room only."""
    room = _scans(POSES)
    room[0] = (room[0][0], room[0][1][room[0][1][:, 0] > 3.0])
    return [(10, np.array([5.0, 3.0]), np.empty((0, 2)))] + [(i, o, p) for i, (o, p) in enumerate(room)]


def test_the_answer_plans_are_the_plans_built_anew(scans):
    """Each k's plan from the incremental grids equals the plan of the map extractor's
    segments on the grid of the first k scans built from their points, walls, faces,
    clutter and junctions, without its rooms; k = 1 (no wall point) is a plan without
    walls."""
    ks = curve_ks(len(scans), 6)
    got = list(answer_plans(scans, segments_of, GRID, FloorplanParams(), n_points=6))
    assert [k for k, _, _ in got] == ks and ks[0] == 1 and ks[-1] == len(scans) == 9
    for k, n, plan in got:
        pairs = [(o, p) for _, o, p in scans[:k]]
        assert n == sum(len(p) for _, p in pairs)
        if n == 0:
            assert plan.walls.empty and plan.faces.empty
            continue
        grid = occupancy_grid(pairs, GRID)
        want = build_floorplan(segments_of(np.concatenate([p for _, p in pairs]), grid), FloorplanParams(), grid)
        for part in ("walls", "faces", "clutter", "junctions"):
            pd.testing.assert_frame_equal(getattr(plan, part), getattr(want, part), check_exact=True)
        assert len(plan.walls) >= 4
        # the curve scores the walls: the rooms the full plan has are not segmented
        assert plan.rooms.empty and plan.doors.empty and len(want.rooms) >= 1


def test_the_score_stage_scores_the_plans_as_built(scans, tmp_path):
    """The curve read from the plan folders is the curve of the plans in memory, to the
    last bit (the answer's plans keep their numbers as computed); the plan folders hold
    k, the scans and the wall points in their metadata."""
    from floorscan.core.io import read_metadata

    folder = tmp_path / "answer_plans"
    done = write_answer_plans(scans, segments_of, GRID, FloorplanParams(), folder, {"dataset": "room"}, n_points=6)
    reference = Structure(occupancy_grid([(o, p) for _, o, p in scans[1:]], OccupancyParams()))
    curve = answer_curve(folder, reference)
    assert curve["k"].tolist() == [d["k"] for d in done] == curve_ks(len(scans), 6)
    assert curve["n_walls"].tolist() == [d["n_walls"] for d in done]
    first = curve.iloc[0]
    assert first["k"] == 1 and first["n_walls"] == 0 and first["f1_5cm"] == 0.0 and math.isnan(first["correctness_5cm"])
    for (k, n, plan), row in zip(answer_plans(scans, segments_of, GRID, FloorplanParams(), n_points=6), curve.itertuples()):
        meta = read_metadata(folder / f"k{k}" / "walls.parquet")
        assert meta["k"] == str(k) and meta["n_wall_points"] == str(n) and meta["dataset"] == "room"
        if n:
            m = plan_against_reference(plan.faces[["x0", "y0", "x1", "y1"]].to_numpy(np.float64), reference, (0.05,))
            assert (row.f1_5cm, row.completeness_5cm, row.correctness_5cm) == (
                m["f1_5cm"], m["completeness_5cm"], m["correctness_5cm"])
            stored = read_plan_tables(folder / f"k{k}", ("faces",))["faces"]
            np.testing.assert_array_equal(stored[["x0", "y0", "x1", "y1"]].to_numpy(), plan.faces[["x0", "y0", "x1", "y1"]].to_numpy())
    assert curve["f1_5cm"].iloc[-1] > 0.8


def test_a_folder_without_plans_is_refused(tmp_path):
    with pytest.raises(FileNotFoundError, match="answer's plans"):
        answer_curve(tmp_path / "missing", None)


def test_the_parts_of_the_k_grid_make_the_same_plans(scans, tmp_path):
    """Two jobs' shares of the k grid are disjoint, together the whole grid, balanced by
    their scans; their plans, merged into one folder, are the files of one job's plans
    byte for byte."""
    from floorscan.floorplan.answer_plans import answer_plan_ks, merge_answer_plans

    for n in (1, 2, 9, 815, 5000):
        shares = [answer_plan_ks(n, 24, p, 2) for p in range(2)]
        assert sorted(shares[0] + shares[1]) == curve_ks(n, 24) and not set(shares[0]) & set(shares[1])
        if n > 100:
            assert abs(sum(shares[0]) - sum(shares[1])) <= max(curve_ks(n, 24)) / 2
    with pytest.raises(ValueError, match="part 2 of 2"):
        answer_plan_ks(9, 6, 2, 2)
    whole = tmp_path / "whole"
    write_answer_plans(scans, segments_of, GRID, FloorplanParams(), whole, {"dataset": "room"}, n_points=6)
    parts = [tmp_path / f"part{p}" for p in range(2)]
    for p, folder in enumerate(parts):
        done = write_answer_plans(scans, segments_of, GRID, FloorplanParams(), folder, {"dataset": "room"}, n_points=6,
                                  part=p, parts=2)
        assert [d["k"] for d in done] == answer_plan_ks(len(scans), 6, p, 2)
    merged = tmp_path / "answer_plans"
    assert merge_answer_plans(parts, merged) == curve_ks(len(scans), 6)
    files = sorted(f.relative_to(whole) for f in whole.rglob("*") if f.is_file())
    assert files == sorted(f.relative_to(merged) for f in merged.rglob("*") if f.is_file()) and files
    for f in files:
        assert (whole / f).read_bytes() == (merged / f).read_bytes(), f
    write_answer_plans(scans, segments_of, GRID, FloorplanParams(), parts[0], n_points=6, part=0, parts=1)
    write_answer_plans(scans, segments_of, GRID, FloorplanParams(), parts[1], n_points=6, part=0, parts=1)
    with pytest.raises(ValueError, match="k1"):  # both shares hold every k
        merge_answer_plans(parts, tmp_path / "twice")


def test_the_last_k_is_the_plan_of_all_the_scans_copied_in(scans, tmp_path):
    """The workflow's shares leave out the last k (all the scans); the merge copies in the
    plan of all the scans as that k, so the folder is the whole curve's, file for file
    (a plan folder's hidden marks are not copied)."""
    from floorscan.floorplan.answer_plans import answer_plan_ks, merge_answer_plans

    for n in (1, 2, 9, 815, 5000):
        shares = [answer_plan_ks(n, 24, p, 2, all_scans=False) for p in range(2)]
        assert sorted(shares[0] + shares[1]) == curve_ks(n, 24)[:-1] and not set(shares[0]) & set(shares[1])
    n = len(scans)
    whole = tmp_path / "whole"
    write_answer_plans(scans, segments_of, GRID, FloorplanParams(), whole, {"dataset": "room"}, n_points=6)
    (whole / f"k{n}" / ".snakemake_timestamp").touch()
    parts = [tmp_path / f"part{p}" for p in range(2)]
    for p, folder in enumerate(parts):
        done = write_answer_plans(scans, segments_of, GRID, FloorplanParams(), folder, {"dataset": "room"}, n_points=6,
                                  part=p, parts=2, all_scans=False)
        assert n not in [d["k"] for d in done]
    merged = tmp_path / "answer_plans"
    assert merge_answer_plans(parts, merged, whole / f"k{n}") == curve_ks(n, 6)
    files = sorted(f.relative_to(whole) for f in whole.rglob("*") if f.is_file() and not f.name.startswith("."))
    assert files == sorted(f.relative_to(merged) for f in merged.rglob("*") if f.is_file()) and len(files) >= 4 * 4
    for f in files:
        assert (whole / f).read_bytes() == (merged / f).read_bytes(), f
    # a share that holds the last k, or no plan folder of all the scans, is refused
    write_answer_plans(scans, segments_of, GRID, FloorplanParams(), parts[0], n_points=6, part=0, parts=1)
    with pytest.raises(ValueError, match=f"k{n} .* not below all {n} kept scans"):
        merge_answer_plans(parts[:1], tmp_path / "again", whole / f"k{n}")
    with pytest.raises(FileNotFoundError, match="not the plan folder of all"):
        merge_answer_plans([], tmp_path / "again", tmp_path / "missing")
    from floorscan.core.io import read_table, write_table

    unsaid = tmp_path / "unsaid"
    unsaid.mkdir()
    write_table(read_table(whole / f"k{n}" / "walls.parquet"), unsaid / "walls.parquet")  # without the metadata
    with pytest.raises(ValueError, match="does not say how many they are"):
        merge_answer_plans([], tmp_path / "again", unsaid)
    assert not (tmp_path / "again").exists()
