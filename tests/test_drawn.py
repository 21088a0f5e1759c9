"""A plan drawn by people (floorscan.score.drawn): its faces, its alignment to the map
frame by a similarity transform, and a plan scored against it; on a drawing made here
at a known transform, and on the shared drawings of intel and freiburg101."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import SHARED_DATA, needs_shared
from floorscan.score.drawn import (
    Similarity,
    align_drawn,
    drawn_area,
    drawn_faces,
    score_against_drawn,
    score_points_against_drawn,
    umeyama,
)


def _drawing():
    """A 400 x 300 px drawing: two rooms and a corridor, white free space, grey walls."""
    img = np.full((300, 400), 0.8, dtype=np.float32)
    img[40:140, 40:180] = 1.0   # room A
    img[40:140, 190:360] = 1.0  # room B
    img[150:200, 40:360] = 1.0  # corridor
    img[140:150, 100:120] = 1.0  # door A
    img[140:150, 260:280] = 1.0  # door B
    return img


def test_umeyama_recovers_a_similarity():
    rng = np.random.default_rng(0)
    src = rng.uniform(-5, 5, (50, 2))
    s, a, t = 0.05, math.radians(37.0), np.array([3.0, -2.0])
    r = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    got = umeyama(src, s * src @ r.T + t)
    assert got[0] == pytest.approx(s) and got[1] == pytest.approx(a) and np.allclose(got[2], t)


def test_alignment_and_scores_on_a_known_transform():
    faces_px, free = drawn_faces(_drawing())
    assert 1500 < len(faces_px) < 3000
    truth = Similarity(scale=0.052, angle=math.radians(100.0), tx=12.0, ty=-4.0)
    rng = np.random.default_rng(1)
    structure = truth.apply(faces_px) + rng.normal(0, 0.01, (len(faces_px), 2))
    structure = structure[rng.random(len(structure)) < 0.7]  # the recording saw part of it
    got, info = align_drawn(faces_px, structure, resolution_m=0.05)
    assert got.scale == pytest.approx(0.052, rel=0.01)
    assert math.degrees(got.angle) % 360 == pytest.approx(100.0, abs=0.5)
    assert info["residual_median_m"] < 0.02
    # from two control points instead of the search
    cp = [[40, 40, *truth.apply(np.array([[40.0, 40.0]]))[0]], [360, 200, *truth.apply(np.array([[360.0, 200.0]]))[0]]]
    got2, info2 = align_drawn(faces_px, structure, 0.05, control_points=cp)
    assert info2["start"] == "control points" and got2.scale == pytest.approx(0.052, rel=0.01)
    with pytest.raises(ValueError, match="two"):
        align_drawn(faces_px, structure, 0.05, control_points=[cp[0]])
    # a plan of the drawn faces' own lines scores 1; one without room B's walls less
    xy = got.apply(faces_px)
    seen = np.ones(len(xy), dtype=bool)
    px_lines = np.array([[40, 40, 180, 40], [40, 140, 180, 140], [40, 40, 40, 140], [180, 40, 180, 140],
                         [190, 40, 360, 40], [190, 140, 360, 140], [190, 40, 190, 140], [360, 40, 360, 140],
                         [40, 150, 360, 150], [40, 200, 360, 200], [40, 150, 40, 200], [360, 150, 360, 200]], float)
    lines = np.column_stack([got.apply(px_lines[:, :2]), got.apply(px_lines[:, 2:])])
    full = score_against_drawn(lines, xy, seen, in_drawing=drawn_area(free, got))
    part = score_against_drawn(lines[[0, 1, 2, 3, 8, 9, 10, 11]], xy, seen)
    assert full["completeness_10cm"] > 0.9 and full["correctness_10cm"] > 0.9
    assert part["completeness_10cm"] < 0.75 and part["correctness_10cm"] > 0.9
    # a wall far outside the drawing does not count against correctness
    outside = np.r_[lines, [[100.0, 100.0, 110.0, 100.0]]]
    assert score_against_drawn(outside, xy, seen, in_drawing=drawn_area(free, got))["correctness_10cm"] == pytest.approx(
        full["correctness_10cm"])


def test_points_against_the_drawing_bound_the_plans():
    """The reference map's structure scored as points: the drawn faces' own points, half
    of them moved 0.15 m, reach completeness 1 at 20 cm and 0.5 (+- sampling) at 10 cm;
    a point outside the drawing does not count against correctness."""
    faces_px, free = drawn_faces(_drawing())
    t = Similarity(scale=0.05, angle=0.0, tx=0.0, ty=0.0)
    xy = t.apply(faces_px)
    seen = np.ones(len(xy), dtype=bool)
    moved = xy.copy()
    moved[::2] += [0.15, 0.15]  # 0.15 m off a face, or 0.21 m at a corner
    got = score_points_against_drawn(moved, xy, seen, in_drawing=drawn_area(free, t))
    assert got["completeness_20cm"] == pytest.approx(1.0)
    assert got["correctness_20cm"] > 0.99  # a few moved corner points are 0.21 m from any face
    assert 0.45 < got["correctness_10cm"] < 0.75
    far = score_points_against_drawn(np.r_[xy, [[100.0, 100.0]]], xy, seen, in_drawing=drawn_area(free, t))
    assert far["correctness_10cm"] == pytest.approx(1.0) and far["n_seen"] == len(xy)


@needs_shared
@pytest.mark.realdata
@pytest.mark.parametrize("image", ["lab_intel.png", "Freiburg101_scan.png"])
def test_shared_drawings_have_faces(image):
    """The shared drawings read as white free space with its boundary (the alignment to
    the recordings runs in the workflow: rule score_drawn)."""
    from floorscan.score.drawn import read_plan_image

    faces, free = drawn_faces(read_plan_image(SHARED_DATA / "ipa-maps" / image))
    assert free.mean() > 0.2 and len(faces) > 5000
