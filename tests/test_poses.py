import math

import numpy as np
import pandas as pd
import pytest

from floorscan.core.io import InputError
from floorscan.core.geometry import wrap_angle
from floorscan.ingest.poses import interpolate_poses, scan_poses


def stream(t_s, x, y, yaw, z=None):
    n = len(t_s)
    return pd.DataFrame(
        {
            "t_ns": (np.asarray(t_s) * 1e9).astype(np.int64),
            "x": np.asarray(x, float),
            "y": np.asarray(y, float),
            "z": np.zeros(n) if z is None else np.asarray(z, float),
            "yaw": np.asarray(yaw, float),
        }
    )


def test_linear_interpolation_hand_computed():
    s = stream([0.0, 0.4], [0.0, 2.0], [0.0, -4.0], [0.0, math.pi / 2], z=[0.3, 0.5])
    out = interpolate_poses(s, np.array([int(0.1e9), int(0.3e9)]))
    assert out["valid"].tolist() == [True, True]
    # w = 0.25 and 0.75
    np.testing.assert_allclose(out["x"], [0.5, 1.5])
    np.testing.assert_allclose(out["y"], [-1.0, -3.0])
    np.testing.assert_allclose(out["z"], [0.35, 0.45])
    np.testing.assert_allclose(out["yaw"], [math.pi / 8, 3 * math.pi / 8])


def test_yaw_takes_the_shorter_arc_across_pi():
    # from +3.0 to -3.0 rad: the short way is +0.2832 rad through pi, not -6 rad through 0
    s = stream([0.0, 1.0], [0, 0], [0, 0], [3.0, -3.0])
    out = interpolate_poses(s, np.array([int(0.25e9), int(0.5e9), int(0.75e9)]), max_gap_s=2.0)
    arc = 2 * math.pi - 6.0
    expected = wrap_angle([3.0 + 0.25 * arc, 3.0 + 0.5 * arc, 3.0 + 0.75 * arc])
    np.testing.assert_allclose(out["yaw"], expected, atol=1e-12)
    assert out["yaw"].iloc[0] == pytest.approx(3.0707963, abs=1e-6)
    assert out["yaw"].iloc[2] == pytest.approx(-3.0707963, abs=1e-6)
    # and the other way round, from -3.0 to +3.0
    s2 = stream([0.0, 1.0], [0, 0], [0, 0], [-3.0, 3.0])
    out2 = interpolate_poses(s2, np.array([int(0.25e9)]), max_gap_s=2.0)
    assert out2["yaw"].iloc[0] == pytest.approx(-3.0707963, abs=1e-6)


def test_exact_stamps_and_reasons():
    s = stream([1.0, 1.2, 2.0, 2.1], [0, 1, 2, 3], [0, 0, 0, 0], [0, 0, 0, 0])
    q = (np.array([0.5, 1.0, 1.1, 1.5, 2.1, 2.5]) * 1e9).astype(np.int64)
    out = interpolate_poses(s, q, max_gap_s=0.5)
    assert out["reason"].tolist() == ["before_pose_stream", "", "", "pose_gap", "", "after_pose_stream"]
    assert out["valid"].tolist() == [False, True, True, False, True, False]
    np.testing.assert_allclose(out["x"].to_numpy()[[1, 2, 4]], [0.0, 0.5, 3.0])
    assert out["x"].isna().tolist() == [True, False, False, True, False, True]


@pytest.mark.parametrize("t, kind", [([0.0, 0.1, 0.1, 0.3], "duplicate"), ([0.0, 0.2, 0.1, 0.3], "unsorted")])
def test_bad_stream_stamps_raise(t, kind):
    s = stream(t, [0] * 4, [0] * 4, [0] * 4)
    with pytest.raises(InputError, match=f"pose.parquet: {kind} t_ns at row 2"):
        interpolate_poses(s, np.array([int(0.15e9)]), source="pose.parquet")


def test_stream_not_overlapping_scans_raises():
    s = stream([10.0, 11.0], [0, 1], [0, 0], [0, 0])
    with pytest.raises(InputError, match="does not overlap the scans"):
        interpolate_poses(s, (np.array([1.0, 2.0]) * 1e9).astype(np.int64), source="x")


def test_scan_poses_carries_scan_ids():
    s = stream([0.0, 1.0], [0, 1], [0, 0], [0, 0])
    index = pd.DataFrame({"scan_id": np.array([7, 8], np.int32), "t_ns": np.array([0, int(0.5e9)])})
    out = scan_poses(index, s, 2.0, "x")
    assert out["scan_id"].tolist() == [7, 8]
    assert out["x"].tolist() == [0.0, 0.5]
    assert out["valid"].all()


def test_empty_stream_means_no_pose_source():
    """Pose kind none (wheel odometry only): every scan without a pose, no error."""
    s = stream([], [], [], [])
    index = pd.DataFrame({"scan_id": np.array([0, 1, 2], np.int32), "t_ns": np.array([0, 100, 200])})
    out = scan_poses(index, s, 0.5, "pose_stream.parquet")
    assert out["scan_id"].tolist() == [0, 1, 2]
    assert out["valid"].tolist() == [False] * 3
    assert out["reason"].tolist() == ["no_pose_source"] * 3
    assert out[["x", "y", "z", "yaw"]].isna().all().all()
