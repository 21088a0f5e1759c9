"""The rigid-motion property of the plan on seeds the tests do not use (issue 44, item 4).

Run: ``.venv/bin/python -m benchmarks properties [--seeds 7 8] [--poses 300]``

``tests/test_plan_properties.py`` runs the property on one fixed seed (numpy seed 44,
:data:`TEST_SEED`) and allows the wrong poses measured there, so that a change that makes
the plan less stable fails. A change made to pass those poses need not make the plan any
more stable on others; this benchmark draws the same kind of cases from other seeds and
prints, per seed, the poses on which the plan differs:

- a building of :func:`floorscan.sim.generated.room_grid_building` (:func:`seeded_building`:
  1-3 x 1-2 rooms of 2-3.5 m, a door in every inner wall, half of them on a 1/8 m
  lattice) drawn as a map (:func:`map_plan`) at its own pose and turned by a random
  angle, mirrored or not and shifted by a fraction of a cell (:func:`pose_errors`);
- wrong when the counts of walls, rooms or doors differ, or a room of the moved plan,
  mapped back, lies farther than :data:`ROOM_TOLERANCE_M` from its room;
- the wrong poses are counted by kind: a wall more or fewer (rooms and doors the same),
  a room or a door more or fewer, a room moved.

The helpers are the tests' (``tests/test_plan_properties.py`` imports them from here).
The measurements are in ``benchmarks/README.md``.
"""

from __future__ import annotations

import argparse
import logging
import math
import time

import numpy as np
import shapely

from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.scans import plan_of_scans
from floorscan.sim.footprint import building_outline
from floorscan.sim.generated import moved, room_grid_building
from floorscan.sim.occupancy_map import MAP_RESOLUTION_M, building_map
from floorscan.walls.map_stage import map_of_grid

#: The seed of the tests' seeded cases (``tests/test_plan_properties.py``).
TEST_SEED = 44
#: A room of the moved plan, mapped back, lies within this Hausdorff distance of its
#: room at the building's own pose, metres. Issue 44 asks for one cell; each plan traces
#: its rooms on its own cells and cuts them at its doors, and turned maps put rooms 0.15
#: to 0.3 m apart (``benchmarks/README.md``), so five cells.
ROOM_TOLERANCE_M = 5 * MAP_RESOLUTION_M


def counts(plan) -> tuple[int, int, int]:
    """The plan's counts of walls, rooms and doors."""
    return len(plan.walls), len(plan.rooms), len(plan.doors)


def quiet(f, *args):
    """``f(*args)`` with the plan's INFO logging off."""
    logging.disable(logging.INFO)
    try:
        return f(*args)
    finally:
        logging.disable(logging.NOTSET)


def map_plan(b, shift_xy=(0.0, 0.0)):
    """The plan of the building's map, its cells' corner ``shift_xy`` (metres) past a
    whole cell 1 m below and left of the building."""
    x0, y0 = (math.floor(v / MAP_RESOLUTION_M) * MAP_RESOLUTION_M - 1.0 for v in building_outline(b).bounds[:2])
    grid = building_map(b, furniture=False, origin_xy=(x0 + shift_xy[0], y0 + shift_xy[1]))
    return quiet(plan_of_scans, map_of_grid(grid, None), None, FloorplanParams(), grid)


def seeded_building(rng) -> tuple:
    """A seeded building's key of :func:`room_grid_building`: half of them with sizes and
    doors on a 1/8 m lattice, whose faces lie on the map cells' edges."""
    n_x, n_y = int(rng.integers(1, 4)), int(rng.integers(1, 3))
    w, d, doors = rng.uniform(2.0, 3.5, n_x), rng.uniform(2.0, 3.5, n_y), rng.uniform(0, 1, 7)
    if rng.integers(2):
        w, d, doors = np.round(w * 8) / 8, np.round(d * 8) / 8, np.round(doors * 8) / 8
    return tuple(w.tolist()), tuple(d.tolist()), tuple(doors.tolist())


def back(geom, theta: float, mirror: bool):
    """``geom`` of :func:`~floorscan.sim.generated.moved` (no shift) mapped back."""
    c, s = math.cos(theta), math.sin(theta)
    inv = np.array([[c, -s], [s, c]])

    def f(p):
        q = p @ inv
        if mirror:
            q[:, 0] = -q[:, 0]
        return q

    return shapely.transform(geom, f)


def pose_errors(rng) -> tuple[tuple, float]:
    """One seeded building and pose: (its pose and the counts at its own pose and
    moved, the largest distance of a moved room to its room; NaN when a count differs)."""
    b = room_grid_building(*seeded_building(rng))
    theta, mirror = float(rng.uniform(0, 2 * math.pi)), bool(rng.integers(2))
    shift = tuple(float(v) for v in rng.uniform(0, MAP_RESOLUTION_M, 2))
    ref, got = map_plan(b), map_plan(moved(b, theta, mirror), shift)
    far = math.nan
    if counts(ref) == counts(got):
        rooms = list(ref.rooms["polygon"])
        far = max((min(back(p, theta, mirror).hausdorff_distance(r) for r in rooms) for p in got.rooms["polygon"]),
                  default=0.0)
    return (round(theta, 3), mirror, counts(ref), counts(got)), far


def kind(case: tuple, far: float) -> str:
    """``walls`` (a wall more or fewer, rooms and doors the same), ``rooms or doors``,
    ``room moved`` or ``right``, for a case and distance of :func:`pose_errors`."""
    (_, _, ref, got), moved_far = case, far
    if ref == got:
        return "room moved" if moved_far > ROOM_TOLERANCE_M else "right"
    return "walls" if ref[1:] == got[1:] else "rooms or doors"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks properties", description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[7, 8], help="numpy seeds (the tests use 44)")
    ap.add_argument("--poses", type=int, default=300, help="buildings and poses per seed")
    args = ap.parse_args(argv)
    kinds = ("walls", "rooms or doors", "room moved")
    print(f"{'seed':>5} {'poses':>6} {'wrong':>6} " + " ".join(f"{k:>15}" for k in kinds) + "   time")
    for seed in args.seeds:
        rng = np.random.default_rng(seed)
        t0 = time.perf_counter()
        wrong = []
        for i in range(args.poses):
            case, far = pose_errors(rng)
            k = kind(case, far)
            if k != "right":
                wrong.append((i, k, case, None if math.isnan(far) else round(far, 3)))
        by = [sum(w[1] == k for w in wrong) for k in kinds]
        note = " (the tests' seed)" if seed == TEST_SEED else ""
        print(f"{seed:>5} {args.poses:>6} {len(wrong):>6} " + " ".join(f"{n:>15}" for n in by)
              + f" {time.perf_counter() - t0:6.1f} s{note}")
        for i, k, (theta, mirror, ref, got), far in wrong:
            extra = f", room {far} m off" if far is not None else ""
            print(f"      pose {i}: {k}: turned {theta} rad{', mirrored' if mirror else ''}, "
                  f"walls/rooms/doors {ref} -> {got}{extra}")
