"""Room segmentation scored against rooms drawn by people: one implementation of the
two room scores the project uses, from the intersection matrix of true and found rooms.

- Bormann's four figures (Bormann et al., "Room segmentation: survey, implementation,
  and analysis", ICRA 2016; ipa_room_segmentation's ``evaluation_segmentation.cpp``,
  ``EvaluationSegmentation::computePrecisionRecall``, which ROSE^2, Luperto et al.,
  RA-L 2022, uses too): regions of :data:`MIN_REGION_PX` pixels or fewer on either
  side are dropped; each found room's largest overlap with one true room, each true
  room's largest overlap with one found room; precision is the mean over found rooms
  of overlap / found area (``precision_micro`` in ipa's code, "per-room mean" here)
  and the sum of the overlaps over the found rooms' summed area (``precision_macro``,
  "pooled"); recall the same over the true rooms (:func:`bormann_scores`).
- The one-to-one matching of rooms whose IoU is at least 0.5, room precision, recall
  and mean IoU (:func:`match_rooms`: the Hungarian method on the IoU of the pairs
  at least :data:`ROOM_IOU`, SciPy's ``linear_sum_assignment``), and why each room
  left unmatched is (:func:`room_errors`: a true room merged into a larger one, split
  into pieces, or left uncovered; a plan room a piece of one true room, spanning
  several, or extra).

:func:`segmentation_scores` computes both from an intersection matrix (pixels or m2),
on the same rooms: the true rooms that count and the found rooms not left out of
precision. :func:`score_label_images` scores two label images directly (the common
top-left part when their shapes differ, as a drawing one pixel smaller than its map),
dropping the small regions first as ipa's code does. :func:`label_drawn_regions` and
:func:`label_colours` read the two conventions of drawn segmentations: white regions
between drawn lines (ipa's test maps), one colour per room (ROSE^2's).

A new figure of a segmentation is a key of :func:`segmentation_scores` (and, for the
evaluation's ``room_scores.csv``, a name in
:data:`floorscan.score.rooms.ROOM_SCORE_COLUMNS`).
"""

from __future__ import annotations

import math

import numpy as np

#: A found room and a true room match when their IoU is at least this (Bormann et al.).
ROOM_IOU = 0.5
#: A found room with at least this share of its area in true rooms that do not count is
#: left out of precision.
LEFT_OUT_SHARE = 0.5
#: An unmatched room is explained by where most of it lies (:func:`room_errors`): more
#: than this share of it in one room of the other side, or in rooms of it at all.
MOST = 0.5
#: The causes of :func:`room_errors`, a true room's and a plan room's, and the keys of
#: their counts (``n_true_<cause>``, ``n_plan_<cause>``).
TRUE_CAUSES, PLAN_CAUSES = ("merged", "split", "uncovered"), ("pieces", "spanning", "extra")
ROOM_ERROR_KEYS = tuple(f"n_true_{c}" for c in TRUE_CAUSES) + tuple(f"n_plan_{c}" for c in PLAN_CAUSES)
#: Regions of this many pixels or fewer, true or found, are not scored (ipa's code).
MIN_REGION_PX = 100
#: A pixel of a drawing of white regions between lines is white above this grey level,
#: of 255 (ipa's ``cv::threshold(gt_map, bw_map, 250, 255, THRESH_BINARY)``).
DRAWN_WHITE_ABOVE = 250
#: Bormann's four figures, the keys :func:`bormann_scores` returns.
BORMANN_KEYS = ("seg_precision_mean", "seg_precision_pooled", "seg_recall_mean", "seg_recall_pooled")


def bormann_scores(inter: np.ndarray, true_area: np.ndarray, found_area: np.ndarray, min_area: float = 0.0) -> dict:
    """Bormann's per-room mean and pooled precision and recall.

    Parameters
    ----------
    inter : (T, F) float ndarray
        Overlap of true room ``t`` and found room ``f`` (pixels or m2).
    true_area : (T,) float ndarray
    found_area : (F,) float ndarray
        Room areas, the same unit.
    min_area : float
        Rooms of this area or less, on either side, are dropped (ipa's code: 100
        pixels, :data:`MIN_REGION_PX`); the overlaps with them too.

    Returns
    -------
    dict
        :data:`BORMANN_KEYS`, each in [0, 1]; precision NaN without any found room,
        recall NaN without any true room.
    """
    inter = np.asarray(inter, dtype=np.float64).reshape(len(true_area), len(found_area))
    ta, fa = np.asarray(true_area, np.float64), np.asarray(found_area, np.float64)
    keep_t, keep_f = ta > min_area, fa > min_area
    inter, ta, fa = inter[np.ix_(keep_t, keep_f)], ta[keep_t], fa[keep_f]
    best_f = inter.max(axis=0) if len(ta) else np.zeros(len(fa))  # (F,) each found room's best overlap
    best_t = inter.max(axis=1) if len(fa) else np.zeros(len(ta))  # (T,)
    nan = math.nan
    return {
        "seg_precision_mean": float(np.mean(best_f / fa)) if len(fa) else nan,
        "seg_precision_pooled": float(best_f.sum() / fa.sum()) if len(fa) else nan,
        "seg_recall_mean": float(np.mean(best_t / ta)) if len(ta) else nan,
        "seg_recall_pooled": float(best_t.sum() / ta.sum()) if len(ta) else nan,
    }


def match_rooms(
    inter: np.ndarray, true_area: np.ndarray, plan_area: np.ndarray, counted: np.ndarray,
    min_iou: float = ROOM_IOU, left_out_share: float = LEFT_OUT_SHARE,
) -> tuple[dict, dict]:  # fmt: skip
    """Room precision, recall and mean IoU of a one-to-one matching by IoU.

    Parameters
    ----------
    inter : (T, P) float ndarray
        Intersection area of true room ``t`` and plan room ``p`` (any unit: m2, pixels).
    true_area : (T,) float ndarray
    plan_area : (P,) float ndarray
        Areas, the same unit.
    counted : (T,) bool ndarray
        The true rooms that count (:data:`SEEN_SHARE` of them seen).
    min_iou, left_out_share : float

    Returns
    -------
    scores : dict
        ``room_precision`` (matched / plan rooms scored; NaN without any),
        ``room_recall`` (matched / counted true rooms; NaN without any),
        ``room_mean_iou`` (of the matched pairs; NaN without any), ``n_true_rooms``
        (counted), ``n_true_rooms_all``, ``n_plan_rooms``, ``n_plan_rooms_scored``,
        ``n_matched_rooms``, and why the others are unmatched (:func:`room_errors`).
    detail : dict
        ``iou`` (T, P), ``pairs`` (K, 2) int (true, plan index), ``pair_iou`` (K,),
        ``left_out`` (P,) bool, ``true_cause`` (T,) and ``plan_cause`` (P,) str
        (:func:`room_errors`).
    """
    from scipy.optimize import linear_sum_assignment

    inter = np.asarray(inter, dtype=np.float64).reshape(len(true_area), len(plan_area))
    ta, pa = np.asarray(true_area, np.float64), np.asarray(plan_area, np.float64)
    counted = np.asarray(counted, dtype=bool)
    union = ta[:, None] + pa[None, :] - inter
    iou = np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)
    outside = inter[~counted].sum(axis=0)
    # left out of precision: mostly in true rooms that do not count, or nothing of it
    # where the truth is drawn (a plan room wholly outside a drawing that shows part of
    # the building)
    left_out = (np.divide(outside, pa, out=np.zeros_like(pa), where=pa > 0) >= left_out_share) | (pa <= 0)
    ti, pi = np.flatnonzero(counted), np.flatnonzero(~left_out)
    sub = iou[np.ix_(ti, pi)]
    # only pairs that count take part: the matching of the largest summed IoU among them
    rows, cols = linear_sum_assignment(np.where(sub >= min_iou, sub, 0.0), maximize=True)
    pairs = np.column_stack([ti[rows], pi[cols]]).astype(np.int64).reshape(-1, 2)
    pair_iou = iou[pairs[:, 0], pairs[:, 1]]
    keep = pair_iou >= min_iou
    pairs, pair_iou = pairs[keep], pair_iou[keep]
    k = len(pairs)
    scores = {
        "room_precision": k / len(pi) if len(pi) else math.nan,
        "room_recall": k / len(ti) if len(ti) else math.nan,
        "room_mean_iou": float(pair_iou.mean()) if k else math.nan,
        "n_true_rooms": len(ti), "n_true_rooms_all": len(ta), "n_plan_rooms": len(pa),
        "n_plan_rooms_scored": len(pi), "n_matched_rooms": k,
    }  # fmt: skip
    counts, true_cause, plan_cause = room_errors(inter, ta, pa, ti, pi, pairs)
    scores.update(counts)
    return scores, {"iou": iou, "pairs": pairs, "pair_iou": pair_iou, "left_out": left_out,
                    "true_cause": true_cause, "plan_cause": plan_cause}  # fmt: skip


def room_errors(inter: np.ndarray, true_area: np.ndarray, plan_area: np.ndarray, true_rooms: np.ndarray,
                plan_rooms: np.ndarray, pairs: np.ndarray) -> tuple[dict, np.ndarray, np.ndarray]:  # fmt: skip
    """Why the rooms that the matching leaves unmatched are unmatched, by where most
    (:data:`MOST`) of each lies.

    A true room is *merged* when one plan room holds most of it (the match fails on
    the plan room's other part: other rooms, or space, joined to it), *split* when the
    plan rooms hold most of it but none alone does, *uncovered* when they do not. A plan
    room is one of the *pieces* of a true room when most of it lies in that one (the
    rest of the room is elsewhere), *spanning* when most of it lies in true rooms but in none alone, *extra*
    when most of it lies in none (space no one drew as a room).

    Parameters
    ----------
    inter : (T, P) float ndarray
        Intersection areas (:func:`match_rooms`).
    true_area : (T,) float ndarray
    plan_area : (P,) float ndarray
    true_rooms, plan_rooms : int ndarray
        The true rooms that count and the plan rooms scored (indices).
    pairs : (K, 2) int ndarray
        The matched (true, plan) pairs.

    Returns
    -------
    counts : dict
        ``n_true_merged``, ``n_true_split``, ``n_true_uncovered``, ``n_plan_pieces``,
        ``n_plan_spanning``, ``n_plan_extra`` (ints; each side's three sum to its
        unmatched rooms).
    true_cause : (T,) object ndarray
        ``"merged"``, ``"split"`` or ``"uncovered"`` for each unmatched true room that
        counts, ``""`` for the others.
    plan_cause : (P,) object ndarray
        ``"pieces"``, ``"spanning"`` or ``"extra"`` for each unmatched plan room scored,
        ``""`` for the others.
    """
    inter = np.asarray(inter, dtype=np.float64)
    ta, pa = np.asarray(true_area, np.float64), np.asarray(plan_area, np.float64)
    true_rooms, plan_rooms = np.asarray(true_rooms, dtype=np.int64), np.asarray(plan_rooms, dtype=np.int64)
    ti = np.setdiff1d(true_rooms, pairs[:, 0])
    pi = np.setdiff1d(plan_rooms, pairs[:, 1])
    t_best = inter[np.ix_(ti, plan_rooms)].max(axis=1, initial=0.0)
    t_all = inter[np.ix_(ti, plan_rooms)].sum(axis=1)
    p_best = inter[np.ix_(true_rooms, pi)].max(axis=0, initial=0.0)
    p_all = inter[np.ix_(true_rooms, pi)].sum(axis=0)
    t_most, p_most = MOST * ta[ti], MOST * pa[pi]
    true_cause, plan_cause = np.full(len(ta), "", dtype=object), np.full(len(pa), "", dtype=object)
    true_cause[ti] = np.where(t_best > t_most, "merged", np.where(t_all > t_most, "split", "uncovered"))
    plan_cause[pi] = np.where(p_best > p_most, "pieces", np.where(p_all > p_most, "spanning", "extra"))
    counts = {f"n_{side}_{c}": int(np.count_nonzero(cause == c))
              for side, cause, causes in (("true", true_cause, TRUE_CAUSES), ("plan", plan_cause, PLAN_CAUSES))
              for c in causes}  # fmt: skip
    return counts, true_cause, plan_cause


def segmentation_scores(
    inter: np.ndarray, true_area: np.ndarray, found_area: np.ndarray, counted=None, min_area: float = 0.0,
) -> tuple[dict, dict]:  # fmt: skip
    """Bormann's four figures and the IoU-0.5 matching of a segmentation, on the same rooms.

    The matching is :func:`match_rooms` (true rooms that do not
    count, and found rooms mostly in them, out); Bormann's figures
    (:func:`bormann_scores`) are computed on the true rooms that count and the found
    rooms the matching scores.

    Parameters
    ----------
    inter : (T, F) float ndarray
        Overlap of true room ``t`` and found room ``f`` (pixels or m2).
    true_area : (T,) float ndarray
    found_area : (F,) float ndarray
    counted : (T,) bool ndarray, optional
        The true rooms that count; None: all.
    min_area : float
        Passed to :func:`bormann_scores` (the matching keeps every room).

    Returns
    -------
    scores : dict
        :func:`match_rooms`'s scores and :data:`BORMANN_KEYS`.
    detail : dict
        :func:`match_rooms`'s detail.
    """
    ta, fa = np.asarray(true_area, np.float64), np.asarray(found_area, np.float64)
    inter = np.asarray(inter, dtype=np.float64).reshape(len(ta), len(fa))
    counted = np.ones(len(ta), dtype=bool) if counted is None else np.asarray(counted, dtype=bool)
    scores, detail = match_rooms(inter, ta, fa, counted)
    scored = ~detail["left_out"]
    scores.update(bormann_scores(inter[np.ix_(counted, scored)], ta[counted], fa[scored], min_area))
    return scores, detail


def relabel(labels: np.ndarray, min_px: int = 0) -> np.ndarray:
    """Labels renumbered 1..n in order of their old values, 0 kept 0, regions of
    ``min_px`` pixels or fewer set to 0.

    Parameters
    ----------
    labels : (H, W) int ndarray
        0 no room, any other value a room.
    min_px : int

    Returns
    -------
    (H, W) int32 ndarray
    """
    values, inverse, counts = np.unique(np.asarray(labels).ravel(), return_inverse=True, return_counts=True)
    keep = (values != 0) & (counts > min_px)
    new = np.zeros(len(values), dtype=np.int32)
    new[keep] = np.arange(1, int(keep.sum()) + 1, dtype=np.int32)
    return new[inverse].reshape(np.shape(labels))


def intersection_matrix(true_labels: np.ndarray, found_labels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel overlaps and areas of two label images of one shape, labels 1..T and 1..F.

    Parameters
    ----------
    true_labels, found_labels : (H, W) int ndarray
        0 no room, rooms numbered from 1 without gaps (:func:`relabel`).

    Returns
    -------
    inter : (T, F) float64 ndarray
        Pixels in both.
    true_area : (T,) float64 ndarray
    found_area : (F,) float64 ndarray
        Pixels.
    """
    t, f = np.asarray(true_labels, np.int64).ravel(), np.asarray(found_labels, np.int64).ravel()
    n_t, n_f = int(t.max(initial=0)), int(f.max(initial=0))
    joint = np.bincount(t * (n_f + 1) + f, minlength=(n_t + 1) * (n_f + 1)).reshape(n_t + 1, n_f + 1)
    joint = joint.astype(np.float64)
    return joint[1:, 1:], joint[1:, :].sum(axis=1), joint[:, 1:].sum(axis=0)


def score_label_images(true_labels: np.ndarray, found_labels: np.ndarray, min_px: int = MIN_REGION_PX) -> dict:
    """A segmentation against the true one, both label images of the same pixels.

    Both are cut to their common top-left part; regions of ``min_px`` pixels or fewer
    (within that part) are dropped on either side before anything is scored, as ipa's
    code does, so both the matching and Bormann's figures see the same rooms.

    Parameters
    ----------
    true_labels, found_labels : (H, W) int ndarray
        0 no room, any other value a room (values need not be consecutive).
    min_px : int
        :data:`MIN_REGION_PX`.

    Returns
    -------
    dict
        :func:`segmentation_scores`'s scores (every true room counts).
    """
    h = min(np.shape(true_labels)[0], np.shape(found_labels)[0])
    w = min(np.shape(true_labels)[1], np.shape(found_labels)[1])
    t = relabel(np.asarray(true_labels)[:h, :w], min_px)
    f = relabel(np.asarray(found_labels)[:h, :w], min_px)
    inter, ta, fa = intersection_matrix(t, f)
    return segmentation_scores(inter, ta, fa, min_area=min_px)[0]


def label_drawn_regions(grey: np.ndarray, white_above: float = DRAWN_WHITE_ABOVE) -> np.ndarray:
    """The rooms of a segmentation drawn as white regions between lines, as ipa's code
    reads ``<map>_gt_segmentation.png``: each 8-connected region of pixels whose grey
    level is above ``white_above`` is one room (no region dropped here).

    Parameters
    ----------
    grey : (H, W) float ndarray
        Grey levels, 0..255 (:func:`grey_of_image`).
    white_above : float

    Returns
    -------
    (H, W) int32 ndarray
        0 no room, rooms 1..n.
    """
    from scipy import ndimage

    labels, _ = ndimage.label(np.asarray(grey) > white_above, structure=np.ones((3, 3), dtype=bool))
    return labels.astype(np.int32)


def label_colours(rgba: np.ndarray) -> np.ndarray:
    """The rooms of a segmentation drawn one colour per room (ROSE^2's ``_gt.png`` and
    ``_rose2.png``): each colour other than black is one room; transparent pixels are
    no room.

    Parameters
    ----------
    rgba : (H, W, 3) or (H, W, 4) uint8 ndarray

    Returns
    -------
    (H, W) int32 ndarray
        0 no room, rooms 1..n in order of their colour code.
    """
    a = np.asarray(rgba)
    if a.ndim != 3 or a.shape[2] < 3:
        raise ValueError(f"expected an (H, W, 3|4) colour image, got shape {a.shape}")
    rgb = a[..., :3].astype(np.int64)
    key = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
    if a.shape[2] == 4:
        key = np.where(a[..., 3] > 0, key, 0)
    return relabel(key)


def grey_of_image(image: np.ndarray) -> np.ndarray:
    """Grey levels 0..255 of an 8-bit image as OpenCV's ``imread(..., IMREAD_GRAYSCALE)``
    reads it: ``0.299 R + 0.587 G + 0.114 B`` (alpha ignored); a grey image as it is.

    Parameters
    ----------
    image : (H, W), (H, W, 2), (H, W, 3) or (H, W, 4) uint8 ndarray

    Returns
    -------
    (H, W) float64 ndarray
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        return a
    if a.shape[2] <= 2:  # grey and alpha
        return a[..., 0]
    return a[..., :3] @ np.array([0.299, 0.587, 0.114])
