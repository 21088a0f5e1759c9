"""Bad and unusual recordings, as a new user brings them (issue 35's Done-when): a corpus
of tiny recordings in every format, each run through ingest, poses and register in
process, each outcome judged against what the user should get, and the tally.

Each case declares what a user should get: an error whose one-paragraph message names
the file and the field, topic or frame at fault; or a run whose verdict or notes name
what was lost, with its numbers; or a correct run with nothing to say. The stages run as
their scripts run them (``scripts/ingest.py``, ``scripts/poses.py``,
``scripts/register.py``): :func:`floorscan.ingest.readers.open_recording` and
:func:`floorscan.ingest.writer.write_recording`, :func:`floorscan.ingest.poses.scan_poses`,
:func:`floorscan.register.stream.register_recording` with the config's defaults; an
expected error is shown as :func:`floorscan.core.stage.failure_message` prints it.

Outcomes:

- ``clear``: an error whose message contains the expected words, on one line, without
  traceback text;
- ``warning``: ran, and the verdict, the notes or a WARNING log line name what was lost
  (the expected words, with the numbers);
- ``correct``: ran, nothing lost, the result as expected;
- ``unclear``: an error that does not name what it should, an unexpected exception type
  (a bug, with its traceback), or a recording that should run refused;
- ``silent``: ran with a wrong or partial result and nothing said.

Usage: ``python -m benchmarks bad_input [--only SUBSTRING ...] [--keep DIR]`` (about 5 s).
The recordings are written to a temporary folder (``--keep DIR``: there, kept). The
room every recording sees is the 10 m x 6 m room with a notch and a pillar of
``tests/test_registration.py``; the tiny-recording writers are ``tests/conftest.py``'s.
"""

from __future__ import annotations

import argparse
import dataclasses
import gzip
import logging
import math
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any, Callable

import numpy as np

REPO = Path(__file__).resolve().parents[1]
if str(REPO / "tests") not in sys.path:  # the tiny-recording writers of tests/conftest.py
    sys.path.insert(0, str(REPO / "tests"))

from conftest import T0_NS, cast_rays, flaser_line, laser_pose, robotlaser_line, write_room_bag  # noqa: E402
# The room of tests/test_registration.py: 10 m x 6 m with a notch and a free-standing
# pillar wall, so that no translation or rotation leaves it unchanged.
from test_registration import SEGMENTS  # noqa: E402

OUTCOMES = ("clear", "warning", "correct", "unclear", "silent")

N_SCANS = 30  # 3 s at 10 Hz along conftest.base_pose
DT_S = 0.1
N_BEAMS = 181  # LaserScan: 181 beams over 180 degrees
NOISE_M = 0.003


def room_ranges(i: int, t_s: float | None = None, n: int = N_BEAMS, fov: float = math.pi,
                start: float = -math.pi / 2, still: bool = False) -> np.ndarray:
    """Ranges (float32, metres) of the laser at ``laser_pose`` of scan ``i`` (t = i x 0.1 s,
    or ``t_s``; t = 0 when ``still``) in the room, beams from ``start`` over ``fov``
    radians with both ends included, with 3 mm of seeded noise (a robot standing still
    still reads a little differently each scan)."""
    t = 0.0 if still else (i * DT_S if t_s is None else t_s)
    x, y, yaw = laser_pose(t)
    ang = float(yaw) + start + np.arange(n) * (fov / (n - 1))
    r = cast_rays(SEGMENTS, (float(x), float(y)), ang)
    return (r + np.random.default_rng(i).normal(0.0, NOISE_M, n)).astype(np.float32)


# --- recordings ---------------------------------------------------------------------------


def room_bag(path: Path, n: int = N_SCANS, still: bool = False, ranges: Callable[[int], np.ndarray] | None = None,
             **kw) -> Path:
    """A bag of ``n`` scans of the room (:func:`conftest.write_room_bag`, whose keywords
    ``kw`` are: ``ros2``, ``cloud``, ``change``, ``raw``, ``stamps``, ``scan_frame``,
    ``links``, ``static``, ``map_until_s``, ``pose_topic``); the ranges are
    :func:`room_ranges` unless ``ranges(i)`` gives them."""
    return write_room_bag(path, ranges or (lambda i: room_ranges(i, still=still)), n=n, still=still, **kw)


def carmen_lines(n: int = N_SCANS, kind: str = "FLASER", bad: Callable[[int], dict] | None = None,
                 stamps: list[float] | None = None, still: bool = False) -> list[str]:
    """Laser lines of the room along ``laser_pose`` (FLASER: 180 beams at pi/180 from
    -pi/2; ROBOTLASER1: 181 beams over pi; :func:`conftest.flaser_line`,
    :func:`conftest.robotlaser_line`). ``bad(i)`` -> keyword changes of line ``i``
    (ROBOTLASER1: ``start``/``fov``/``res``; either: ``ranges``, ``shift``: (dx, dy)
    metres added to the line's pose, the scan unchanged: the localizer jumped; ``scale``:
    the ranges written in metres x scale, 1000 for millimetres; ``theta_deg``: the pose's
    heading written in degrees)."""
    lines = []
    for i in range(n):
        t_s = 10.0 + i * DT_S if stamps is None else stamps[i]
        pose = tuple(float(v) for v in laser_pose(0.0 if still else i * DT_S))
        kw = dict(bad(i) or {}) if bad else {}
        dx, dy = kw.pop("shift", (0.0, 0.0))
        scale = kw.pop("scale", 1.0)
        theta = math.degrees(pose[2]) if kw.pop("theta_deg", False) else pose[2]
        pose = (pose[0] + dx, pose[1] + dy, theta)
        if kind == "FLASER":
            r = kw.pop("ranges", None)
            if r is None:
                r = room_ranges(i, n=180, fov=math.pi * 179 / 180, still=still)
            lines.append(flaser_line(r * scale, pose, t_s))
        else:
            r = kw.pop("ranges", None)
            if r is None:
                r = room_ranges(i, still=still)
            lines.append(robotlaser_line(r * scale, pose, t_s, **kw))
    return lines


def write_log(path: Path, lines: list[str], prefix: bytes = b"", suffix: bytes = b"") -> Path:
    data = prefix + ("\n".join(lines) + "\n").encode()
    if path.name.endswith(".gz"):
        data = gzip.compress(data, mtime=0)
    path.write_bytes(data + suffix)
    return path


def pcd_folder(folder: Path, n: int = 40, listed: Callable[[int], bool] | None = None,
               nan_at: tuple[int, ...] = (), stamps: list[int] | None = None, scale: float = 1.0,
               yaw_deg: bool = False) -> Path:
    """A folder of ``n`` ascii PCD scans of the room (the laser's beams as points, z 0.4 m)
    and its locations.csv (``listed(i)`` False: file i is left out of it; ``stamps``: the
    ``t_ns`` of each file, else ``T0_NS`` + 0.1 s steps). ``scale``: points and locations
    written in metres x ``scale`` (1000: millimetres); ``yaw_deg``: the yaw column in
    degrees."""
    folder.mkdir(parents=True)
    rows = ["file,t_ns,x,y,z,yaw"]
    ang = np.linspace(-math.pi / 2, math.pi / 2, N_BEAMS)
    for i in range(n):
        r = room_ranges(i)
        pts = np.c_[r * np.cos(ang), r * np.sin(ang), np.full(N_BEAMS, 0.4)] * scale
        if i in nan_at:
            pts[:] = np.nan
        body = "\n".join(f"{a:.4f} {b:.4f} {c:.4f}" for a, b, c in pts)
        (folder / f"{i:04d}.pcd").write_text(
            f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {N_BEAMS}\nHEIGHT 1\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {N_BEAMS}\nDATA ascii\n{body}\n")
        if listed is None or listed(i):
            x, y, yaw = laser_pose(i * DT_S)
            t_ns = T0_NS + int(i * DT_S * 1e9) if stamps is None else stamps[i]
            yaw = math.degrees(yaw) if yaw_deg else yaw
            rows.append(f"{i:04d}.pcd,{t_ns},{x * scale:.5f},{y * scale:.5f},0.0,{yaw:.6f}")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    return folder


# --- the cases ------------------------------------------------------------------------------


@dataclasses.dataclass
class Case:
    """A recording and what its user should get.

    ``expect``: ``"error"`` (a message containing ``words``), ``"warning"`` (a run whose
    verdict, notes or warnings contain ``words``; an error stopping at a threshold that
    contains them is clear too), ``"correct"`` (a run, nothing lost), or
    ``"correct|error"`` (either a correct run or an error containing ``words``).
    ``n_index``: the scans the index should hold after a run; ``check(run)`` returns a
    problem of the result (None: none). ``{path}`` and ``{name}`` in ``words`` are the
    recording's path and file name. ``issue``: a class of issue 35 or 45 (else a control or an
    older class)."""

    name: str
    build: Callable[[Path], dict]
    expect: str
    words: tuple[str, ...] = ()
    n_index: int | None = None
    check: Callable[["Run"], str | None] | None = None
    issue: bool = True


@dataclasses.dataclass
class Run:
    """What the three stages gave."""

    dataset: dict
    out: Path | None = None  # the folder of the stages' tables
    notes: list[str] = dataclasses.field(default_factory=list)
    detected: dict = dataclasses.field(default_factory=dict)
    index: Any = None
    poses: Any = None
    summary: dict | None = None
    warnings: list[str] = dataclasses.field(default_factory=list)  # WARNING log records
    stage: str = ""
    error: BaseException | None = None
    message: str = ""  # the paragraph the stage prints, or the traceback of a bug


@dataclasses.dataclass
class Outcome:
    case: Case
    outcome: str
    stage: str
    detail: str
    seconds: float


def _bag_ds(path: Path, **extra) -> dict:
    return {"name": path.name, "path": str(path), **extra}


def _set(**fields) -> Callable[[int, Any], None]:
    def change(i, m):
        for k, v in fields.items():
            setattr(m, k, v(m) if callable(v) else v)
    return change


def _only(which, change):
    def f(i, m):
        if i in which:
            change(i, m)
    return f


def _neg_inc(m):
    return -m.angle_increment


def _twice(m):
    return np.r_[m.ranges, m.ranges]


def _swap_span(m):
    m.angle_min, m.angle_max = m.angle_max, m.angle_min


def _degrees(m):
    m.angle_min, m.angle_max, m.angle_increment = -90.0, 90.0, 1.0


def _nan_cloud(m):
    m.data = np.frombuffer(np.full(3 * m.width, np.nan, "<f4").tobytes(), np.uint8)


def _first_pose_at(x: float, y: float, tol: float = 0.05):
    def check(run: Run) -> str | None:
        if run.poses is None or not len(run.poses) or not bool(run.poses["valid"].iloc[0]):
            return "the first scan has no map pose"
        px, py = float(run.poses["x"].iloc[0]), float(run.poses["y"].iloc[0])
        if math.hypot(px - x, py - y) > tol:
            return f"first pose ({px:.2f}, {py:.2f}), expected ({x:.2f}, {y:.2f})"
        return None
    return check


LX0, LY0, _ = (float(v) for v in laser_pose(0.0))
MAP_POSE = _first_pose_at(LX0, LY0)


def _sorted_stamps(run: Run) -> str | None:
    t = run.index["t_ns"].to_numpy()
    return None if (np.diff(t) > 0).all() else "scan stamps not increasing in the index"


def _all(*checks):
    def check(run):
        for c in checks:
            problem = c(run)
            if problem:
                return problem
        return None
    return check


def _swapped(n=N_SCANS, pairs=((5, 6),)) -> list[int]:
    s = [T0_NS + int(i * DT_S * 1e9) for i in range(n)]
    for a, b in pairs:
        s[a], s[b] = s[b], s[a]
    return s


def _ros2_metadata_edit(folder: Path, edit: Callable[[str], str]) -> None:
    meta = folder / "metadata.yaml"
    meta.write_text(edit(meta.read_text()))


def _lying_count(text: str) -> str:
    """/scan's message_count set to 0 in a ROS2 metadata.yaml."""
    import yaml

    doc = yaml.safe_load(text)
    for entry in doc["rosbag2_bagfile_information"]["topics_with_message_count"]:
        if entry["topic_metadata"]["name"] == "/scan":
            entry["message_count"] = 0
    return yaml.safe_dump(doc, sort_keys=False)


def _lying_type(text: str) -> str:
    """/scan's type given as PointCloud2 (its messages are LaserScans)."""
    import yaml

    doc = yaml.safe_load(text)
    for entry in doc["rosbag2_bagfile_information"]["topics_with_message_count"]:
        if entry["topic_metadata"]["name"] == "/scan":
            entry["topic_metadata"]["type"] = "sensor_msgs/msg/PointCloud2"
    return yaml.safe_dump(doc, sort_keys=False)


def _ros2_bag(root: Path, name: str, edit=None, **kw) -> dict:
    folder = room_bag(root / name, ros2=True, **kw)
    if edit is not None:
        _ros2_metadata_edit(folder, edit)
    return _bag_ds(folder)


def _bag(name: str, **kw) -> Callable[[Path], dict]:
    return lambda root: _bag_ds(room_bag(root / name, **kw))


def _log(name: str, prefix: bytes = b"", suffix: bytes = b"", before: tuple[str, ...] = (), ds: dict | None = None,
         **kw) -> Callable[[Path], dict]:
    def build(root):
        lines = [*before, *carmen_lines(**kw)]
        return {"name": name, "path": str(write_log(root / name, lines, prefix, suffix)), **(ds or {})}
    return build


def _pcd(name: str, **kw) -> Callable[[Path], dict]:
    return lambda root: {"name": name, "path": str(pcd_folder(root / name, **kw)), "format": "pcd"}


def _ros2_without_metadata(root: Path) -> dict:
    """A ROS2 bag folder whose metadata.yaml is gone (copied without it)."""
    folder = room_bag(root / "no_metadata_ros2", ros2=True)
    (folder / "metadata.yaml").unlink()
    return {"name": folder.name, "path": str(folder), "format": "rosbag"}


def _not_cdr(text: str) -> str:
    """Every topic's serialization_format given as json in a ROS2 metadata.yaml."""
    import yaml

    doc = yaml.safe_load(text)
    for entry in doc["rosbag2_bagfile_information"]["topics_with_message_count"]:
        entry["topic_metadata"]["serialization_format"] = "json"
    return yaml.safe_dump(doc, sort_keys=False)


def _pcd_spaced_header(root: Path) -> dict:
    """A PCD folder whose locations.csv has a space after each comma, header and rows."""
    folder = pcd_folder(root / "pcd_spaced_csv")
    csv = folder / "locations.csv"
    csv.write_text(csv.read_text().replace(",", ", "))
    return {"name": folder.name, "path": str(folder)}


def _pcd_in_subfolder(root: Path) -> dict:
    """A PCD folder whose .pcd files sit in ``scans/``, named so in locations.csv; the
    format left to detection."""
    folder = pcd_folder(root / "pcd_subfolder")
    (folder / "scans").mkdir()
    for f in folder.glob("*.pcd"):
        f.rename(folder / "scans" / f.name)
    csv = folder / "locations.csv"
    head, *rows = csv.read_text().splitlines()
    csv.write_text("\n".join([head, *(f"scans/{r}" for r in rows)]) + "\n")
    return {"name": folder.name, "path": str(folder)}


def _truncated_bag(root: Path) -> dict:
    good = room_bag(root / "whole_for_truncated.bag")
    p = root / "truncated.bag"
    p.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    good.unlink()
    return _bag_ds(p)


def _empty_bag(root: Path) -> dict:
    p = root / "empty.bag"
    p.write_bytes(b"")
    return _bag_ds(p)


def _carmen_on_bag(root: Path) -> dict:
    return _bag_ds(room_bag(root / "given_carmen.bag"), format="carmen")


def _nan_at(which: int, n: int = 180):
    return lambda i: {"ranges": np.full(n, np.nan)} if i == which else None


UNKNOWN_LINES = ("FLASR 180 " + " ".join(["1.0"] * 180), "XYZZY 1 2 3")


def _unknown_lines_log(root: Path) -> dict:
    lines = carmen_lines()
    lines = ["PARAM robot_front_laser_max 81.9 nohost 0", *lines[:3], UNKNOWN_LINES[0], *lines[3:9],
             "ODOM 0 0 0 0 0 0 10.1 host 10.1", UNKNOWN_LINES[1], *lines[9:]]
    p = write_log(root / "unknown_types.log", lines)
    return {"name": p.name, "path": str(p)}


def _late_laser_log(root: Path) -> dict:
    odom = [f"ODOM {0.0001 * k:.4f} 0 0 0 0 0 {1.0 + 0.0003 * k:.4f} host {1.0 + 0.0003 * k:.4f}"
            for k in range(25_000)]
    p = write_log(root / "late_laser.log", ["PARAM robot_name pioneer 0 host 0", *odom, *carmen_lines()])
    return {"name": p.name, "path": str(p)}


def _short_line_log(root: Path) -> dict:
    """Line 5 says 180 ranges and has 179 (a value lost when the log was cut and pasted)."""
    lines = carmen_lines()
    tok = lines[4].split()
    lines[4] = " ".join(tok[:2] + tok[3:])
    p = write_log(root / "short_line.log", lines)
    return {"name": p.name, "path": str(p)}


LOST_BAD = ("lost_bad_frames",)

# --- issue 45: valid recordings that were refused, pose jumps ----------------------------------

#: Real epoch stamps in nanoseconds: ~1.6e18 with every digit set (a float64 keeps 15-16).
EPOCH_STAMPS = [1_612_345_678_123_456_789 + i * 100_000_117 for i in range(40)]


def _first_base_pose(run: Run) -> str | None:
    """A pose topic without a mount (no /tf_static): the scanner is taken to be at the
    base's pose."""
    from conftest import X0, Y0

    return _first_pose_at(X0, Y0)(run)


def _points_on_walls(run: Run, tol_m: float = 0.05, sids: tuple[int, ...] = (0, 10, 20)) -> str | None:
    """The points of scans ``sids`` at their poses lie on the room's walls (a mirrored
    scan's do not)."""
    from floorscan.core.io import read_table

    scans = read_table(run.out / "scans.parquet")
    p = run.poses.set_index("scan_id")
    seg = SEGMENTS.reshape(-1, 2, 2)
    for sid in sids:
        pts = scans.loc[scans["scan_id"] == sid, ["x", "y"]].to_numpy(np.float64)
        x, y, yaw = (float(p.loc[sid, c]) for c in ("x", "y", "yaw"))
        c, s_ = math.cos(yaw), math.sin(yaw)
        w = np.c_[x + c * pts[:, 0] - s_ * pts[:, 1], y + s_ * pts[:, 0] + c * pts[:, 1]]
        a, b = seg[:, 0], seg[:, 1]
        ab = b - a
        u = np.clip(((w[:, None] - a) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
        d = np.linalg.norm(w[:, None] - (a + u[..., None] * ab), axis=-1).min(axis=1)
        if np.median(d) > tol_m:
            return f"scan {sid}: its points lie {np.median(d):.2f} m (median) off the room's walls"
    return None


def _rear_points_on_walls(run: Run) -> str | None:
    """The rear scanner's scans (odd ones of the two-scanner bag) lie on the walls too."""
    return _points_on_walls(run, sids=(1, 11, 21))


def _jump_named(metres: float, tol_m: float = 0.2):
    """The verdict says the map pose jumped ``metres``, within ``tol_m`` (the rover's
    way over the dropped scans is extrapolated)."""
    def check(run: Run) -> str | None:
        import re

        text = " ".join(t for _, t in _said(run))
        found = [float(v) for v in re.findall(r"the map pose jumped ([0-9.]+) m", text)]
        if not found:
            return "no 'the map pose jumped ... m' in what the run said"
        if abs(found[0] - metres) > tol_m:
            return f"the verdict says the map pose jumped {found[0]:.2f} m, expected {metres:.2f} m"
        return None
    return check


def _exact_stamps(stamps: list[int]):
    def check(run: Run) -> str | None:
        got = run.index["t_ns"].to_numpy(np.int64)
        if got.tolist() != stamps[: len(got)]:
            i = int(np.flatnonzero(got != np.asarray(stamps[: len(got)], np.int64))[0])
            return f"scan {i} stamped {got[i]} ns in the index, {stamps[i]} ns in the CSV"
        return None
    return check


def _reduces(run: Run) -> str | None:
    """The reduced recording of every third scan is written (the select stage's check
    of the recording against the scan index: stamps, counts)."""
    from floorscan.core.io import InputError
    from floorscan.ingest.reduced import read_detection, write_reduced_recording

    ids = run.index["scan_id"].to_numpy()[::3]
    try:
        write_reduced_recording(run.dataset["path"], run.dataset.get("format"), ids, run.out / "reduced",
                                read_detection(run.out / "scan_index.parquet"))
    except InputError as e:
        return f"the reduced recording fails: {e}"
    return None


def _span360(extra_beams: int):
    """A 360 degree scanner with ``extra_beams`` beams past the full turn (1 degree apart)."""
    n, inc = 360 + extra_beams, math.radians(1.0)

    def change(i, m):
        m.angle_min, m.angle_increment, m.angle_max = -math.pi, inc, -math.pi + (n - 1) * inc
        m.ranges = room_ranges(i, n=n, fov=(n - 1) * inc, start=-math.pi)
    return change


def _upside_down(i: int) -> np.ndarray:
    """The ranges of a scanner mounted upside down: the level scanner's, in reverse."""
    return np.ascontiguousarray(room_ranges(i)[::-1])


def _jumped(which: tuple[int, ...], dx: float = 500.0):
    return lambda i: {"shift": (dx, 0.0)} if i in which else None


# --- issue 45 item 2: two sources in one recording -------------------------------------------

#: The rear scanner of the two-scanner bag: its static mount on base_link (x, y metres,
#: yaw radians): 0.2 m behind the base, looking back.
REAR_MOUNT = (-0.2, 0.0, math.pi)


def _rear_ranges(i: int) -> np.ndarray:
    """Ranges of the rear scanner (:data:`REAR_MOUNT`) at scan ``i``'s time, as
    :func:`room_ranges` reads the front one's."""
    from conftest import base_pose

    x, y, yaw = (float(v) for v in base_pose(i * DT_S))
    mx, my, myaw = REAR_MOUNT
    sx, sy = x + mx * math.cos(yaw) - my * math.sin(yaw), y + mx * math.sin(yaw) + my * math.cos(yaw)
    ang = yaw + myaw - math.pi / 2 + np.arange(N_BEAMS) * (math.pi / (N_BEAMS - 1))
    r = cast_rays(SEGMENTS, (sx, sy), ang)
    return (r + np.random.default_rng(1000 + i).normal(0.0, NOISE_M, N_BEAMS)).astype(np.float32)


def _frame_of(frame: str, which: Callable[[int], bool]):
    """A ``change`` giving scan ``i``'s header ``frame`` when ``which(i)``."""
    def change(i, m):
        if which(i):
            m.header.frame_id = frame
    return change


def _two_scanners(root: Path) -> dict:
    """Front ('laser') and rear ('rear') scanners on one topic, alternating, each with its
    static mount on /tf_static."""
    path = room_bag(root / "two_scanners.bag", ranges=lambda i: _rear_ranges(i) if i % 2 else room_ranges(i),
                    change=_frame_of("rear", lambda i: i % 2 == 1), static=(("base_link", "laser"), ("base_link", "rear")),
                    mounts={"rear": REAR_MOUNT})
    return _bag_ds(path)


def _two_logs(root: Path) -> dict:
    """Two CARMEN logs of the room concatenated: the second recorded earlier (its stamps
    start 8 s before the first's), its poses in its own map frame (1.5 m, 0.5 m off)."""
    first = carmen_lines()
    second = carmen_lines(n=20, stamps=[2.0 + i * DT_S for i in range(20)],
                          bad=lambda i: {"shift": (1.5, 0.5)})
    header = ["# CARMEN Logfile", "PARAM robot_front_laser_max 81.9 nohost 0"]
    p = write_log(root / "two_logs.log", [*header, *first, *header, *second])
    return {"name": p.name, "path": str(p)}


def _two_logs_forward(root: Path) -> dict:
    """Two CARMEN logs of the room concatenated, the second recorded a day later (its
    stamps go on forward), its poses in its own map frame (1.5 m, 0.5 m off)."""
    first = carmen_lines()
    day = 86_400.0
    second = carmen_lines(n=20, stamps=[10.0 + day + i * DT_S for i in range(20)],
                          bad=lambda i: {"shift": (1.5, 0.5)})
    header = ["# CARMEN Logfile", "PARAM robot_front_laser_max 81.9 nohost 0"]
    p = write_log(root / "two_logs_forward.log", [*header, *first, *header, *second])
    return {"name": p.name, "path": str(p)}


def _early_line(root: Path) -> dict:
    """One laser line stamped a minute before the line before it (line 12)."""
    stamps = [100.0 + i * DT_S for i in range(N_SCANS)]
    stamps[11] -= 60.0
    p = write_log(root / "early_line.log", carmen_lines(stamps=stamps))
    return {"name": p.name, "path": str(p)}


#: The relocalising localizer's recording: 100 scans (10 s), ``map -> odom`` jumping 3 m
#: at 5 s and staying there.
RELOCALISED_N, RELOCALISED_AT_S, RELOCALISED_M = 100, 5.0, 3.0


# --- issue 45 item 4: units -----------------------------------------------------------------


def _in_units(scale: float):
    """A LaserScan ``change``: ranges and range limits written in metres x ``scale`` (a
    driver publishing millimetres, 1000, or centimetres, 100, throughout)."""
    def change(i, m):
        m.ranges = (np.asarray(m.ranges, np.float64) * scale).astype(np.float32)
        m.range_min, m.range_max = m.range_min * scale, m.range_max * scale
    return change


def _every(**kw):
    return lambda i: dict(kw)


def cases() -> list[Case]:
    """The corpus: issue 35's and 45's classes, a few older ones and good controls."""
    n = N_SCANS
    one = (7,)
    lost1 = (f"1 of the recording's {n} scans",)
    return [
        # --- LaserScan geometry (issue 35 item 1)
        Case("scan_increment_zero_every_scan", _bag("inc0.bag", change=_set(angle_increment=0.0)),
             "error", ("{name}", "/scan", "angle_increment")),
        Case("scan_increment_zero_one_scan", _bag("inc0_one.bag", change=_only(one, _set(angle_increment=0.0))),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("scan_increment_negative_every_scan", _bag("inc_neg.bag", change=_set(angle_increment=_neg_inc)),
             "error", ("{name}", "/scan", "angle_increment")),
        Case("scan_increment_negative_one_scan",
             _bag("inc_neg_one.bag", change=_only(one, _set(angle_increment=_neg_inc))),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("scan_increment_against_the_span", _bag("span_swapped.bag", change=lambda i, m: _swap_span(m)),
             "error", ("{name}", "/scan", "angle_increment")),
        Case("scan_ranges_twice_the_angles", _bag("ranges_twice.bag", change=_set(ranges=_twice)),
             "error", ("{name}", "/scan", "ranges has 362 values")),
        Case("scan_ranges_twice_in_one_scan", _bag("ranges_twice_one.bag", change=_only(one, _set(ranges=_twice))),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("scan_one_range_more_than_the_angles",
             _bag("ranges_plus1.bag", change=_set(ranges=lambda m: np.r_[m.ranges, np.float32(2.0)])),
             "correct", n_index=n, check=MAP_POSE),
        Case("scan_range_min_not_below_range_max", _bag("range_limits.bag", change=_set(range_min=30.0, range_max=0.05)),
             "error", ("{name}", "/scan", "range_min")),
        Case("scan_range_min_not_below_range_max_in_three",
             _bag("range_limits_three.bag", change=_only((0, 5, 6), _set(range_min=30.0, range_max=0.05))),
             "warning", (f"3 of the recording's {n} scans", *LOST_BAD), n_index=n - 3),
        Case("scan_angles_in_degrees", _bag("degrees.bag", change=lambda i, m: _degrees(m)),
             "error", ("{name}", "/scan", "degrees")),
        # --- no valid return, one bad frame (items 1, 3, 4)
        Case("scan_every_range_at_range_max",
             _bag("all_far.bag", ranges=lambda i: np.full(N_BEAMS, 30.0, np.float32)),
             "error", ("{name}", "/scan", "no valid return", "range_max")),
        Case("scan_every_range_nan", _bag("all_nan.bag", ranges=lambda i: np.full(N_BEAMS, np.nan, np.float32)),
             "error", ("{name}", "/scan", "no valid return", "NaN")),
        Case("scan_one_all_nan_laserscan",
             _bag("one_nan.bag", change=_only(one, _set(ranges=lambda m: np.full(N_BEAMS, np.nan, np.float32)))),
             "warning", (*lost1, "lost_no_points"), n_index=n - 1),
        Case("cloud_one_all_nan_frame_ros1", _bag("cloud_nan.bag", cloud=True, change=_only(one, lambda i, m: _nan_cloud(m))),
             "warning", (*lost1, "lost_no_points"), n_index=n - 1),
        Case("cloud_one_all_nan_frame_ros2",
             lambda root: _ros2_bag(root, "cloud_nan_ros2", cloud=True, change=_only(one, lambda i, m: _nan_cloud(m))),
             "warning", (*lost1, "lost_no_points"), n_index=n - 1),
        Case("scan_one_undecodable_frame_ros1",
             _bag("garbled.bag", raw=lambda i: b"\x01\x02\x03" if i == 7 else None),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("scan_one_undecodable_frame_ros2",
             lambda root: _ros2_bag(root, "garbled_ros2", raw=lambda i: b"\x00\x01\x00\x00\x01" if i == 7 else None),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        # --- stamps and stationary recordings (item 4)
        Case("bag_two_swapped_stamps", _bag("swapped.bag", stamps=_swapped()),
             "correct", n_index=n, check=_all(_sorted_stamps, MAP_POSE)),
        Case("bag_stamps_out_of_order_often", _bag("scrambled.bag", stamps=_swapped(pairs=((2, 3), (8, 9), (14, 15), (20, 21)))),
             "error", ("{name}", "/scan", "not sorted")),
        Case("bag_stationary_pose_topic", _bag("still_topic.bag", still=True, pose_topic=True),
             "correct", n_index=n, check=MAP_POSE),
        Case("bag_stationary_tf", _bag("still_tf.bag", still=True),
             "correct", n_index=n, check=MAP_POSE),
        Case("carmen_two_swapped_stamps",
             _log("swapped.log", stamps=[10.0 + DT_S * j for j in (0, 1, 2, 3, 4, 6, 5, *range(7, N_SCANS))]),
             "correct", n_index=n, check=_sorted_stamps),
        Case("carmen_stationary", _log("still.log", still=True), "correct", n_index=n),
        # --- CARMEN geometry and losses
        Case("robotlaser1_resolution_zero", _log("res0.log", kind="ROBOTLASER1", bad=lambda i: {"res": 0.0}),
             "error", ("{name}", "angular_resolution")),
        Case("robotlaser1_resolution_zero_one_line",
             _log("res0_one.log", kind="ROBOTLASER1", bad=lambda i: {"res": 0.0} if i == 7 else None),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("robotlaser1_fov_disagrees", _log("fov.log", kind="ROBOTLASER1", bad=lambda i: {"fov": 2 * math.pi, "res": math.pi / 180}),
             "error", ("{name}", "fov")),
        Case("robotlaser1_fov_disagrees_one_line",
             _log("fov_one.log", kind="ROBOTLASER1",
                  bad=lambda i: {"fov": 2 * math.pi, "res": math.pi / 180} if i == 7 else None),
             "warning", (*lost1, *LOST_BAD), n_index=n - 1),
        Case("carmen_every_range_zero", _log("all_zero.log", bad=lambda i: {"ranges": np.zeros(180)}),
             "error", ("{name}", "no valid return")),
        Case("carmen_one_all_nan_line", _log("one_nan.log", bad=_nan_at(7)),
             "warning", (*lost1, "lost_no_points"), n_index=n - 1),
        Case("carmen_unknown_line_types", _unknown_lines_log,
             "warning", ("lost_unknown_lines", "2 of the recording's", "FLASR", "XYZZY"), n_index=n),
        # --- format detection (item 7)
        Case("carmen_byte_order_mark", _log("bom.log", prefix=b"\xef\xbb\xbf"), "correct", n_index=n),
        Case("carmen_25000_lines_before_the_first_laser_line", _late_laser_log, "correct", n_index=n),
        Case("carmen_gzip_trailing_garbage", _log("garbage.log.gz", suffix=b"\x00\x00junk appended by a copy tool\n" * 4),
             "warning", ("trailing garbage",), n_index=n),
        Case("format_carmen_given_on_a_bag", _carmen_on_bag, "error", ("{name}", "FLASER")),
        Case("ros2_metadata_count_zero", lambda root: _ros2_bag(root, "lying_count", edit=_lying_count),
             "correct|error", ("{name}", "metadata.yaml"), n_index=n),
        Case("ros2_metadata_wrong_type", lambda root: _ros2_bag(root, "lying_type", edit=_lying_type),
             "error", ("{name}", "metadata.yaml", "/scan")),
        # --- TF (item 2)
        Case("tf_misspelt_scan_frame", _bag("misspelt.bag", scan_frame="lasr"), "error", ("{name}", "'lasr'", "map")),
        Case("tf_empty_scan_frame", _bag("empty_frame.bag", scan_frame=""), "error", ("{name}", "frame_id is empty")),
        Case("tf_loop", _bag("loop.bag", links=(("map", "odom"), ("laser", "base_link"))),
             "error", ("{name}", "loop", "'laser'")),
        Case("tf_two_parents", _bag("two_parents.bag", links=(("map", "odom"), ("odom", "base_link"), ("world", "base_link"))),
             "error", ("{name}", "'base_link'", "several parents")),
        Case("tf_map_chain_under_another_root", _bag("apart.bag", links=(("map", "odom"), ("odom2", "base_link"))),
             "error", ("{name}", "'laser'", "odom2")),
        Case("tf_map_to_odom_ends_at_a_third", _bag("map_stops.bag", map_until_s=1.0),
             "warning", ("{name}", f"20 of the recording's {n} scans", "no pose", "max_lost_fraction"), n_index=n),
        Case("tf_map_to_odom_ends_near_the_end", _bag("map_stops_late.bag", map_until_s=2.6),
             "warning", (f"4 of the recording's {n} scans", "no pose"), n_index=n),
        Case("tf_no_map_frame_odometry_only", _bag("odom_only.bag", links=(("odom", "base_link"),)),
             "warning", ("LIDAR odometry", "no map poses"), n_index=n),
        # --- PCD folders (item 3)
        Case("pcd_half_the_files_not_listed", _pcd("pcd_half_unlisted", listed=lambda i: i % 2 == 0),
             "warning", ("20 of the recording's 40 scans", "locations CSV"), n_index=20),
        Case("pcd_two_files_not_listed", _pcd("pcd_two_unlisted", listed=lambda i: i not in (11, 23)),
             "warning", ("2 of the recording's 40 scans", "locations CSV"), n_index=38),
        Case("pcd_one_nan_file", _pcd("pcd_one_nan", nan_at=(7,)),
             "warning", ("1 of the recording's 40 scans", "lost_no_points"), n_index=39),
        # --- valid recordings refused until issue 45 (item 1)
        Case("bag_no_tf_scan_only_ros1", _bag("no_tf.bag", links=(), static=()),
             "warning", ("LIDAR odometry", "no map poses"), n_index=n),
        Case("bag_no_tf_scan_only_ros2", lambda root: _ros2_bag(root, "no_tf_ros2", links=(), static=()),
             "warning", ("LIDAR odometry", "no map poses"), n_index=n),
        Case("bag_no_tf_pose_topic_ros1", _bag("no_tf_topic.bag", links=(), static=(), pose_topic=True),
             "correct", n_index=n, check=_all(_first_base_pose, _reduces)),
        Case("bag_no_tf_pose_topic_ros2",
             lambda root: _ros2_bag(root, "no_tf_topic_ros2", links=(), static=(), pose_topic=True),
             "correct", n_index=n, check=_all(_first_base_pose, _reduces)),
        Case("pcd_epoch_stamps", _pcd("pcd_epoch", stamps=EPOCH_STAMPS),
             "correct", n_index=40, check=_all(_exact_stamps(EPOCH_STAMPS), _reduces)),
        Case("scan_360_span_a_little_over_two_pi", _bag("span360.bag", change=_span360(3)),
             "correct", n_index=n, check=_all(MAP_POSE, _points_on_walls)),
        Case("scan_upside_down_tf", _bag("upside_down.bag", mount_roll=math.pi, ranges=_upside_down),
             "correct", n_index=n, check=_all(MAP_POSE, _points_on_walls, _reduces)),
        Case("scan_upside_down_pose_topic",
             _bag("upside_down_topic.bag", mount_roll=math.pi, ranges=_upside_down, pose_topic=True,
                  links=(("odom", "base_link"),)),
             "correct", n_index=n, check=_all(MAP_POSE, _points_on_walls)),
        # --- a pose topic in the odometry frame is no map pose (issue 45 item 4)
        Case("bag_pose_topic_in_odom_frame",
             _bag("odom_frame_topic.bag", pose_topic=True, pose_frame="odom", links=(("odom", "base_link"),)),
             "warning", ("/amcl_pose skipped", "frame_id is 'odom'", "LIDAR odometry"), n_index=n),
        # --- scans dropped before registration are in the verdict (issue 45 item 3)
        Case("carmen_three_poses_500_m_off", _log("jumps.log", bad=_jumped((10, 11, 20))),
             "warning", (f"3 of the recording's {n} scans", "pose_jump", "2 jumps", "at scan 10 (1.0 s into the scans) 500.05 m"),
             n_index=n),
        # --- two sources in one recording (issue 45 item 2)
        Case("bag_two_scanners_one_topic", _two_scanners, "correct", n_index=n,
             check=_all(MAP_POSE, _points_on_walls, _rear_points_on_walls)),
        Case("bag_scan_frame_renamed_midway", _bag("renamed.bag", change=_frame_of("laser_link", lambda i: i >= 18)),
             "error", ("{name}", "'/scan'", "'laser' (18 scans)", "'laser_link' (12 scans)", "static")),
        Case("carmen_two_logs_concatenated", _two_logs, "error",
             ("{name}", "2 logs", "line 35", f"{n} scans", "20 scans", "split")),
        Case("carmen_two_logs_a_day_apart", _two_logs_forward, "warning",
             ("the scans pause for 24.0 h after scan 29", "two recordings in one file", "split")),
        Case("carmen_one_line_a_minute_early", _early_line, "error", ("{name}:12", "59.9 s earlier", "line 11")),
        Case("bag_one_scan_stamped_a_minute_early",
             _bag("early.bag", stamps=[T0_NS + int(i * DT_S * 1e9) - (60 * 10**9 if i == 5 else 0) for i in range(n)]),
             "error", ("{name}", "'/scan'", "59.9 s earlier")),
        Case("bag_localizer_relocalises", _bag("relocalised.bag", n=RELOCALISED_N,
                                               map_jump=(RELOCALISED_AT_S, RELOCALISED_M)),
             "warning", ("at scan 50", "5.0 s into", "the map pose jumped", "relocalisation"), n_index=RELOCALISED_N,
             check=_jump_named(RELOCALISED_M)),
        # --- clear messages and folders (issue 45, items 5 and 6)
        Case("ros2_folder_without_metadata", _ros2_without_metadata, "error",
             ("{name}", "without its metadata.yaml", "ros2 bag reindex")),
        Case("ros2_metadata_not_cdr", lambda root: _ros2_bag(root, "json_ros2", edit=_not_cdr), "error",
             ("metadata.yaml", "not serialized as 'cdr'", "/scan")),
        Case("pcd_csv_header_with_spaces", _pcd_spaced_header, "correct", n_index=40),
        Case("pcd_scans_in_a_subfolder", _pcd_in_subfolder, "correct", n_index=40),
        Case("bag_three_scans_lidar_odometry", _bag("three.bag", n=3, links=(), static=()), "warning",
             ("only", "the recording is too short"), n_index=3),
        # --- units (issue 45 item 4): ranges in millimetres or centimetres, headings in degrees
        Case("bag_ranges_in_millimetres", _bag("ranges_mm.bag", change=_in_units(1000.0)),
             "error", ("{name}", "'/scan'", "look like millimetres", "expected metres")),
        Case("bag_ranges_in_centimetres_ros2", lambda root: _ros2_bag(root, "ranges_cm_ros2", change=_in_units(100.0)),
             "error", ("{name}", "'/scan'", "look like centimetres", "expected metres")),
        Case("carmen_ranges_in_millimetres", _log("ranges_mm.log", bad=_every(scale=1000.0)),
             "error", ("{name}", "r1..rn of the FLASER lines", "look like millimetres", "expected metres")),
        Case("carmen_ranges_in_centimetres_robotlaser1",
             _log("ranges_cm.log", kind="ROBOTLASER1", bad=_every(scale=100.0)),
             "error", ("{name}", "ROBOTLASER1 lines", "look like centimetres", "expected metres")),
        Case("carmen_theta_in_degrees", _log("theta_deg.log", bad=_every(theta_deg=True)),
             "error", ("{name}", "theta of the FLASER lines", "looks like degrees", "expected radians")),
        Case("pcd_yaw_in_degrees", _pcd("pcd_yaw_deg", yaw_deg=True),
             "error", ("locations.csv", "column 'yaw'", "looks like degrees", "expected radians")),
        Case("pcd_folder_in_millimetres", _pcd("pcd_mm", scale=1000.0),
             "error", ("{name}", ".pcd files", "look like millimetres", "expected metres")),
        # --- older classes (issue 24)
        Case("older_truncated_bag", _truncated_bag, "error", ("{name}",), issue=False),
        Case("older_empty_bag", _empty_bag, "error", ("{name}",), issue=False),
        Case("older_carmen_short_line", _short_line_log, "error", ("{name}:5", "FLASER"), issue=False),
        # --- good recordings (controls)
        Case("good_ros1_tf", _bag("good_tf.bag"), "correct", n_index=n, check=MAP_POSE, issue=False),
        Case("good_ros1_pose_topic", _bag("good_topic.bag", pose_topic=True, links=(("odom", "base_link"),)),
             "correct", n_index=n, check=MAP_POSE, issue=False),
        Case("good_ros2_tf", lambda root: _ros2_bag(root, "good_ros2"), "correct", n_index=n, check=MAP_POSE,
             issue=False),
        Case("good_ros1_pointcloud2", _bag("good_cloud.bag", cloud=True), "correct", n_index=n, check=MAP_POSE,
             issue=False),
        Case("good_carmen_flaser", _log("good.log"), "correct", n_index=n, issue=False),
        Case("good_carmen_robotlaser1_gz", _log("good_rl.log.gz", kind="ROBOTLASER1"), "correct", n_index=n,
             issue=False),
        Case("good_pcd_folder", _pcd("pcd_good"), "correct", n_index=40, issue=False),
    ]


# --- running a case ---------------------------------------------------------------------


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.lines: list[str] = []

    def emit(self, record):
        self.lines.append(record.getMessage())


def run_stages(dataset: dict, out: Path) -> Run:
    """Ingest, poses and register on ``dataset`` in ``out``, as the stage scripts run
    them; an error is caught and kept with the paragraph the stage would print."""
    from floorscan.core.config import stage_params
    from floorscan.core.io import POSES, read_metadata, read_table, write_table
    from floorscan.core.stage import failure_message, is_expected_error
    from floorscan.ingest.params import PosesParams
    from floorscan.ingest.poses import missing_poses_line, scan_poses
    from floorscan.ingest.readers import open_recording
    from floorscan.ingest.writer import write_recording
    from floorscan.register.stream import register_recording

    out.mkdir(parents=True, exist_ok=True)
    run = Run(dataset, out)
    collect = _Collect()
    root = logging.getLogger()
    root.addHandler(collect)
    index_path = out / "scan_index.parquet"
    try:
        run.stage = "ingest"
        rec = open_recording(dataset, {}, max_gap_s=0.5)
        index = write_recording(rec, out / "scans.parquet", index_path, out / "pose_stream.parquet",
                                sensor_height_m=dataset.get("sensor_height_m", 0.0),
                                metadata={"dataset": dataset["name"], "source": rec.source})
        run.notes, run.detected, run.index = list(rec.notes), dict(rec.detected), index
        run.stage = "poses"
        stream = read_table(out / "pose_stream.parquet")
        detected = read_metadata(out / "pose_stream.parquet")
        source = f"{detected.get('source', out / 'pose_stream.parquet')} (poses: {detected.get('pose_source', 'none')})"
        params = stage_params(PosesParams, {"max_gap_s": 0.5})
        index = read_table(index_path)
        poses = scan_poses(index, stream, params.max_gap_s, source)
        write_table(poses, out / "poses.parquet", schema=POSES)
        run.poses = poses
        missing = "" if stream.empty else missing_poses_line(poses)
        if missing:
            run.warnings.append(missing)
        run.stage = "register"
        result = register_recording(out / "scans.parquet", index, read_table(out / "poses.parquet"), {},
                                    out / "registered.parquet", metadata={"dataset": dataset["name"]},
                                    recording=read_metadata(index_path))
        run.summary = result.summary
        run.stage = "done"
    except Exception as e:  # noqa: BLE001 - judged below
        run.error = e
        if is_expected_error(e):
            run.message = failure_message(run.stage, e, index_path if run.stage != "ingest" else None)
        else:
            run.message = "".join(traceback.format_exception(e))
    finally:
        root.removeHandler(collect)
    run.warnings += collect.lines
    return run


def _said(run: Run) -> list[tuple[str, str]]:
    """(where, text) of what the run told the user."""
    said = [("notes", n) for n in run.notes] + [("log WARNING", w) for w in run.warnings]
    if run.summary:
        v = run.summary.get("verdict") or {}
        said += [("verdict", w) for w in v.get("warnings", [])] + [("verdict", v.get("line", ""))]
        said += [("verdict", p) for p in v.get("problems", [])]
    return said


def _found(words: tuple[str, ...], text: str) -> list[str]:
    """The words missing from ``text`` (case-insensitive)."""
    low = text.lower()
    return [w for w in words if w.lower() not in low]


def judge(case: Case, run: Run) -> tuple[str, str]:
    """(outcome, detail) of ``case``'s run."""
    path = run.dataset["path"]
    words = tuple(w.replace("{name}", Path(path).name).replace("{path}", path) for w in case.words)
    if run.error is not None:
        from floorscan.core.stage import is_expected_error

        if not is_expected_error(run.error):
            last = run.message.strip().splitlines()[-1]
            return "unclear", f"{run.stage}: unexpected {type(run.error).__name__} (a traceback): {last[:300]}"
        msg = run.message
        form = []
        if "\n" in msg:
            form.append("more than one line")
        if "Traceback" in msg:
            form.append("traceback text")
        if len(msg) > 2000:
            form.append(f"{len(msg)} characters")
        if case.expect == "correct":
            return "unclear", f"{run.stage}: refused a recording that should run: {msg[:400]}"
        missing = _found(words, msg)
        if not missing and not form:
            return "clear", msg[:400]
        return "unclear", f"{run.stage}: missing {missing or ''} {', '.join(form)}: {msg[:400]}"
    # it ran
    problems = []
    if case.n_index is not None and len(run.index) != case.n_index:
        problems.append(f"{len(run.index)} scans in the index, expected {case.n_index}")
    if case.check is not None:
        problem = case.check(run)
        if problem:
            problems.append(problem)
    verdict = (run.summary or {}).get("verdict") or {}
    n_lost = ((verdict.get("losses") or {}).get("counts") or {})
    said = _said(run)
    text = "\n".join(t for _, t in said)
    if case.expect in ("warning", "error"):
        missing = _found(words, text)
        if not missing:
            where = sorted({w for w, t in said if any(x.lower() in t.lower() for x in words)})
            # what to show: the verdict's warning (else the note) naming most of the words
            best = max(said, key=lambda s: (sum(x.lower() in s[1].lower() for x in words), s[0] == "verdict"))
            extra = f" (wrong: {'; '.join(problems)})" if problems else ""
            return "warning", f"named in {', '.join(where)}{extra}: {best[1][:300]}"
        return "silent", (f"ran{' (expected an error)' if case.expect == 'error' else ''}; "
                          f"{'; '.join(problems) + '; ' if problems else ''}"
                          f"missing {missing}; verdict: {verdict.get('line', '')[:250]}")
    # expected a correct run
    if problems:
        return "silent", f"{'; '.join(problems)}; verdict: {verdict.get('line', '')[:250]}"
    if n_lost:
        return "warning", f"lost {n_lost} (expected none): {verdict.get('line', '')[:250]}"
    return "correct", f"{len(run.index)} scans; {verdict.get('line', '').split(';')[0]}"


def run_corpus(root: Path, selected: list[Case], echo: Callable[[str], None] | None = print) -> list[Outcome]:
    """Build and run each case in ``root``; one line per case through ``echo``."""
    outcomes = []
    (root / "in").mkdir(parents=True, exist_ok=True)
    width = max(len(c.name) for c in selected)
    for case in selected:
        t0 = time.perf_counter()
        folder = root / "in" / case.name
        folder.mkdir()
        try:
            dataset = case.build(folder)
        except Exception:  # noqa: BLE001 - a broken builder is the benchmark's bug
            raise RuntimeError(f"building case {case.name} failed") from None
        run = run_stages(dataset, root / "out" / case.name)
        outcome, detail = judge(case, run)
        o = Outcome(case, outcome, run.stage, detail, time.perf_counter() - t0)
        outcomes.append(o)
        if echo:
            echo(f"{outcome:8s} {case.name:{width}s} [{o.seconds:4.1f} s, {case.expect}] {detail}")
    return outcomes


def tally(outcomes: list[Outcome]) -> dict[str, int]:
    return {k: sum(o.outcome == k for o in outcomes) for k in OUTCOMES}


def tally_line(outcomes: list[Outcome]) -> str:
    t = tally(outcomes)
    n_issue = sum(o.case.issue for o in outcomes)
    return (f"{len(outcomes)} recordings ({n_issue} of issues 35 and 45's classes): "
            + " / ".join(f"{k} {t[k]}" for k in OUTCOMES))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks bad_input", description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="*", default=[], help="run the cases whose name contains one of these")
    ap.add_argument("--keep", type=Path, help="write the recordings and outputs here and keep them")
    args = ap.parse_args(argv or [])
    selected = [c for c in cases() if not args.only or any(s in c.name for s in args.only)]
    if args.keep and args.keep.exists() and any(args.keep.iterdir()):
        raise SystemExit(f"--keep {args.keep}: the folder is not empty; name a new or empty one")
    with tempfile.TemporaryDirectory() as tmp:
        outcomes = run_corpus(args.keep or Path(tmp), selected)
    print(tally_line(outcomes))


if __name__ == "__main__":
    main(sys.argv[1:])
