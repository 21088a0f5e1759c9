"""A reference plan drawn by people: a floor plan image (free space white, walls and
the outside any other shade; e.g. the test maps of ipa_room_segmentation, Bormann et
al., ICRA 2016), aligned to the recording's map frame by a similarity transform and
used to score a floor plan's walls (rule ``score_drawn``).

- :func:`drawn_faces`: the drawn wall faces, the free pixels next to a non-free one
  (the boundary of the drawn free space), in pixels.
- :func:`align_drawn`: the similarity transform (rotation, scale, translation) that
  puts them on the reference map's structure (:mod:`floorscan.core.occupancy`): a
  coarse search over rotation and scale, the translation of each by FFT
  cross-correlation of the two rasterised point sets (SciPy; a branch and bound with
  the exhaustive search's answer, :mod:`floorscan.score.correlative`), then trimmed
  ICP with Umeyama's closed-form similarity (Umeyama, "Least-squares estimation of
  transformation parameters between two point patterns", PAMI 1991); or, from at least
  two control points (pixel -> map metres), Umeyama on them, refined the same way. The
  residual is the distance from the structure cells near a drawn face to the nearest
  drawn face (median and 90th percentile, metres).
- :func:`score_against_drawn`: completeness (the drawn faces the recording saw, within
  ``seen_m`` of its free space, that lie within tau of the plan's faces) and
  correctness (the plan's face length within tau of a drawn face) at 10 and 20 cm.
- The rooms drawn by people (the dataset's ``reference: rooms``, a segmentation in the
  drawing's pixel frame) are scored with the same transform in
  :mod:`floorscan.score.drawn_rooms`.

Only what the recording saw is scored: a drawing may hold rooms the robot never
entered (intel's does).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Similarity:
    """``x_map = scale * R(angle) @ (col, -row) + (tx, ty)``: pixel (col, row) to the map
    frame, metres; angle in radians."""

    scale: float
    angle: float
    tx: float
    ty: float

    def invert(self, xy: np.ndarray) -> np.ndarray:
        """Map points to image pixels: the inverse of :meth:`apply`.

        Parameters
        ----------
        xy : (N, 2) float ndarray
            Map metres.

        Returns
        -------
        (N, 2) float64 ndarray
            Pixels (col, row).
        """
        c, s = math.cos(self.angle), math.sin(self.angle)
        p = ((np.asarray(xy, dtype=np.float64) - np.array([self.tx, self.ty])) / self.scale) @ np.array([[c, -s], [s, c]])
        return np.column_stack([p[:, 0], -p[:, 1]])

    def apply(self, px: np.ndarray) -> np.ndarray:
        """Image pixels to map points.

        Parameters
        ----------
        px : (N, 2) float ndarray
            Pixels (col, row).

        Returns
        -------
        (N, 2) float64 ndarray
            Map metres.
        """
        p = np.column_stack([px[:, 0], -px[:, 1]]).astype(np.float64)
        c, s = math.cos(self.angle), math.sin(self.angle)
        return self.scale * (p @ np.array([[c, s], [-s, c]])) + np.array([self.tx, self.ty])


def read_plan_image(path, grey: bool = True) -> np.ndarray:
    """The grey levels of a plan image (PNG, grey or colour): the mean of its colour
    channels.

    Parameters
    ----------
    path : path
    grey : bool
        False: the image as read, an alpha channel kept.

    Returns
    -------
    (H, W) or (H, W, C) float32 ndarray
        In [0, 1]; (H, W) with ``grey``.

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not an image matplotlib reads.
    """
    import matplotlib.image as mpimg

    from floorscan.core.io import InputError

    try:
        img = mpimg.imread(str(path))
    except (OSError, ValueError, SyntaxError) as e:
        raise InputError(f"{path}: not an image of a drawn plan ({e})") from None
    img = np.asarray(img, dtype=np.float32)
    if grey and img.ndim == 3:
        img = img[..., :3].mean(axis=2)
    if img.max() > 1.0:
        img = img / 255.0
    return img


def drawn_faces(image: np.ndarray, free_level: float = 0.98) -> tuple[np.ndarray, np.ndarray]:
    """The drawn wall faces: white pixels (grey level above ``free_level``) with a
    non-white 4-neighbour.

    Parameters
    ----------
    image : (H, W) float ndarray
        Grey levels in [0, 1] (:func:`read_plan_image`).
    free_level : float

    Returns
    -------
    faces : (N, 2) float64 ndarray
        (col, row) of each face pixel.
    free : (H, W) bool ndarray
        The drawn free space.
    """
    from scipy import ndimage

    free = image > free_level
    edge = free & ~ndimage.binary_erosion(free, structure=np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], bool))
    rows, cols = np.nonzero(edge)
    return np.column_stack([cols, rows]).astype(np.float64), free


def umeyama(src: np.ndarray, dst: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Least-squares similarity ``dst ~ s R src + t`` of 2D point pairs (Umeyama 1991).

    Parameters
    ----------
    src, dst : (N, 2) float ndarray
        Matching points.

    Returns
    -------
    scale : float
        1 when ``src`` has no spread.
    angle : float
        Radians.
    translation : (2,) float64 ndarray
    """
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    a, b = src - mu_s, dst - mu_d
    cov = b.T @ a / len(src)
    u, sig, vt = np.linalg.svd(cov)
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    r = u @ d @ vt
    var = (a * a).sum() / len(src)
    s = float(np.trace(np.diag(sig) @ d) / var) if var > 0 else 1.0
    return s, math.atan2(r[1, 0], r[0, 0]), mu_d - s * (r @ mu_s)


def _flip(px: np.ndarray) -> np.ndarray:
    return np.column_stack([px[:, 0], -px[:, 1]])


def align_drawn(
    faces_px: np.ndarray,
    structure_xy: np.ndarray,
    resolution_m: float = 0.05,
    control_points=None,
    scale_range: float = 0.15,
    angle_step_deg: float = 3.0,
) -> tuple[Similarity, dict]:
    """The similarity transform of the drawn faces onto the reference map's structure.

    Parameters
    ----------
    faces_px : (N, 2) float ndarray
        :func:`drawn_faces`, pixels.
    structure_xy : (M, 2) float ndarray
        The reference map's structure cells, map metres.
    resolution_m : float
        The drawing's nominal metres per pixel; the search spans it +- ``scale_range``.
    control_points : sequence of (col, row, x_m, y_m), optional
        At least two pairs: the start instead of the search.
    scale_range : float
    angle_step_deg : float

    Returns
    -------
    transform : Similarity
    info : dict
        ``residual_median_m``, ``residual_p90_m`` (structure cells within 0.5 m of a
        drawn face, to the nearest one), ``n_residual``, ``scale_m_per_px``,
        ``angle_deg``, ``start`` (search or control points).

    Raises
    ------
    ValueError
        With fewer than two control points, or no face or structure point.
    """
    from scipy.spatial import cKDTree

    if len(faces_px) == 0 or len(structure_xy) == 0:
        raise ValueError("alignment of a drawn plan: no drawn face or no structure cell")
    tree = cKDTree(structure_xy)
    src = _flip(np.asarray(faces_px, dtype=np.float64))
    if control_points:
        cp = np.asarray(control_points, dtype=np.float64).reshape(-1, 4)
        if len(cp) < 2:
            raise ValueError("a drawn plan's control_points need at least two [col, row, x_m, y_m] pairs")
        s, a, t = umeyama(_flip(cp[:, :2]), cp[:, 2:])
        start = "control points"
    else:
        s, a, t = _coarse_search(src, structure_xy, resolution_m, scale_range, angle_step_deg)
        start = "search"
    for bound in (1.0, 0.6, 0.4, 0.3, 0.2, 0.2, 0.15, 0.15, 0.1, 0.1):
        c, sn = math.cos(a), math.sin(a)
        moved = s * (src @ np.array([[c, sn], [-sn, c]])) + t
        d, idx = tree.query(moved, distance_upper_bound=bound)
        ok = np.isfinite(d)
        if ok.sum() < 10:
            break
        s, a, t = umeyama(src[ok], structure_xy[idx[ok]])
    transform = Similarity(s, a, float(t[0]), float(t[1]))
    faces_map = transform.apply(np.asarray(faces_px, dtype=np.float64))
    d, _ = cKDTree(faces_map).query(structure_xy, distance_upper_bound=0.5)
    near = d[np.isfinite(d)]
    info = {
        "residual_median_m": float(np.median(near)) if len(near) else math.nan,
        "residual_p90_m": float(np.percentile(near, 90)) if len(near) else math.nan,
        "n_residual": int(len(near)), "n_structure": int(len(structure_xy)),
        "scale_m_per_px": float(s), "angle_deg": math.degrees(a), "tx_m": float(t[0]), "ty_m": float(t[1]),
        "start": start,
    }  # fmt: skip
    return transform, info


def _coarse_search(src, dst, resolution_m, scale_range, angle_step_deg, cell_m: float = 0.2):
    """Rotation and scale on a grid (9 scales, ``angle_step_deg`` steps), the translation
    of each by FFT cross-correlation of the rasterised points
    (:func:`floorscan.score.correlative.correlative_search`): the best score's
    (scale, angle, translation)."""
    from scipy import fft

    from floorscan.score.correlative import correlative_search

    lo = dst.min(axis=0) - 2.0
    src = src[:: max(1, len(src) // 20000)]  # enough points for a coarse score
    src_c = src - src.mean(axis=0)
    extent = max(np.ptp(dst, axis=0).max(), np.ptp(src_c, axis=0).max() * resolution_m * (1 + scale_range)) + 8.0
    n = int(fft.next_fast_len(int(math.ceil(2 * extent / cell_m))))
    scales = resolution_m * np.linspace(1 - scale_range, 1 + scale_range, 9)
    angles = [math.radians(deg) for deg in np.arange(0.0, 360.0, angle_step_deg)]
    scale, a, shift, _ = correlative_search(src_c, dst, scales, angles, cell_m, origin=lo, size=n)
    c, s = math.cos(a), math.sin(a)
    t = shift - scale * (src.mean(axis=0) @ np.array([[c, s], [-s, c]]))
    return scale, a, t


def drawn_area(free: np.ndarray, transform: Similarity, margin_m: float = 0.5):
    """A test of map points: inside the drawn building (its free space grown by
    ``margin_m``, so its walls count).

    Parameters
    ----------
    free : (H, W) bool ndarray
        The drawn free space (:func:`drawn_faces`).
    transform : Similarity
        Pixels -> map metres.
    margin_m : float
        Metres.

    Returns
    -------
    callable
        ``(N, 2)`` map metres -> ``(N,)`` bool; False off the image.
    """
    from scipy import ndimage

    r = max(1, int(round(margin_m / transform.scale)))
    yy, xx = np.mgrid[-r : r + 1, -r : r + 1]
    inside = ndimage.binary_dilation(free, structure=(xx * xx + yy * yy) <= r * r)

    def test(xy: np.ndarray) -> np.ndarray:
        px = np.floor(transform.invert(xy) + 0.5).astype(np.int64)
        ok = (px[:, 0] >= 0) & (px[:, 1] >= 0) & (px[:, 0] < inside.shape[1]) & (px[:, 1] < inside.shape[0])
        out = np.zeros(len(xy), dtype=bool)
        out[ok] = inside[px[ok, 1], px[ok, 0]]
        return out

    return test


def score_against_drawn(
    faces: np.ndarray, drawn_xy: np.ndarray, seen: np.ndarray, taus_m=(0.10, 0.20), sample_m: float = 0.02,
    in_drawing=None,
) -> dict:
    """A plan's wall faces against the aligned drawn faces.

    Parameters
    ----------
    faces : (F, 4) float ndarray
        The plan's faces, map metres.
    drawn_xy : (N, 2) float ndarray
        The drawn faces in the map frame (:meth:`Similarity.apply`), metres.
    seen : (N,) bool ndarray
        Which drawn face points the recording saw.
    taus_m : tuple of float
    sample_m : float
        Spacing of the plan's face samples, metres.
    in_drawing : callable, optional
        :func:`drawn_area`: correctness counts only the plan inside the drawn building
        (a drawing of part of a floor says nothing of the rest).

    Returns
    -------
    dict
        ``completeness_<t>cm``, ``correctness_<t>cm``, ``f1_<t>cm``, ``n_seen``.
    """
    from scipy.spatial import cKDTree

    from floorscan.core.geometry import sample_segments
    from floorscan.score.nearest import nearest_distances

    faces = np.asarray(faces, dtype=np.float64).reshape(-1, 4)
    samples = sample_segments(faces, sample_m) if len(faces) else np.empty((0, 2))
    if in_drawing is not None and len(samples):
        samples = samples[in_drawing(samples)]
    d_plan = cKDTree(drawn_xy).query(samples)[0] if len(samples) else np.empty(0)
    d_drawn = nearest_distances(drawn_xy[seen], faces) if len(faces) and seen.any() else np.full(int(seen.sum()), np.inf)
    return _completeness_correctness(d_drawn, d_plan, taus_m)


def score_points_against_drawn(
    points: np.ndarray, drawn_xy: np.ndarray, seen: np.ndarray, taus_m=(0.10, 0.20), in_drawing=None
) -> dict:
    """Points (the reference map's structure cells) against the aligned drawn faces, as
    :func:`score_against_drawn` scores a plan's face samples: how close the recording's
    own map comes to the drawing, the bound of any plan built from it under this
    alignment.

    Parameters
    ----------
    points : (P, 2) float ndarray
        Map metres.
    drawn_xy, seen, taus_m, in_drawing
        As :func:`score_against_drawn`.

    Returns
    -------
    dict
        As :func:`score_against_drawn`.
    """
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if in_drawing is not None and len(points):
        points = points[in_drawing(points)]
    if not len(points):
        return _completeness_correctness(np.full(int(seen.sum()), np.inf), np.empty(0), taus_m)
    d_plan = cKDTree(drawn_xy).query(points)[0]
    d_drawn = cKDTree(points).query(drawn_xy[seen])[0]
    return _completeness_correctness(d_drawn, d_plan, taus_m)


def _completeness_correctness(d_drawn: np.ndarray, d_plan: np.ndarray, taus_m) -> dict:
    """Completeness (drawn points within tau of the plan), correctness (plan samples
    within tau of the drawing) and F1 at each tau, from the two distance arrays."""
    out = {"n_seen": len(d_drawn)}
    for tau in taus_m:
        cm = f"{round(tau * 100):d}cm"
        comp = float((d_drawn <= tau).mean()) if len(d_drawn) else math.nan
        corr = float((d_plan <= tau).mean()) if len(d_plan) else math.nan
        out[f"completeness_{cm}"], out[f"correctness_{cm}"] = comp, corr
        out[f"f1_{cm}"] = 2 * comp * corr / (comp + corr) if comp + corr > 0 else 0.0
    return out


def seen_by_recording(points: np.ndarray, grid, within_m: float = 0.5) -> np.ndarray:
    """Which map points lie within ``within_m`` of a cell the recording's rays crossed
    more often than they hit it (its free space).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Map metres.
    grid : OccupancyGrid
        The reference map.
    within_m : float
        Metres.

    Returns
    -------
    (N,) bool ndarray
        False outside the grid.
    """
    from scipy import ndimage

    r = max(1, int(round(within_m / grid.resolution_m)))
    yy, xx = np.mgrid[-r : r + 1, -r : r + 1]
    free = (grid.n_miss_scans > grid.n_hit_scans) & (grid.n_miss_scans > 0)
    near_free = ndimage.binary_dilation(free, structure=(xx * xx + yy * yy) <= r * r)
    rows, cols, inside = grid.cells_of(points)
    out = np.zeros(len(points), dtype=bool)
    out[inside] = near_free[rows[inside], cols[inside]]
    return out


def score_drawn_plans(plans: dict, image_path, grid, reference_cfg) -> tuple["pd.DataFrame", dict, dict]:
    """Rule ``score_drawn``: the drawn plan ``image_path`` aligned to the reference map
    ``grid`` (:func:`align_drawn`; ``reference_cfg`` the dataset's ``reference``:
    ``resolution_m``, ``control_points``) and every plan of ``plans`` (``{name:
    plan folder}``) scored against it (:func:`score_against_drawn`).

    Parameters
    ----------
    plans : dict of str to path
        Name -> the plan's folder (:func:`floorscan.score.answer.plan_parts`: its
        merged faces are scored).
    image_path : path
        The drawn plan (PNG).
    grid : OccupancyGrid
        The reference map.
    reference_cfg : mapping or None
        The dataset's ``reference`` section.

    Returns
    -------
    table : pandas.DataFrame
        One row per plan: ``plan`` and the scores; a last row ``reference_map``, the
        reference map's structure cells (:func:`score_points_against_drawn`), the bound.
    alignment : dict
        :func:`align_drawn`'s info.
    overlay : dict
        What the overlay figure draws: ``drawn_xy`` (N, 2) and ``seen`` (N,), the
        structure cells, each plan's faces; and ``transform``, the
        :class:`Similarity` (pixels -> map metres) the drawn rooms are scored with
        (:func:`floorscan.score.drawn_rooms.score_drawn_rooms`: one alignment for both).

    Raises
    ------
    floorscan.core.io.InputError
        When the image cannot be read.
    FileNotFoundError
        When a plan's folder is not a plan folder.
    """
    import pandas as pd

    from floorscan.score.answer import plan_parts

    cfg = dict(reference_cfg or {})
    faces_px, free = drawn_faces(read_plan_image(image_path))
    structure = grid.cell_centres(grid.structure())
    transform, info = align_drawn(faces_px, structure, float(cfg.get("resolution_m", 0.05)), cfg.get("control_points"))
    drawn_xy = transform.apply(faces_px)
    seen = seen_by_recording(drawn_xy, grid)
    inside = drawn_area(free, transform)
    rows, plan_faces = [], {}
    aligned = {f"alignment_{k}": v for k, v in info.items() if k != "start"}
    for name, folder in plans.items():
        plan_faces[name] = plan_parts(folder)["faces"]
        rows.append({"plan": name, **score_against_drawn(plan_faces[name], drawn_xy, seen, in_drawing=inside), **aligned})
    # the bound: the recording's own map (every kept scan's structure) under this alignment
    rows.append({"plan": "reference_map", **score_points_against_drawn(structure, drawn_xy, seen, in_drawing=inside),
                 **aligned})  # fmt: skip
    overlay = {"drawn_xy": drawn_xy, "seen": seen, "structure": structure, "faces": plan_faces, "transform": transform}
    return pd.DataFrame(rows), info, overlay
