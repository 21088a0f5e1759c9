"""The rooms of a segmentation drawn by people (ipa_room_segmentation's ground-truth
maps, Bormann et al., ICRA 2016), and a floor plan's rooms scored against them on the
drawing's pixels (rule ``score_drawn``).

- :func:`drawn_rooms`, :func:`read_drawn_rooms`: each white region between the drawn
  lines is one room (flood-fill by ``scipy.ndimage.label``).
- :func:`score_drawn_rooms`: the plan's rooms put on the drawing with the drawn plan's
  alignment (:func:`floorscan.score.drawn.align_drawn`, the same pixel frame), a pixel
  belonging to a plan room when its centre lies inside it (pixel-exact IoU), then
  scored by :func:`floorscan.score.segmentation.segmentation_scores` (the IoU-0.5
  matching, and Bormann's figures without regions of 100 pixels or fewer). Only the part of a plan
  room on the drawn floor (:func:`drawn_floor`) is scored: inside the drawn building
  (:func:`drawn_building`), since a drawing may show part of the building the
  recording saw (freiburg101's ends at the hall's west end), as the walls' correctness
  is scored inside the drawing only; and not on the drawn walls, which are no room's
  floor, as the room benchmark scores a segmentation on the pixels its reference
  labels (``benchmarks/bench_rooms.py``). A region of the building the drawing gives
  no room stays scored, so a plan room there counts against precision.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from floorscan.score.rooms import (
    ROOM_SCORE_COLUMNS,
    SEEN_SHARE,
    SEEN_WITHIN_M,
    read_plan_folder_rooms,
    score_row,
)
from floorscan.score.segmentation import MIN_REGION_PX, segmentation_scores

#: A region of a drawn segmentation is a room when a disc this wide fits in it ...
DRAWN_MIN_WIDTH_M = 0.5
#: ... and its area is at least this, m2 (smaller: a sliver between two drawn lines).
DRAWN_MIN_AREA_M2 = 1.0
#: The drawn walls are at most this thick, metres: the drawn building is its rooms
#: closed over them (:func:`drawn_building`).
DRAWN_WALL_M = 0.4
#: Grey level above which a pixel of a drawn segmentation is white (a room's).
DRAWN_FREE_LEVEL = 0.98


def drawn_rooms(image: np.ndarray, free_level: float = DRAWN_FREE_LEVEL, min_width_px: float = 10.0,
                min_area_px: float = 400.0) -> np.ndarray:  # fmt: skip
    """The rooms of a segmentation drawn by people: each white region is one room.

    Lines drawn across the free space (doors closed) part the rooms. The near-white
    pixels (every channel above ``free_level``) are labelled by 4-connectivity
    (``scipy.ndimage.label``); regions touching the image border (the outside), narrower
    than ``min_width_px`` (no disc that wide fits: a sliver between two lines) or
    smaller than ``min_area_px`` are dropped. The format of ipa_room_segmentation's
    ground-truth maps (Bormann et al., ICRA 2016).

    Parameters
    ----------
    image : (H, W) or (H, W, C) float ndarray
        Grey levels or colours in [0, 1] (an alpha channel is ignored).
    free_level : float
    min_width_px, min_area_px : float
        Pixels (:data:`DRAWN_MIN_WIDTH_M`, :data:`DRAWN_MIN_AREA_M2` at the drawing's scale).

    Returns
    -------
    (H, W) int32 ndarray
        0 outside every room, rooms 1..n in raster order of their first pixel.
    """
    from scipy import ndimage

    img = np.asarray(image, dtype=np.float64)
    white = (img[..., :3].min(axis=2) if img.ndim == 3 else img) > free_level
    labels, n = ndimage.label(white)
    if n == 0:
        return labels.astype(np.int32)
    idx = np.arange(1, n + 1)
    area = ndimage.sum_labels(white, labels, idx)
    width = 2 * ndimage.maximum(ndimage.distance_transform_edt(white), labels, idx)
    border = np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])
    keep = (area >= min_area_px) & (width >= min_width_px) & ~np.isin(idx, border)
    new = np.zeros(n + 1, dtype=np.int32)
    new[idx[keep]] = np.arange(1, int(keep.sum()) + 1, dtype=np.int32)
    return new[labels]


def read_drawn_rooms(path, scale_m_per_px: float) -> np.ndarray:
    """:func:`drawn_rooms` of the image at ``path`` (PNG, read in colour by
    :func:`floorscan.score.drawn.read_plan_image`), the width and area limits in metres
    converted to pixels.

    Parameters
    ----------
    path : path
    scale_m_per_px : float
        Metres per pixel.

    Returns
    -------
    (H, W) int32 ndarray
        As :func:`drawn_rooms`: 0 outside every room, rooms 1..n.

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not an image matplotlib reads.
    """
    from floorscan.score.drawn import read_plan_image

    return drawn_rooms(read_plan_image(path, grey=False), min_width_px=DRAWN_MIN_WIDTH_M / scale_m_per_px,
                       min_area_px=DRAWN_MIN_AREA_M2 / scale_m_per_px**2)  # fmt: skip


def drawn_building(labels: np.ndarray, wall_px: float) -> np.ndarray:
    """The building a drawn segmentation shows: its rooms closed over the drawn walls
    with the holes filled.

    Parameters
    ----------
    labels : (H, W) int ndarray
        Rooms > 0.
    wall_px : float
        Drawn wall thickness, pixels.

    Returns
    -------
    (H, W) bool ndarray
    """
    from scipy import ndimage

    r = max(1, int(math.ceil(wall_px)))
    rooms = np.pad(labels > 0, r)
    closed = ndimage.binary_closing(rooms, structure=np.ones((3, 3)), iterations=r)[r:-r, r:-r]
    return ndimage.binary_fill_holes(closed)


def drawn_floor(labels: np.ndarray, wall_px: float) -> np.ndarray:
    """The floor a drawn segmentation shows: the drawn building (:func:`drawn_building`)
    without its drawn walls, that is its rooms' pixels and the pixels farther than a
    drawn wall's thickness from every room (a region the drawing leaves without a room).
    Parameters and returns as :func:`drawn_building`."""
    from scipy import ndimage

    rooms = labels > 0
    return drawn_building(labels, wall_px) & (rooms | (ndimage.distance_transform_edt(~rooms) > wall_px))


def _plan_room_pixels(poly, transform, floor: np.ndarray) -> tuple[int, np.ndarray]:
    """The pixels of the drawing whose centres lie inside a plan room (map metres) and
    on the drawn ``floor`` ((H, W) bool, the drawing's shape, :func:`drawn_floor`):
    their count and their flat indices."""
    import shapely

    px = shapely.transform(poly, transform.invert)
    c0, r0, c1, r1 = px.bounds
    cols, rows = np.arange(math.floor(c0), math.ceil(c1) + 1), np.arange(math.floor(r0), math.ceil(r1) + 1)
    cc, rr = (a.ravel() for a in np.meshgrid(cols, rows))
    inside = shapely.contains_xy(px, cc.astype(np.float64), rr.astype(np.float64))
    cc, rr = cc[inside], rr[inside]
    h, w = floor.shape
    ok = (rr >= 0) & (cc >= 0) & (rr < h) & (cc < w)
    ok[ok] = floor[rr[ok], cc[ok]]
    return int(ok.sum()), rr[ok] * w + cc[ok]


def _label_outlines(labels: np.ndarray, transform) -> list:
    """Shapely polygons (map metres) of each room's outline, for drawing only: its
    longest contour, the others (a connected region's) its holes."""
    from shapely.geometry import Polygon
    from skimage.measure import find_contours

    out = []
    for k in range(1, int(labels.max()) + 1):
        contours = sorted(find_contours(np.pad(labels == k, 1).astype(np.float32), 0.5), key=len, reverse=True)
        rings = [transform.apply(c[:, ::-1] - 1.0) for c in contours if len(c) >= 4]  # (col, row), unpadded
        out.append(Polygon(rings[0], rings[1:]).buffer(0))
    return out


def score_drawn_rooms(plans: dict, labels: np.ndarray, transform, grid) -> tuple[pd.DataFrame, dict]:
    """Every plan's rooms against a drawn segmentation, on the drawing's pixels.

    Parameters
    ----------
    plans : dict
        ``{name: folder}`` of plan folders (:func:`floorscan.score.rooms.read_plan_folder_rooms`).
    labels : (H, W) int ndarray
        :func:`drawn_rooms` (0 no room, rooms 1..T).
    transform : floorscan.score.drawn.Similarity
        Pixel (col, row) -> map metres (:func:`floorscan.score.drawn.align_drawn`).
    grid : floorscan.core.occupancy.OccupancyGrid
        The reference map: a drawn room counts when the recording saw
        :data:`SEEN_SHARE` of its pixels (:func:`floorscan.score.drawn.seen_by_recording`).

    Returns
    -------
    table : pandas.DataFrame
        One row per plan, :data:`ROOM_SCORE_COLUMNS` (``truth`` ``drawn``; door scores
        NaN: the drawing marks no doors).
    overlay : dict
        What :func:`floorscan.figures.rooms.rooms_overlay_figure` draws.
    """
    from floorscan.score.drawn import seen_by_recording

    labels = np.asarray(labels)
    n = int(labels.max())
    flat = labels.ravel()
    true_area = np.bincount(flat, minlength=n + 1)[1:].astype(np.float64)
    rows_px, cols_px = np.nonzero(labels)
    seen = seen_by_recording(transform.apply(np.column_stack([cols_px, rows_px]).astype(np.float64)), grid, SEEN_WITHIN_M)
    seen_px = np.bincount(labels[rows_px, cols_px], weights=seen, minlength=n + 1)[1:]
    counted = np.divide(seen_px, true_area, out=np.zeros(n), where=true_area > 0) >= SEEN_SHARE
    overlay = {"truth": "drawn", "true_rooms": _label_outlines(labels, transform), "counted": counted,
               "true_doors_xy": np.empty((0, 2)), "true_doors_counted": np.zeros(0, bool),
               "structure": grid.cell_centres(grid.structure()), "plans": {}}  # fmt: skip
    rows = []
    floor = drawn_floor(labels, DRAWN_WALL_M / transform.scale)
    for name, folder in plans.items():
        rooms, doors = read_plan_folder_rooms(folder)
        plan_area = np.zeros(len(rooms))
        inter = np.zeros((n, len(rooms)))
        for j, poly in enumerate(rooms["polygon"]):
            plan_area[j], idx = _plan_room_pixels(poly, transform, floor)
            inter[:, j] = np.bincount(flat[idx], minlength=n + 1)[1:]
        scores, detail = segmentation_scores(inter, true_area, plan_area, counted, MIN_REGION_PX)
        rows.append(score_row(name, "drawn", scores, {"n_plan_doors": len(doors)}))
        overlay["plans"][name] = {"rooms": list(rooms["polygon"]), "doors_xy": doors[["x", "y"]].to_numpy(np.float64),
                                  "rooms_detail": detail}  # fmt: skip
    table = pd.DataFrame(rows, columns=ROOM_SCORE_COLUMNS)
    overlay["scores"] = table
    return table, overlay
