"""Rooms (and walls) of the floor plan on the room segmentation benchmarks of
``../shared/data/room-maps/`` (its README: the data and the metric definitions).

For every map the plan is built as a map is a recording (issue 43):
:func:`floorscan.ingest.occupancy_map.read_occupancy_map` (5 cm a pixel, origin 0; a
Bormann map through a yaml of :data:`READINGS`, by default as ipa's evaluation reads it),
:func:`floorscan.walls.map_stage.map_of_grid`, then
:func:`floorscan.floorplan.scans.plan_of_scans` with the default
:class:`~floorscan.floorplan.params.FloorplanParams`; the time per map is of these three.
``--walls-seed N`` seeds the map extractor's RANSAC with N instead of its default
(``walls.seed``): on a noisy map the plan depends on the draws. Several seeds print
each seed's tables, the groups' means per seed and over the seeds
(:func:`print_seed_means`), and each map's room precision and recall over the seeds
(:func:`print_map_spread`).
Its rooms are rasterised on the map's pixels (a pixel is a room's when its centre lies
inside the room's polygon; the grid's row 0 is the image's bottom row) and scored by
:func:`floorscan.score.segmentation.score_label_images`: Bormann's per-room mean and
pooled precision and recall, room precision and recall at IoU 0.5 and the mean IoU of
the matched rooms, regions of 100 pixels or fewer dropped on either side.

A segmentation is scored on the pixels the reference labels as rooms
(:func:`on_reference`), as the published ones are: ipa's segmentations label the map's
free pixels, which are the pixels its references label, and ROSE^2's evaluation
(declutter-reconstruct, ``code/util/evaluation.py``) counts a segment's pixels only where
the reference labels a room, as its segmentation images here hold them. The plan's
rooms are polygons up to the wall faces, holding the floor under furniture and unseen
corners, which no reference labels; scored whole, each room would be charged with them.
The whole polygons' figures are printed beside (``whole_`` keys).

- ``bormann``: the 20 maps of Bormann et al. (ICRA 2016) without furniture
  (``<name>.png``) and with it (``<name>_furnitures.png``), against
  ``<name>_gt_segmentation.png`` read as ipa's ``evaluation_segmentation.cpp`` reads
  it (:func:`~floorscan.score.segmentation.label_drawn_regions`: grey above 250,
  8-connected white regions).
- ``rose2``: the 5 real robot maps of ROSE^2 (Luperto et al., RA-L 2022) against
  ``<name>_gt.png`` (one colour per room, black none; compared on the common top-left
  part), with ROSE^2's own ``<name>_rose2.png`` scored by the same code beside.

Walls (issue 43, item 4): on each Bormann map, the faces of the plan of
``<name>_furnitures.png`` against the walls of ``<name>.png``, and, as the bound with
nothing in the way, the faces of the plan of ``<name>.png`` against the same walls. The
walls of ``<name>.png`` are its wall cells that face its rooms
(:func:`reference_wall_cells`: :func:`floorscan.walls.map_stage.wall_cells`, the
occupied cells facing the free space, next to the free space opened as the room step
opens it, so that the borders of a ray seen through a window into the unknown are no
wall), at their centres: that is what a wall is in a map (the layer of occupied cells
the free space looks at), it is the same building's, independent of any plan (the
plan of the furniture-free map would score its own faults as the truth's), and it is
what the map extractor fits the plan's faces on. Completeness is the share of those
cells within tau of a plan face, correctness the share of the plan's face length
within tau of one (:func:`floorscan.score.drawn.score_against_drawn`), at 5 and 10 cm.

``python -m benchmarks rooms [--maps NAME ...] [--out DIR] [--workers 2] [--no-figures] [--rooms plan|layout]
[--reading ipa|map_server]``:
a table per map, the averages per group, the published figures beside them, why the
rooms left unmatched are (:func:`print_errors`), and one figure per map (``--out``,
default ``results/bench_rooms/``: the map, the rooms people drew, floorscan's rooms with
its plan's walls, doors and clutter, ROSE^2's rooms where there are any).
"""
from __future__ import annotations

import argparse
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data" / "room-maps"
BORMANN = ["Freiburg101_scan", "Freiburg52_scan", "Freiburg79_scan", "NLB", "lab_a_scan", "lab_b_scan", "lab_c_scan",
           "lab_d_scan", "lab_f_scan", "lab_intel", "lab_ipa", "office_a", "office_b", "office_c", "office_d",
           "office_e", "office_f", "office_g", "office_h", "office_i"]  # fmt: skip
ROSE2 = ["freiburg_building52", "g4s_y2", "map15", "photo_2020-01-08_09-53-31", "map_with_clutter"]
GROUPS = {"bormann": "Bormann, no furniture", "bormann_furniture": "Bormann, furniture", "rose2": "ROSE^2 real maps"}
FIGURES = ["seg_precision_mean", "seg_precision_pooled", "seg_recall_mean", "seg_recall_pooled",
           "room_precision", "room_recall", "room_mean_iou"]  # fmt: skip
HEAD = ["P mean", "P pool", "R mean", "R pool", "room P", "room R", "mIoU"]
WALL_TAUS_M = (0.05, 0.10)
#: Published averages (per-room mean precision / recall, per cent), with their source.
PUBLISHED = [
    ("rose2", "ROSE^2 (11 real maps)", 89.0, 93.9), ("rose2", "ipa morphological (11 real maps)", 85.0, 82.3),
    ("rose2", "ipa distance (11 real maps)", 88.3, 79.8), ("rose2", "ipa Voronoi (11 real maps)", 85.9, 71.9),
    ("bormann", "ROSE^2", 93.3, 97.6), ("bormann_furniture", "ROSE^2", 93.5, 91.0),
]  # fmt: skip
PUBLISHED_SOURCE = ("Luperto et al., RA-L 2022 (ROSE^2), as quoted in ../shared/data/room-maps/README.md; "
                    "Bormann et al.'s own table (ICRA 2016) of ipa's four methods on the 20 maps was not "
                    "found in the material searched, so it is not printed")  # fmt: skip


def tasks(maps: list[str] | None) -> list[tuple[str, str]]:
    """``(group, name)`` of every map present, ``bormann`` covering both its images."""
    out = [("bormann", n) for n in BORMANN] + [("rose2", n) for n in ROSE2]
    return [t for t in out if not maps or t[1] in maps]


def read_image(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path))


#: How a Bormann map is read (``--reading``): ``ipa``, as ipa_room_segmentation's
#: evaluation binarises its maps (a pixel above 250 free, every other pixel an
#: obstacle, the grey walls of lab_a, office_b, office_d, lab_intel and Freiburg52
#: included); ``map_server``, the map_server defaults of
#: :mod:`floorscan.ingest.occupancy_map` (grey 205-211 reads free, 90-204 unknown).
READINGS = {"ipa": {"occupied_thresh": 4.6 / 255, "free_thresh": 4.5 / 255}, "map_server": None}


def map_path(image: Path, reading: str | None, folder: Path) -> Path:
    """``image`` itself, or a map_server yaml in ``folder`` that reads it as ``reading``
    (:data:`READINGS`) says."""
    thresholds = READINGS.get(reading) if reading else None
    if not thresholds:
        return image
    folder.mkdir(parents=True, exist_ok=True)
    yml = folder / f"{image.stem}.yaml"
    yml.write_text(f"image: {image.resolve()}\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
                   f"occupied_thresh: {thresholds['occupied_thresh']!r}\nfree_thresh: {thresholds['free_thresh']!r}\n")
    return yml


def plan_labels(path: Path, rooms: str = "plan", walls_seed: int | None = None):
    """The plan of a map image (or of its map_server yaml) and its rooms on the image's pixels.

    ``rooms``: ``plan``, the plan's own rooms (the pipeline's room step,
    :mod:`floorscan.floorplan.rooms`); ``layout``, the rooms of the candidate global
    layout of issue 44 (:func:`floorscan.floorplan.layout.layout_plan_rooms` on the
    plan's walls, its clutter faces as hypotheses without evidence of their own, and
    the map's grid, whose own wall lines it adds), in the plan's place. ``walls_seed``:
    the map extractor's seed (config ``walls.seed``), its default when None.

    Returns
    -------
    labels : (H, W) int32 ndarray
        0 no room, plan room ``k`` (its row in ``plan.rooms``) ``k + 1``; image rows
        (row 0 the top).
    plan : floorscan.floorplan.plan.FloorPlan
    grid : floorscan.core.occupancy.OccupancyGrid
    seconds : float
        Read, walls and plan.
    """
    import shapely

    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.scans import plan_of_scans
    from floorscan.ingest.occupancy_map import read_occupancy_map
    from floorscan.walls.map_stage import map_of_grid

    t0 = time.perf_counter()
    grid = read_occupancy_map(path)[0]
    params = FloorplanParams()
    plan = plan_of_scans(map_of_grid(grid, None if walls_seed is None else {"seed": walls_seed}), None, params, grid)
    if rooms == "layout":
        from dataclasses import replace

        from floorscan.floorplan.layout import layout_plan_rooms

        table, doors = layout_plan_rooms(plan.walls[["x0", "y0", "x1", "y1"]].to_numpy(np.float64),
                                         plan.walls["thickness_m"].to_numpy(np.float64), grid, params.rooms,
                                         plan.clutter[["x0", "y0", "x1", "y1"]].to_numpy(np.float64))  # fmt: skip
        plan = replace(plan, rooms=table, doors=doors)
    seconds = time.perf_counter() - t0
    h, w = grid.shape
    r, (ox, oy) = grid.resolution_m, grid.origin_xy
    labels = np.zeros((h, w), dtype=np.int32)
    for k, poly in enumerate(plan.rooms["polygon"]):
        x0, y0, x1, y1 = poly.bounds
        cols = np.arange(max(0, math.floor((x0 - ox) / r)), min(w, math.ceil((x1 - ox) / r) + 1))
        rows = np.arange(max(0, math.floor((y0 - oy) / r)), min(h, math.ceil((y1 - oy) / r) + 1))
        cc, rr = np.meshgrid(cols, rows)
        inside = shapely.contains_xy(poly, ox + (cc + 0.5) * r, oy + (rr + 0.5) * r)
        labels[rr[inside], cc[inside]] = k + 1  # grid rows
    return labels[::-1], plan, grid, seconds


def reference_wall_cells(grid) -> np.ndarray:
    """(H, W) bool: the wall cells of a furniture-free map that face its rooms' space:
    :func:`~floorscan.walls.map_stage.wall_cells` next to the free space opened by a
    disc of :data:`~floorscan.floorplan.room_space.FREE_OPEN_M`, as the room step
    opens it (module docstring). The two borders of a ray seen through a window into
    the unknown beyond a wall (lab_ipa's fans, each a line of free cells a cell or two
    wide in the grey) face no room and are no wall."""
    from scipy import ndimage

    from floorscan.floorplan.room_space import FREE_OPEN_M, disc_opening
    from floorscan.walls.map_stage import MAP_SEAM_M, wall_cells

    rooms = disc_opening(grid.free(), FREE_OPEN_M / grid.resolution_m)
    # within the seam and a cell of the rooms, through walls too: a wall's outer face,
    # seen through a window, is the building's (wall_cells' own seam stops at walls)
    steps = int(round(MAP_SEAM_M / grid.resolution_m)) + 1
    return wall_cells(grid) & ndimage.binary_dilation(rooms, np.ones((3, 3), dtype=bool), iterations=steps)


def wall_scores(plan, reference_grid) -> dict:
    """The plan's faces against the wall cells of ``reference_grid`` (module docstring)."""
    from floorscan.score.drawn import score_against_drawn

    walls_xy = reference_grid.cell_centres(reference_wall_cells(reference_grid))
    faces = plan.faces[["x0", "y0", "x1", "y1"]].to_numpy(np.float64)
    out = score_against_drawn(faces, walls_xy, np.ones(len(walls_xy), dtype=bool), WALL_TAUS_M)
    return out | {"n_faces": len(faces), "n_clutter": len(plan.clutter)}


def score_one(group: str, name: str, image: Path, truth: np.ndarray, rooms: str = "plan",
              walls_seed: int | None = None):
    """The plan of one map image scored against ``truth`` (image rows): its row of
    figures, its room labels, its grid and the plan."""
    from floorscan.score.segmentation import score_label_images

    labels, plan, grid, seconds = plan_labels(image, rooms, walls_seed)
    row = {"group": group, "map": name, "seconds": seconds, "n_plan_rooms_all": len(plan.rooms)}
    row |= score_label_images(truth, on_reference(truth, labels))
    row |= {f"whole_{k}": v for k, v in score_label_images(truth, labels).items()}
    return row, labels, grid, plan


def on_reference(truth: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """``labels`` on the pixels ``truth`` labels as a room (the module docstring).

    Parameters
    ----------
    truth, labels : (H, W) and (H', W') int ndarray
        0 no room; compared on their common top-left part.

    Returns
    -------
    (min(H, H'), min(W, W')) int ndarray
        ``labels`` there, 0 where ``truth`` is 0.
    """
    h, w = min(truth.shape[0], labels.shape[0]), min(truth.shape[1], labels.shape[1])
    return np.where(truth[:h, :w] > 0, labels[:h, :w], 0)


def run_task(task: tuple[str, str], data: Path = DATA, out: Path | None = None, rooms: str = "plan",
             reading: str = "ipa", walls_seed: int | None = None) -> list[dict]:
    """Every figure of one map (a Bormann map: both its images), and its figure in ``out``.

    Returns
    -------
    list of dict
        One row per plan scored: ``group``, ``map``, ``seconds``, the
        :func:`~floorscan.score.segmentation.score_label_images` figures (``rose2_`` of
        ROSE^2's own segmentation), ``walls_*`` (Bormann maps).
    """
    from floorscan.score.segmentation import grey_of_image, label_colours, label_drawn_regions, score_label_images

    import tempfile

    group, name = task
    rows, panels = [], []
    if group == "bormann":
        folder = data / "bormann"
        truth = label_drawn_regions(grey_of_image(read_image(folder / f"{name}_gt_segmentation.png")))
        with tempfile.TemporaryDirectory() as tmp:
            clean_map, furn_map = (map_path(folder / f"{name}{s}.png", reading, Path(tmp)) for s in ("", "_furnitures"))
            clean, clean_labels, clean_grid, clean_plan = score_one("bormann", name, clean_map, truth, rooms,
                                                                    walls_seed)
            furn, furn_labels, furn_grid, furn_plan = score_one("bormann_furniture", name, furn_map, truth, rooms,
                                                                walls_seed)
        clean |= {f"walls_{k}": v for k, v in wall_scores(clean_plan, clean_grid).items()}
        furn |= {f"walls_{k}": v for k, v in wall_scores(furn_plan, clean_grid).items()}
        rows += [clean, furn]
        panels = [(f"{name}.png", folder / f"{name}.png", None), ("drawn by people", None, truth),
                  ("floorscan, no furniture", None, clean_labels, clean_plan, clean_grid),
                  (f"{name}_furnitures.png", folder / f"{name}_furnitures.png", None),
                  ("floorscan, furniture", None, furn_labels, furn_plan, furn_grid)]  # fmt: skip
    else:
        folder = data / "rose2"
        truth = label_colours(read_image(folder / f"{name}_gt.png"))
        row, labels, grid, plan = score_one("rose2", name, folder / f"{name}.png", truth, rooms, walls_seed)
        rose = label_colours(read_image(folder / f"{name}_rose2.png"))
        row |= {f"rose2_{k}": v for k, v in score_label_images(truth, on_reference(truth, rose)).items()}
        rows.append(row)
        panels = [(f"{name}.png", folder / f"{name}.png", None), ("drawn by people", None, truth),
                  ("floorscan", None, labels, plan, grid), ("ROSE^2", None, rose)]  # fmt: skip
    if out is not None:
        write_figure(out / f"{group}_{name}.png", panels, truth, rows)
    return rows


def write_figure(path: Path, panels, truth: np.ndarray, rows: list[dict]) -> None:
    """The panels of one map: maps in grey, segmentations one colour per room (regions
    of 100 pixels or fewer left out, as scored), the drawn rooms' outlines in black over
    floorscan's and ROSE^2's rooms, and over floorscan's its plan's walls (red), doors
    (blue) and clutter (orange), from the plan and the grid that follow a panel's labels;
    cut to the part with rooms."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from floorscan.score.segmentation import grey_of_image

    from floorscan.score.segmentation import MIN_REGION_PX, relabel

    truth = relabel(truth, MIN_REGION_PX)
    h, w = truth.shape
    # the part of the image with any room, a margin round it
    rooms = truth > 0
    for _, _, labels, *_ in panels:
        if labels is not None:
            rooms[: labels.shape[0], : labels.shape[1]] |= labels[:h, :w] > 0
    rr, cc = np.nonzero(rooms) if rooms.any() else (np.array([0, h - 1]), np.array([0, w - 1]))
    r0, r1, c0, c1 = max(0, rr.min() - 10), min(h, rr.max() + 11), max(0, cc.min() - 10), min(w, cc.max() + 11)
    aspect = (c1 - c0) / max(1, r1 - r0)
    ncol = 2 if len(panels) == 4 else min(3, len(panels))
    nrow = -(-len(panels) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(ncol * 4.5, nrow * 4.5 / max(0.6, aspect) + 0.6), squeeze=False)
    cmap = plt.get_cmap("tab20")
    edge = np.zeros_like(truth, dtype=bool)
    edge[:-1] |= truth[:-1] != truth[1:]
    edge[:, :-1] |= truth[:, :-1] != truth[:, 1:]
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, (title, image, labels, *drawn) in zip(axes.ravel(), panels):
        if image is not None:
            ax.imshow(grey_of_image(read_image(image))[r0:r1, c0:c1], cmap="gray", vmin=0, vmax=255,
                      interpolation="nearest")  # fmt: skip
            ax.set_title(title, fontsize=9)
            continue
        labels = relabel(labels[:h, :w], MIN_REGION_PX)
        rgb = np.ones((*labels.shape, 3))
        rgb[labels > 0] = np.asarray(cmap((labels[labels > 0] * 7) % 20))[:, :3]
        if title != "drawn by people":  # the drawn rooms' outlines over the found ones
            rgb[edge[: labels.shape[0], : labels.shape[1]]] = 0.0
        ax.imshow(rgb[r0:r1, c0:c1], interpolation="nearest")
        ax.set_title(f"{title}: {int(labels.max())} rooms", fontsize=9)
        if drawn:  # the plan's lines in the image's pixels (row 0 the top), on the crop
            plan, grid = drawn
            (ox, oy), res = grid.origin_xy, grid.resolution_m
            for table, colour, width in ((plan.clutter, "orange", 0.5), (plan.walls, "red", 0.8),
                                         (plan.doors, "blue", 1.5)):  # fmt: skip
                xy = table[["x0", "y0", "x1", "y1"]].to_numpy(np.float64).reshape(-1, 2, 2)
                u, v = (xy[..., 0] - ox) / res - c0, grid.shape[0] - (xy[..., 1] - oy) / res - r0
                ax.plot(u.T, v.T, "-", color=colour, lw=width)
            ax.set_xlim(-0.5, c1 - c0 - 0.5)
            ax.set_ylim(r1 - r0 - 0.5, -0.5)
    scored = "; ".join(f"{r['group']}: P {r['seg_precision_mean']:.2f} R {r['seg_recall_mean']:.2f}, "
                       f"room P/R {r['room_precision']:.2f}/{r['room_recall']:.2f}" for r in rows)  # fmt: skip
    scored += "\nfloorscan's plan: walls red, doors blue, clutter orange"
    fig.suptitle(scored, fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, path)


def _fmt(v) -> str:
    return "  -  " if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:5.3f}"


def print_tables(rows: list[dict]) -> None:
    print(f"{'group':<18} {'map':<28} {'true':>4} {'found':>5} " + " ".join(f"{h:>6}" for h in HEAD) + "   time")
    for r in rows:
        print(f"{r['group']:<18} {r['map'][:28]:<28} {r['n_true_rooms']:>4d} {r['n_plan_rooms_scored']:>5d} "
              + " ".join(f"{_fmt(r[k]):>6}" for k in FIGURES) + f" {r['seconds']:5.1f} s")  # fmt: skip
        if "rose2_seg_precision_mean" in r:
            print(f"{'  ROSE^2':<18} {'':<28} {r['rose2_n_true_rooms']:>4d} {r['rose2_n_plan_rooms_scored']:>5d} "
                  + " ".join(f"{_fmt(r['rose2_' + k]):>6}" for k in FIGURES))  # fmt: skip
    print("\nAverages per group (mean over maps):")
    print(f"{'group':<24} {'method':<44} " + " ".join(f"{h:>6}" for h in HEAD) + "  time/map")
    for g, label in GROUPS.items():
        sub = [r for r in rows if r["group"] == g]
        if not sub:
            continue
        mean = {k: float(np.nanmean([r[k] for r in sub])) for k in FIGURES}
        secs = float(np.mean([r["seconds"] for r in sub]))
        print(f"{label:<24} {'floorscan (' + str(len(sub)) + ' maps)':<44} " + " ".join(f"{_fmt(mean[k]):>6}" for k in FIGURES)
              + f"  {secs:5.2f} s")  # fmt: skip
        whole = {k: float(np.nanmean([r["whole_" + k] for r in sub])) for k in FIGURES}
        print(f"{'':<24} {'floorscan, whole polygons':<44} " + " ".join(f"{_fmt(whole[k]):>6}" for k in FIGURES))
        if g == "rose2":
            rm = {k: float(np.nanmean([r["rose2_" + k] for r in sub])) for k in FIGURES}
            print(f"{'':<24} {'ROSE^2, scored here':<44} " + " ".join(f"{_fmt(rm[k]):>6}" for k in FIGURES))
        for pg, method, p, rc in PUBLISHED:
            if pg == g:
                print(f"{'':<24} {method + ', published':<44} {p / 100:6.3f} {'':>6} {rc / 100:6.3f}")
    print(f"Published figures: {PUBLISHED_SOURCE}.")
    print_errors(rows)
    walls = [r for r in rows if r["group"].startswith("bormann") and "walls_f1_5cm" in r]
    if walls:
        print("\nWalls of each Bormann map's plan against the wall cells of <name>.png (no furniture):")
        cols = [f"walls_{m}_{t}" for t in ("5cm", "10cm") for m in ("completeness", "correctness", "f1")]
        print(f"{'plan of':<18} {'map':<28} " + " ".join(f"{c[6:]:>17}" for c in cols) + "  faces clutter")
        for r in walls:
            print(f"{r['group']:<18} {r['map'][:28]:<28} " + " ".join(f"{_fmt(r[c]):>17}" for c in cols)
                  + f"  {r['walls_n_faces']:5d} {r['walls_n_clutter']:5d}")  # fmt: skip
        for g in ("bormann", "bormann_furniture"):
            sub = [r for r in walls if r["group"] == g]
            print(f"{g + ' mean':<18} {'':<28} " + " ".join(f"{_fmt(float(np.mean([r[c] for r in sub]))):>17}" for c in cols))


def print_errors(rows: list[dict]) -> None:
    """Why the rooms left unmatched at IoU 0.5 are unmatched, per map and summed per
    group (:func:`floorscan.score.segmentation.room_errors`): true rooms merged into a
    larger found room, split between found rooms, or left uncovered; found rooms that are a
    piece of one true room, span several, or lie where no room was drawn. ROSE^2's on
    its maps below each."""
    from floorscan.score.segmentation import PLAN_CAUSES, ROOM_ERROR_KEYS, TRUE_CAUSES

    print("\nUnmatched rooms: true rooms merged / split / uncovered; found rooms pieces / spanning / extra:")
    print(f"{'group':<22} {'map':<28} " + " ".join(f"{h:>9}" for h in TRUE_CAUSES + PLAN_CAUSES))
    for r in rows:
        print(f"{r['group']:<22} {r['map'][:28]:<28} " + " ".join(f"{r[k]:>9d}" for k in ROOM_ERROR_KEYS))
        if "rose2_n_true_merged" in r:
            print(f"{'  ROSE^2':<22} {'':<28} " + " ".join(f"{r['rose2_' + k]:>9d}" for k in ROOM_ERROR_KEYS))
    for g in GROUPS:
        sub = [r for r in rows if r["group"] == g]
        if sub:
            print(f"{g + ' sum':<22} {str(len(sub)) + ' maps':<28} " + " ".join(f"{sum(r[k] for r in sub):>9d}" for k in ROOM_ERROR_KEYS))
            if g == "rose2":
                print(f"{'  ROSE^2 sum':<22} {'':<28} " + " ".join(f"{sum(r['rose2_' + k] for r in sub):>9d}" for k in ROOM_ERROR_KEYS))


def main(argv: list[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(prog="python -m benchmarks rooms", description=__doc__.split("\n\n")[0])
    ap.add_argument("--maps", nargs="*", help="map names (e.g. lab_ipa map15); default every map")
    ap.add_argument("--out", type=Path, default=REPO / "results" / "bench_rooms", help="folder of the figures")
    ap.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    ap.add_argument("--no-figures", action="store_true")
    ap.add_argument("--rooms", choices=["plan", "layout"], default="plan",
                    help="plan: the pipeline's room step (default); layout: the candidate global layout of issue 44")
    ap.add_argument("--data", type=Path, default=DATA, help="the room-maps folder")
    ap.add_argument("--reading", choices=sorted(READINGS), default="ipa",
                    help="how a Bormann map is read: ipa (default; a pixel above 250 free, every other an obstacle, "
                         "as ipa's evaluation reads them) or map_server (its default thresholds)")
    ap.add_argument("--walls-seed", type=int, nargs="+", default=[None],
                    help="the map extractor's RANSAC seed (config walls.seed; default its default): the plan of a "
                         "noisy map depends on it; several seeds: each seed's tables, then the groups' figures "
                         "per seed and their mean over the seeds")
    args = ap.parse_args(argv or [])
    if not args.data.is_dir():
        print(f"skipped: {args.data} is absent (the shared room-maps data, see issue 43)")
        return []
    todo = tasks(args.maps)
    if not todo:
        raise SystemExit(f"no map named {args.maps}; known: {' '.join(BORMANN + ROSE2)}")
    by_seed = {}
    order = {g: i for i, g in enumerate(GROUPS)}
    for seed in args.walls_seed:
        out = None if args.no_figures else (args.out if len(args.walls_seed) == 1 else args.out / f"walls_seed_{seed}")
        if len(args.walls_seed) > 1:
            print(f"\n## map extractor seed {seed}\n")
        t0 = time.perf_counter()
        with ProcessPoolExecutor(max_workers=max(1, args.workers)) as pool:
            done = list(pool.map(run_task, todo, [args.data] * len(todo), [out] * len(todo), [args.rooms] * len(todo),
                                  [args.reading] * len(todo), [seed] * len(todo)))
        wall = time.perf_counter() - t0
        rows = by_seed[seed] = sorted((r for rs in done for r in rs), key=lambda r: order[r["group"]])
        print_tables(rows)
        print(f"\n{len(rows)} maps, {len(todo)} tasks in {wall:.1f} s with {args.workers} processes "
              f"(plans alone: {sum(r['seconds'] for r in rows):.1f} s of CPU time)" + (f"; figures in {out}" if out else ""))  # fmt: skip
    if len(by_seed) > 1:
        print_seed_means(by_seed)
        print_map_spread(by_seed)
    return [r for rows in by_seed.values() for r in rows]


def print_seed_means(by_seed: dict) -> None:
    """Each group's mean over its maps (:func:`print_tables`' averages) per seed of the map
    extractor, and their mean over the seeds: the figure a plan of a noisy map can be
    expected to reach, not one draw's."""
    print("\nAverages per group and seed of the map extractor (mean over maps), and their mean over the seeds:")
    print(f"{'group':<24} {'seed':<8} " + " ".join(f"{h:>6}" for h in HEAD))
    for g, label in GROUPS.items():
        means = []
        for seed, rows in by_seed.items():
            sub = [r for r in rows if r["group"] == g]
            if sub:
                means.append([float(np.nanmean([r[k] for r in sub])) for k in FIGURES])
                print(f"{label:<24} {str(seed):<8} " + " ".join(f"{_fmt(v):>6}" for v in means[-1]))
        if means:
            print(f"{label:<24} {'mean':<8} " + " ".join(f"{_fmt(v):>6}" for v in np.mean(means, axis=0)))


def print_map_spread(by_seed: dict) -> None:
    """Each map's room precision and recall at IoU 0.5 over the seeds of the map
    extractor: their mean, lowest and highest, and those of the first seed given: a
    rule accepted on one seed's plans shows there as a first seed at the top of its
    map's spread."""
    seeds = list(by_seed)
    print(f"\nRoom P / R per map over the map extractor's seeds {', '.join(str(s) for s in seeds)} "
          f"(mean; lowest; highest; seed {seeds[0]}):")
    print(f"{'group':<18} {'map':<30} {'mean':>13} {'lowest':>13} {'highest':>13} {'seed ' + str(seeds[0]):>13}")
    by_map: dict[tuple[str, str], list] = {}  # (group, map): (seed, room P, room R) in the seeds' order
    for seed, rows in by_seed.items():
        for r in rows:
            by_map.setdefault((r["group"], r["map"]), []).append((seed, r["room_precision"], r["room_recall"]))
    for (g, name), got in sorted(by_map.items(), key=lambda kv: list(GROUPS).index(kv[0][0])):
        pr = np.array([v[1:] for v in got], dtype=np.float64)
        cells = [np.nanmean(pr, axis=0), np.nanmin(pr, axis=0), np.nanmax(pr, axis=0)]
        cells += [v[1:] for v in got if v[0] == seeds[0]][:1]
        print(f"{g:<18} {name:<30} " + " ".join(f"{_fmt(p):>6}/{_fmt(r):<6}" for p, r in cells))
