"""Scans of one topic in several frames: two scanners on one topic, or a frame renamed
mid-recording.

A bag's pose stream is the pose of one frame, the frame of the topic's first scan
(:mod:`floorscan.ingest.rosbag`). A scan in another frame is placed by its own frame's
pose: its points are moved into the first frame by the static transform between the
two frames (:func:`floorscan.ingest.tf_poses.static_between`: both scanners' mounts on
a common frame, e.g. ``base_link -> laser`` and ``base_link -> rear`` on
``/tf_static``), one rigid transform per scan, looked up once per frame. A frame with
no static transform to the first (no TF for it, a renamed frame, a scanner on a moving
link) cannot be placed: ingest reads the topic to the end, to count each frame's
scans, and stops with one message naming the file, the topic and each frame with its
count, and what to do (:meth:`ScanFrames.finish`).

Why place rather than refuse every second frame: a robot with a front and a rear
scanner on one topic, both mounts on ``/tf_static``, is a setup users have, and what
they expect is both scanners in the map; the TF they recorded says exactly where each
scan was taken. A frame that TF does not place is a question only the user can answer
(a rename, or a scanner whose mount was not recorded), so it is refused, never
guessed. Usage::

    frames = ScanFrames(path, topic, first_frame, edges)
    scan = frames.place(scan)      # None: a frame TF does not place (counted)
    ...
    frames.finish(notes, detected) # after the last scan: refuses, or notes the frames
"""

from __future__ import annotations

import dataclasses
import logging
from collections import Counter
from pathlib import Path

import numpy as np

from floorscan.core.io import InputError
from floorscan.ingest.recording import Scan
from floorscan.ingest.tf_chains import tf_chains_text
from floorscan.ingest.tf_poses import static_between

log = logging.getLogger(__name__)


class ScanFrames:
    """The frames of a topic's scans, and each other frame's scans moved into the first.

    Parameters
    ----------
    path : Path
        The bag, for messages.
    topic : str
        The scan topic.
    frame : str
        The frame of the topic's first scan: the frame the pose stream places.
    edges : mapping of (str, str) to TfLink
        The bag's TF links (:func:`floorscan.ingest.tf_chains.read_tf`); empty: none.
    """

    def __init__(self, path: Path, topic: str, frame: str, edges):
        self.path, self.topic, self.frame, self.edges = path, topic, frame, edges
        self.counts: Counter[str] = Counter()
        self.mounts: dict[str, tuple | None] = {}

    def place(self, scan: Scan) -> Scan | None:
        """``scan`` with its points in the first frame, or None when TF does not place
        its frame (it is counted, and :meth:`finish` refuses the recording).

        Parameters
        ----------
        scan : Scan
            Points in ``scan.frame``, metres.

        Returns
        -------
        Scan or None
            A new scan in the first frame (``points`` (N, 3) float32, metres); ``scan``
            itself when it is in the first frame.
        """
        self.counts[scan.frame] += 1
        if scan.frame == self.frame:
            return scan
        if scan.frame not in self.mounts:
            self.mounts[scan.frame] = static_between(self.edges, self.frame, scan.frame)
        mount = self.mounts[scan.frame]
        if mount is None:
            return None
        rot, trans = mount
        pts = rot.apply(np.asarray(scan.points, dtype=np.float64).reshape(-1, 3)) + trans
        return dataclasses.replace(scan, frame=self.frame, points=pts.astype(np.float32))

    def finish(self, notes: list[str], detected: dict) -> None:
        """After the last scan: with several frames, a note and ``detected["scan_frames"]``
        (``laser 15, rear 15``); refuses a frame TF does not place.

        Raises
        ------
        InputError
            A frame with no static transform to the first: names the file, the topic,
            every frame with its count of scans and what to do.
        """
        if len(self.counts) < 2:
            return
        listing = ", ".join(f"{f!r} ({n} scans)" for f, n in self.counts.items())
        detected["scan_frames"] = ", ".join(f"{f} {n}" for f, n in self.counts.items())
        lost = [f for f in self.counts if f != self.frame and self.mounts.get(f) is None]
        if lost:
            names = ", ".join(repr(f) for f in lost)
            tf = f"TF: {tf_chains_text(self.edges, first=(self.frame,))}" if self.edges else "the bag has no TF"
            raise InputError(
                f"{self.path}: topic {self.topic!r} carries scans in {len(self.counts)} frames, {listing}, and no "
                f"static transform links {self.frame!r} to {names} ({tf}), so those scans cannot be placed. Expected "
                "one frame per scan topic, or each scanner's static mount on /tf_static: for a frame renamed during "
                "the recording, rewrite its frame_id to one name (e.g. with rosbags or rosbag filter); for a second "
                f"scanner, record its mount (e.g. base_link -> {lost[0]}) on /tf_static, or publish it on its own "
                "topic and set scan_topic"
            )
        note = (
            f"scans on {self.topic!r} come in {len(self.counts)} frames, {listing}: each placed by its own frame's "
            f"pose (the other frames' scans moved into {self.frame!r} by their static mounts)"
        )
        notes.append(note)
        log.info("%s: %s", self.path, note)
