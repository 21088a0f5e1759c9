"""The pose graph's edge ICP while the scans are read: :class:`EdgeStream`.

The register stage reads and screens a recording scan by scan
(:mod:`floorscan.register.stream`); the edge ICP of the pose graph
(:func:`floorscan.register.edges.scan_pair_edges`) would take as long again after. So
the pairs of the scans expected to be sampled (from the index and the poses alone) are
aligned in the stage's worker processes as soon as both their clouds have been read, and
:func:`~floorscan.register.edges.scan_pair_edges` later aligns only the pairs that were
not expected (a scan the points dropped after all). Usage::

    with process_pool(workers, preload=("open3d",)) as pool:
        stream = EdgeStream(scan_ids, poses, t_s, params, ("sequential", "loop"), pool)
        for scan_id, cloud in clouds:
            stream.add(scan_id, cloud)
        ahead = stream.finish()
        edges = scan_pair_edges(clouds, poses, t_s, params, ahead=ahead, scan_ids=scan_ids)
"""

from __future__ import annotations

from concurrent.futures import Executor, Future

import numpy as np

from floorscan.register.edges import candidate_pairs, pair_rows
from floorscan.register.params import GraphParams
from floorscan.register.prepare import plane_cloud

#: Pairs per call of :class:`EdgeStream` (a fraction of a second of ICP).
STREAM_BATCH = 100


class EdgeStream:
    """The ICP of :func:`floorscan.register.edges.scan_pair_edges`, run in worker
    processes while the clouds arrive, for the scans expected to be sampled.

    The pairs are :func:`~floorscan.register.edges.candidate_pairs` of the expected
    scans and their initial poses; they are sent in batches of :data:`STREAM_BATCH`,
    each with the clouds of its scans, as soon as both clouds of a pair are here; the
    pool gives each batch to the next free worker.
    :func:`~floorscan.register.edges.scan_pair_edges` then takes the rows of its pairs
    and the projected clouds (``rows``, ``pts``) after :meth:`finish` and aligns only
    pairs that were not expected (a scan dropped after all), so the edges are the same
    as without the stream (tested).

    Parameters
    ----------
    scan_ids : (N,) int array-like
        The scans expected, in time order.
    poses : (N, 4) float ndarray
        Their initial poses ``x, y, z, yaw`` (metres, radians).
    t_s : (N,) float ndarray
        Their times, seconds.
    params : GraphParams
    icp_kinds : tuple of str
        As :func:`~floorscan.register.edges.scan_pair_edges`.
    pool : concurrent.futures.Executor
        The worker processes (:func:`floorscan.core.runtime.process_pool`); the caller
        shuts it down.
    """

    def __init__(self, scan_ids, poses, t_s, params: GraphParams, icp_kinds: tuple[str, ...], pool: Executor):
        ids = [int(s) for s in scan_ids]
        poses = np.asarray(poses, dtype=np.float64)
        self.params, self.icp_kinds = params, icp_kinds
        self.poses = {sid: poses[k] for k, sid in enumerate(ids)}
        self.by_later: dict[int, list[tuple[int, int, str]]] = {}
        for i, j, kind in candidate_pairs(poses, t_s, params):
            self.by_later.setdefault(ids[j], []).append((ids[i], ids[j], kind))
        self.pts: dict[int, np.ndarray] = {}
        self.pool = pool
        self.futures: list[Future] = []
        self.ready: list[tuple[int, int, str]] = []
        #: After :meth:`finish`: the ``EDGE_COLUMNS`` rows by ``(i, j)`` (scan ids).
        self.rows: dict[tuple[int, int], tuple] = {}

    def add(self, scan_id: int, cloud: np.ndarray) -> None:
        """Scan ``scan_id``'s cloud (as for ``scan_pair_edges``) is here: send the
        pairs it completes (with an earlier scan) once a batch is full."""
        sid = int(scan_id)
        self.pts[sid] = p = plane_cloud(cloud, self.params.voxel_size_m)
        if len(p) < 3:
            return
        for pair in self.by_later.get(sid, ()):
            other = self.pts.get(pair[0])
            if other is not None and len(other) >= 3:
                self.ready.append(pair)
        if len(self.ready) >= STREAM_BATCH:
            self._send()

    def _send(self) -> None:
        if not self.ready:
            return
        scans = sorted({k for i, j, _ in self.ready for k in (i, j)})
        clouds = {k: self.pts[k] for k in scans}
        poses = {k: self.poses[k] for k in scans}
        self.futures.append(self.pool.submit(pair_rows, clouds, poses, self.ready, self.params, self.icp_kinds))
        self.ready = []

    def finish(self) -> "EdgeStream":
        """Send the last batch and wait for :attr:`rows` (``i, j`` are scan ids); returns
        self. A worker's exception is raised here."""
        self._send()
        self.rows = {(r[0], r[1]): r for f in self.futures for r in f.result()}
        return self

    def close(self) -> None:
        """Cancel the batches not started (after an error elsewhere)."""
        for f in self.futures:
            f.cancel()
