"""The TF tree of a bag: its links and the chain from a fixed frame to the scanner.

Links come from ``/tf`` and ``/tf_static`` (several publishers, :func:`read_tf`). A link
that never changes is static, whichever topic carried it; of samples with one stamp the
last one wins, as in tf2. A link's transform at any stamp is interpolated linearly in
translation and by slerp in rotation, as tf2 does (:meth:`TfLink.at`). A frame with
several parents or a loop on the way up from the scanner is an error
(:class:`TfChainError`, naming the frames and the tree's chains), never taken for a
missing chain (:func:`tf_chain`, :func:`walk_up`). The pose streams and the scanner's
mount composed from a chain are :mod:`floorscan.ingest.tf_poses`.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from floorscan.core.io import InputError
from floorscan.core.messages import quoted
from floorscan.ingest.ros_messages import bag_messages, message_label, pose_problem, stamp_ns


TF_TOPICS = ("/tf", "/tf_static")


class TfLink:
    """Samples of one TF link parent -> child: stamps, translations, rotations."""

    def __init__(self, parent: str, child: str):
        self.parent, self.child = parent, child
        self.t: list[int] = []
        self.trans: list[tuple[float, float, float]] = []
        self.quat: list[tuple[float, float, float, float]] = []
        self.static = False
        #: The first bad sample (file, topic, message, field), left out; the link is
        #: refused when a chain uses it (:mod:`floorscan.ingest.tf_poses`).
        self.bad: str | None = None

    def finish(self) -> None:
        if not self.t:  # every sample was bad
            self.t_arr, self.trans_arr, self.rot = np.zeros(0, np.int64), np.zeros((0, 3)), None
            self.t_sent = self.t_arr
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
        #: every stamp the link was sent at (a static link keeps one sample, but a
        #: stationary robot's links are sent as the recording goes)
        self.t_sent = self.t_arr
        if self.static:
            self.t_arr, self.trans_arr, self.rot = self.t_arr[-1:], self.trans_arr[-1:], self.rot[-1:]

    def at(self, t: np.ndarray) -> tuple[Rotation, np.ndarray]:
        """The link's transform at stamps ``t`` (after :meth:`finish`): a static link's one
        sample, else translations interpolated linearly and rotations by Slerp, held at the
        first and last sample outside them.

        Parameters
        ----------
        t : (N,) int ndarray
            Stamps, nanoseconds.

        Returns
        -------
        rot, trans : scipy.spatial.transform.Rotation, (N, 3) float64 ndarray
            N rotations and translations (metres).
        """
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
    """The bag's TF links on ``/tf`` and ``/tf_static``; samples with a bad pose are
    left out, the first noted in ``TfLink.bad``.

    Parameters
    ----------
    reader : rosbags.highlevel.AnyReader
    path : Path

    Returns
    -------
    dict of (str, str) to TfLink
        (parent, child) -> its link, finished; frame names without a leading ``/``.
    """
    conns = [c for c in reader.connections if c.topic in TF_TOPICS]
    edges: dict[tuple[str, str], TfLink] = {}
    seen: dict[str, int] = defaultdict(int)
    for c, bag_t, raw in bag_messages(reader, conns):
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


class TfChainError(InputError):
    """No TF chain from a fixed frame to a frame (one paragraph naming both, the frames
    TF has and its chains). ``kind``: ``several_parents`` (a frame on the way has two or
    more parents), ``loop`` (the way up comes back to a frame), ``missing`` (the frame is
    not on ``/tf`` or ``/tf_static``, or is empty) or ``elsewhere`` (the frame's chain
    starts at another root)."""

    def __init__(self, message: str, kind: str):
        super().__init__(message)
        self.kind = kind


#: At most this many chains and frames are listed in a message.
MAX_LISTED = 12
#: A frame name is quoted up to this many characters.
MAX_NAME = 60


def _name(frame: str) -> str:
    return quoted(frame, MAX_NAME)


def tf_frames(edges) -> list[str]:
    """Every frame named by a TF link (parent or child), sorted.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
        :func:`read_tf`'s links; only the (parent, child) keys are read.

    Returns
    -------
    list of str
        The distinct frame names, sorted.
    """
    return sorted({f for key in edges for f in key})


def _parents(edges) -> dict[str, list[TfLink]]:
    parents: dict[str, list[TfLink]] = defaultdict(list)
    for e in edges.values():
        parents[e.child].append(e)
    return parents


def walk_up(edges, frame: str, stop: str | None = None) -> tuple[list[TfLink], str, str]:
    """The links from ``frame`` up towards its root, nearest first, ending at ``stop``
    (when given and met), at a frame without parent, or at a problem.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
        :func:`read_tf`'s links.
    frame, stop : str
        ``stop`` optional.

    Returns
    -------
    links : list of TfLink
        Parent -> child links, the one whose child is ``frame`` first.
    kind : str
        ``""`` (the walk ended at ``stop`` or a root), ``several_parents`` or ``loop``.
    problem : str
        The problem in words, naming the frames (``""`` without one).
    """
    parents = _parents(edges)
    links: list[TfLink] = []
    seen, cur = [frame], frame
    while cur != stop:
        ps = parents.get(cur, [])
        if len(ps) > 1:
            names = ", ".join(_name(p.parent) for p in sorted(ps, key=lambda e: e.parent))
            return links, "several_parents", (
                f"TF frame {_name(cur)} has several parents ({names}); a TF tree gives each frame one"
            )
        if not ps:
            break
        links.append(ps[0])
        cur = ps[0].parent
        if cur in seen:
            loop = seen[seen.index(cur):] + [cur]
            return links, "loop", "the TF tree has a loop: " + " -> ".join(_name(f) for f in loop[::-1])
        seen.append(cur)
    return links, "", ""


def tf_chains_text(edges, first: tuple[str, ...] = ()) -> str:
    """The chains of the TF tree for people: ``map -> odom -> base_link -> laser; ...``.

    One chain per leaf, from its root (a frame with several parents appears in a chain
    of each); frames on a loop without root are shown as the loop. Chains through a
    frame of ``first`` come first; at most :data:`MAX_LISTED` are listed.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    first : tuple of str

    Returns
    -------
    str
    """
    parents = _parents(edges)
    children: dict[str, list[str]] = defaultdict(list)
    for parent, child in sorted(edges):
        children[parent].append(child)
    frames = tf_frames(edges)
    roots = [f for f in frames if f not in parents]
    chains: list[list[str]] = []
    reached: set[str] = set()

    def down(path: list[str]) -> None:
        reached.add(path[-1])
        nxt = [c for c in children.get(path[-1], []) if c not in path]
        if not nxt:
            chains.append(path)
        for c in nxt:
            down(path + [c])

    for r in roots:
        down([r])
    for f in frames:  # frames under a loop without root: the loop, then the chains from it
        if f in reached:
            continue
        way, cur = [f], f
        while parents.get(cur) and parents[cur][0].parent not in way:
            cur = parents[cur][0].parent
            way.append(cur)
        top = parents[cur][0].parent if parents.get(cur) else cur
        loop = way[way.index(top):] if top in way else [cur]
        chains.append(loop[::-1] + [loop[-1] + " (a loop)"])
        reached.update(loop)
        for m in loop[::-1]:
            for c in children.get(m, []):
                if c not in loop:
                    down([m, c])
    chains.sort(key=lambda c: (not any(f in c for f in first), c))
    out = [" -> ".join(c) for c in chains[:MAX_LISTED]]
    more = f"; and {len(chains) - MAX_LISTED} more" if len(chains) > MAX_LISTED else ""
    return "; ".join(out) + more if out else "none"


def no_chain_error(edges, fixed: str, frame: str, path, kind: str = "", problem: str = "") -> TfChainError:
    """The :class:`TfChainError` saying why there is no chain ``fixed`` -> ``frame``: the
    problem on the way (``kind``, ``problem`` of :func:`walk_up`), else the frame is
    missing or under another root; with the frames TF has and its chains.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    fixed, frame, kind, problem : str
    path : path
        The bag, for the message (``""``: none).

    Returns
    -------
    TfChainError
        Not raised; its ``kind`` is ``kind``, ``missing`` or ``elsewhere``.
    """
    frames = tf_frames(edges)
    stops = ""
    if not kind:
        if frame == "":
            kind, problem = "missing", "the scan's frame_id is empty"
        elif frame not in frames:
            kind, problem = "missing", f"{_name(frame)} is not a frame on /tf or /tf_static"
        else:
            links, _, _ = walk_up(edges, frame)
            root = links[-1].parent if links else frame
            kind, problem = "elsewhere", f"its chain starts at {_name(root)}, not at {_name(fixed)}"
            stops = f" (stops at {_name(root)})"
    listed = ", ".join(_name(f) for f in frames[: 3 * MAX_LISTED]) or "none"
    if len(frames) > 3 * MAX_LISTED:
        listed += f" and {len(frames) - 3 * MAX_LISTED} more"
    where = f"{path}: " if str(path) else ""
    return TfChainError(
        f"{where}no TF chain from {_name(fixed)} to the scan frame {_name(frame)}{stops}: {problem}. "
        f"Frames on /tf and /tf_static: {listed}. Chains: {tf_chains_text(edges, (fixed, frame))}.",
        kind,
    )


def tf_chain(edges, fixed: str, frame: str, path: Path | str = "") -> list[TfLink]:
    """The links of the TF chain ``fixed`` -> ``frame``, from ``fixed`` down.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    fixed, frame : str
    path : path

    Returns
    -------
    list of TfLink
        Empty when ``fixed == frame``.

    Raises
    ------
    TfChainError
        No such chain: a frame on the way with several parents, a loop, ``frame``
        missing (or empty) or under another root. One paragraph naming the frames, the
        frames TF has and its chains.
    """
    links, kind, problem = walk_up(edges, frame, stop=fixed)
    if kind or (frame != fixed and (not links or links[-1].parent != fixed)):
        raise no_chain_error(edges, fixed, frame, path, kind, problem)
    return links[::-1]


def tf_chain_from_root(edges, frame: str) -> list[str]:
    """Frames from the root of ``frame``'s TF tree down to ``frame`` (first parent each).

    Unlike :func:`tf_chain` it never fails: a frame with several parents goes up
    through the first in ``edges``' order, and the way stops before a frame it has
    already passed (a loop).

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
        :func:`read_tf`'s links; only the (parent, child) keys are read.
    frame : str

    Returns
    -------
    list of str
        The root first, ``frame`` last; ``[frame]`` when ``frame`` has no parent (or
        is not in the tree).
    """
    parents: dict[str, str] = {}
    for parent, child in edges:
        parents.setdefault(child, parent)
    out = [frame]
    while out[-1] in parents and parents[out[-1]] not in out:
        out.append(parents[out[-1]])
    return out[::-1]
