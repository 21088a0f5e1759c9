"""The TF tree of a bag: its links, the chain from a fixed frame to the scanner, pose streams.

Links come from ``/tf`` and ``/tf_static`` (several publishers, :func:`read_tf`). A link
that never changes is static, whichever topic carried it; of samples with one stamp the
last one wins, as in tf2. A chain's pose composes its links, each interpolated at the
union of the moving links' stamps, linearly in translation and by slerp in rotation, as
tf2 does (:func:`tf_pose_stream`); samples inside a gap of a moving link are left out.
The mount of the scanner on the base is the chain of static links between them
(:func:`static_transform`). A link with a bad sample
(:func:`floorscan.ingest.ros_messages.pose_problem`) is refused only when a chain uses
it. A pose stream whose scanner is tilted more than :data:`MAX_TILT_DEG` from level is
refused (:func:`planar_pose_stream`).
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from floorscan.core.io import InputError
from floorscan.ingest.recording import pose_stream_frame
from floorscan.ingest.ros_messages import message_label, pose_problem, stamp_ns


TF_TOPICS = ("/tf", "/tf_static")
#: A scanner tilted more than this (degrees) cannot be treated as planar.
MAX_TILT_DEG = 10.0


def planar_pose_stream(t, rot: Rotation, trans, what: str):
    """Pose stream of a chain of 3D poses, refusing a tilted scanner."""
    mat = rot.as_matrix()
    tilt = np.degrees(np.arccos(np.clip(mat[:, 2, 2], -1.0, 1.0)))
    if np.max(tilt) > MAX_TILT_DEG:
        raise InputError(
            f"{what}: the scanner is tilted {np.max(tilt):.1f} deg from level; floorscan expects a level "
            f"scanner (tilt under {MAX_TILT_DEG} deg)"
        )
    yaw = np.arctan2(mat[:, 1, 0], mat[:, 0, 0])
    return pose_stream_frame(t, trans[:, 0], trans[:, 1], trans[:, 2], yaw)


class TfLink:
    """Samples of one TF link parent -> child: stamps, translations, rotations."""

    def __init__(self, parent: str, child: str):
        self.parent, self.child = parent, child
        self.t: list[int] = []
        self.trans: list[tuple[float, float, float]] = []
        self.quat: list[tuple[float, float, float, float]] = []
        self.static = False
        #: The first bad sample (file, topic, message, field), left out; the link is
        #: refused when a chain uses it (:func:`_check_links`).
        self.bad: str | None = None

    def finish(self) -> None:
        if not self.t:  # every sample was bad
            self.t_arr, self.trans_arr, self.rot = np.zeros(0, np.int64), np.zeros((0, 3)), None
            return
        t = np.asarray(self.t, dtype=np.int64)
        order = np.argsort(t, kind="stable")
        t, trans, quat = t[order], np.asarray(self.trans)[order], np.asarray(self.quat)[order]
        keep = np.r_[t[1:] != t[:-1], True]  # duplicate stamps: the last one wins, as in tf2
        self.t_arr, self.trans_arr = t[keep], trans[keep]
        self.rot = Rotation.from_quat(quat[keep])
        # a link that never changes is static, whichever topic carried it
        if not self.static and len(self.t_arr) > 0:
            same = np.allclose(self.trans_arr, self.trans_arr[0], atol=1e-9) and np.allclose(
                (self.rot * self.rot[0].inv()).magnitude(), 0.0, atol=1e-9
            )
            self.static = bool(same)
        if self.static:
            self.t_arr, self.trans_arr, self.rot = self.t_arr[-1:], self.trans_arr[-1:], self.rot[-1:]

    def at(self, t: np.ndarray) -> tuple[Rotation, np.ndarray]:
        if self.static:
            return Rotation.from_quat(np.repeat(self.rot.as_quat(), len(t), axis=0)), np.repeat(
                self.trans_arr, len(t), axis=0
            )
        tt = t.astype(np.float64)
        ts = self.t_arr.astype(np.float64)
        trans = np.stack([np.interp(tt, ts, self.trans_arr[:, k]) for k in range(3)], axis=1)
        rot = Slerp(ts, self.rot)(np.clip(tt, ts[0], ts[-1])) if len(ts) > 1 else self.rot
        return rot, trans


def read_tf(reader, path: Path) -> dict[tuple[str, str], TfLink]:
    """The bag's TF links on ``/tf`` and ``/tf_static``, (parent, child) -> link."""
    conns = [c for c in reader.connections if c.topic in TF_TOPICS]
    edges: dict[tuple[str, str], TfLink] = {}
    seen: dict[str, int] = defaultdict(int)
    for c, bag_t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, c.msgtype)
        index = seen[c.topic]
        seen[c.topic] += 1
        for tr in msg.transforms:
            key = (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"))
            e = edges.get(key)
            if e is None:
                e = edges[key] = TfLink(*key)
            e.static |= c.topic == "/tf_static"
            t_ns = stamp_ns(tr.header, bag_t)
            v, q = tr.transform.translation, tr.transform.rotation
            trans, quat = (v.x, v.y, v.z), (q.x, q.y, q.z, q.w)
            bad = pose_problem(trans, quat, "transform", ("translation", "rotation"))
            if bad:
                if e.bad is None:
                    e.bad = f"{message_label(path, c.topic, index, t_ns)}: TransformStamped {key[0]} -> {key[1]}: {bad}"
                continue
            e.t.append(t_ns)
            e.trans.append(trans)
            e.quat.append(quat)
    for e in edges.values():
        e.finish()
    return edges


def _chain(edges: dict[tuple[str, str], TfLink], fixed: str, frame: str, path: Path) -> list[TfLink]:
    parents: dict[str, list[TfLink]] = defaultdict(list)
    for e in edges.values():
        parents[e.child].append(e)
    chain, cur, seen = [], frame, set()
    while cur != fixed:
        ps = parents.get(cur, [])
        if len(ps) > 1:
            raise InputError(
                f"{path}: TF frame {cur!r} has several parents {[p.parent for p in ps]}; expected a tree"
            )
        if not ps or cur in seen:
            frames = sorted({f for k in edges for f in k})
            raise InputError(
                f"{path}: no TF chain from {fixed!r} to the scan frame {frame!r} (stops at {cur!r}); "
                f"frames on /tf and /tf_static: {frames}"
            )
        seen.add(cur)
        chain.append(ps[0])
        cur = ps[0].parent
    return chain[::-1]


def tf_chain_or_none(edges, fixed: str, frame: str) -> list[TfLink] | None:
    """The chain of links from ``fixed`` to ``frame``, or None when there is none."""
    if fixed == frame:
        return None
    try:
        return _chain(edges, fixed, frame, Path())
    except InputError:
        return None


def tf_chain_from_root(edges, frame: str) -> list[str]:
    """Frames from the root of ``frame``'s TF tree down to ``frame`` (first parent each)."""
    parents: dict[str, str] = {}
    for parent, child in edges:
        parents.setdefault(child, parent)
    out = [frame]
    while out[-1] in parents and parents[out[-1]] not in out:
        out.append(parents[out[-1]])
    return out[::-1]


def _check_links(chain: list[TfLink]) -> None:
    """Refuse a chain with a link that had a bad sample (its message names it)."""
    for e in chain:
        if e.bad is not None:
            raise InputError(e.bad)


def static_transform(edges, base: str, frame: str):
    if base == frame:
        return Rotation.identity(), np.zeros(3)
    try:
        chain = _chain(edges, base, frame, Path())
    except InputError:
        return None
    _check_links(chain)
    if not all(e.static for e in chain):
        return None
    rot, trans = Rotation.identity(), np.zeros(3)
    for e in chain:
        trans = trans + rot.apply(e.trans_arr[0])
        rot = rot * e.rot[0]
    return rot, trans


def tf_pose_stream(edges, path: Path, fixed: str, frame: str, max_gap_s: float):
    """Pose stream of the TF chain ``fixed`` -> ``frame`` and the chain's links."""
    if not edges:
        raise InputError(f"{path}: pose.source is 'tf' but the bag has no /tf or /tf_static messages")
    chain = _chain(edges, fixed, frame, path)
    _check_links(chain)
    moving = [e for e in chain if not e.static]
    if not moving:
        raise InputError(f"{path}: the TF chain {fixed!r} -> {frame!r} never changes; the scanner does not move")
    lo = max(e.t_arr[0] for e in moving)
    hi = min(e.t_arr[-1] for e in moving)
    t = np.unique(np.concatenate([e.t_arr for e in moving]))
    keep = (t >= lo) & (t <= hi)
    gap_ns = int(max_gap_s * 1e9)
    for e in moving:
        d = np.diff(e.t_arr)
        for i in np.flatnonzero(d > gap_ns):
            keep &= ~((t > e.t_arr[i]) & (t < e.t_arr[i + 1]))
    t = t[keep]
    if t.size == 0:
        raise InputError(f"{path}: the moving TF links {[(e.parent, e.child) for e in moving]} do not overlap in time")
    rot, trans = Rotation.identity(len(t)), np.zeros((len(t), 3))
    for e in chain:
        r_e, t_e = e.at(t)
        trans = trans + rot.apply(t_e)
        rot = rot * r_e
    return planar_pose_stream(t, rot, trans, f"{path}: TF chain {fixed!r} -> {frame!r}"), chain
