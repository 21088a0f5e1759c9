"""Cloud preparation: the clouds of a scan that registration aligns and measures.

- :func:`voxel_downsample`: mean of the points per voxel (Open3D's
  ``voxel_down_sample`` up to point order);
- :func:`normals_2d` (PCA of k neighbours in the xy plane) and :func:`normals_3d`
  (Open3D) for point-to-plane ICP;
- :func:`scan_clouds`: fitness source and reference and ICP cloud of a scan
  (``reference: map``, ``previous``, odometry), 2D and 3D;
- :func:`graph_cloud`: a scan projected to the xy plane for the pose graph (the vertical
  structures of a 3D scan, by the height-extent test of 2.5D elevation maps);
- :func:`plane_cloud`: a cloud as the pose graph's edge ICP aligns it;
- :class:`ScanStore`: these clouds per scan, computed from the points on demand or
  kept while the points stream by.

Usage::

    store = ScanStore(cfg)                              # cfg: RegistrationConfig
    store.add(scan_id, points, ("graph",))              # while streaming
    cloud = store.graph(scan_id)

A new kind of cloud is a function here and a kind in :meth:`ScanStore._compute`.
Sources: thesis 3.5 (2D scans, raw points); Zhang and Singh 2014 (LOAM) and Vizzo et
al. 2023 (KISS-ICP) for registering selected or downsampled points; Fankhauser et al.
2014 for the height-extent test.
"""

from __future__ import annotations

from typing import Any, Mapping, NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.grid import cell_groups, cell_keys, cell_means
from floorscan.core.runtime import one_openmp_thread
from floorscan.register.params import RegistrationConfig

#: 3D scans: ICP points whose normal has |z| above this (within 45 degrees of vertical,
#: floor and ceiling) are dropped (:func:`scan_clouds`).
_MAX_NORMAL_Z = 0.7


def voxel_downsample(points: np.ndarray, voxel_size: float) -> np.ndarray:
    """Mean of the points in each occupied voxel (cubes of side ``voxel_size``).

    Deterministic (voxels in lexicographic order of their integer keys), same result as
    Open3D's ``voxel_down_sample`` up to point order. ``voxel_size <= 0`` returns a copy.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Metres.
    voxel_size : float
        Voxel side, metres.

    Returns
    -------
    (M, 3) float64 ndarray, M <= N
    """
    p = np.asarray(points, dtype=np.float64)
    if voxel_size <= 0 or len(p) == 0:
        return p.copy()
    return cell_means(p, voxel_size)[0]


def normals_2d(points: np.ndarray, tree: cKDTree, k: int) -> np.ndarray:
    """Unit normals in the xy plane of a 2D scan or map, from PCA of k nearest neighbours.

    Open3D's ``estimate_normals`` returns the plane normal (z) for coplanar points, which
    is useless for 2D point-to-plane ICP; this is its 2D counterpart.

    Parameters
    ----------
    points : (N, 3) float64 ndarray
        Points (z ignored), metres; ``tree`` is built on their xy (or xyz with z = 0).
    tree : scipy.spatial.cKDTree
    k : int
        Neighbours per point (including itself).

    Returns
    -------
    (N, 3) float64 ndarray
        Normals with z = 0.
    """
    k = int(min(k, len(points)))
    _, idx = tree.query(points, k=k)
    nb = points[np.asarray(idx).reshape(len(points), k)][:, :, :2]
    nb = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", nb, nb)
    _, vecs = np.linalg.eigh(cov)
    n = np.zeros((len(points), 3))
    n[:, :2] = vecs[:, :, 0]
    return n


def normals_3d(points: np.ndarray, k: int) -> np.ndarray:
    """Unit normals of a 3D point cloud (Open3D ``estimate_normals``, k nearest neighbours).

    Returns
    -------
    (N, 3) float64 ndarray
    """
    import open3d as o3d

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, dtype=np.float64)))
    with one_openmp_thread():  # deterministic, and less CPU time on shared cores
        pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=int(k)))
    return np.asarray(pc.normals).copy()


class ScanClouds(NamedTuple):
    """The clouds of one scan used by registration (scanner frame, float64 metres):
    ``fit_source`` is the scan whose fitness is measured, ``fit_target`` the scan as a
    fitness reference, ``icp`` the ICP source and, placed, the material of the ICP
    targets of other scans."""

    fit_source: np.ndarray
    fit_target: np.ndarray
    icp: np.ndarray


def scan_clouds(points: np.ndarray, cfg: RegistrationConfig) -> ScanClouds:
    """The clouds of a scan used for fitness and ICP (see :class:`ScanClouds`).

    2D scans (z constant): all points for fitness (source and reference), the points on
    the ``voxel_size_m`` grid for ICP, as the thesis (3.5) fits raw 2D scans.

    3D scans (a 16-beam scan has ~14k points): as fitness reference the scan on the
    ``voxel_size_m`` grid; as fitness source and for ICP the coarser
    ``icp_voxel_size_3d_m`` grid. A coarse source against a fine reference keeps the
    fitness unbiased (a voxel centroid of a surface lies on it, and the fine reference
    has a point near it) while the KD-tree queries drop from ~6k to ~1k per scan; the
    fitness becomes the fraction of occupied voxels, not of points, so near ranges weigh
    less. ICP also drops horizontal surfaces: points whose normal (Open3D,
    ``normal_neighbours``) is within 45 degrees of vertical (|n_z| > 0.7). The ICP is
    planar (x, y, yaw) and floor and ceiling carry no information about it: a floor point
    matched to the nearest floor point of another scan only pulls the pose toward zero
    motion (the sampling bias of point-to-point ICP) and costs a query per iteration.
    ICP targets are the other scans' ICP clouds, placed and merged (more accurate and
    faster than targets on the fine grid). None of this is in the thesis (its scans are
    2D); LOAM-style odometry likewise registers selected geometric features only (Zhang
    and Singh 2014), KISS-ICP a voxel-downsampled scan (Vizzo et al. 2023).

    Parameters
    ----------
    points : (N, 3) float ndarray
        Scanner frame, metres.
    cfg : RegistrationConfig

    Returns
    -------
    ScanClouds
        New arrays; for a 2D scan ``fit_source`` and ``fit_target`` are one array.
    """
    p = np.array(points, dtype=np.float64)
    if len(p) == 0 or np.ptp(p[:, 2]) == 0:
        return ScanClouds(p, p, voxel_downsample(p, cfg.voxel_size_m))
    coarse, vertical, _ = _vertical_voxels(p, cfg)
    return ScanClouds(coarse, voxel_downsample(p, cfg.voxel_size_m), coarse[vertical])


def _vertical_voxels(p: np.ndarray, cfg: RegistrationConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 3D scan on the ``icp_voxel_size_3d_m`` grid: voxel centroids, which voxels are
    not horizontal surfaces (normal |z| <= 0.7; all when too few are), and each point's
    voxel (index into the centroids)."""
    coarse, inverse = cell_means(p, cfg.icp_voxel_size_3d_m)
    vertical = np.ones(len(coarse), dtype=bool)
    if len(coarse) > cfg.normal_neighbours:
        v = np.abs(normals_3d(coarse, cfg.normal_neighbours)[:, 2]) <= _MAX_NORMAL_Z
        if v.sum() >= 3:
            vertical = v
    return coarse, vertical, inverse


def graph_cloud(points: np.ndarray, cfg: RegistrationConfig) -> np.ndarray:
    """The points of a scan the pose graph (``reference: graph``) aligns, in the xy plane.

    A 2D scan: all its points. A 3D scan: projected to the xy plane (z = 0) on a 2D grid
    of ``graph.voxel_size_m``, keeping the cells whose points span at least
    ``graph.vertical_extent_m`` in height without a gap wider than
    ``graph.max_height_gap_m`` (the vertical structures: walls, furniture sides), each
    as the mean of its points. The pose refinement is planar (x, y, yaw),
    so the walls' heights carry nothing for it, and the projection is the standard
    practice of 2D SLAM on a 3D LIDAR (``pointcloud_to_laserscan``). Floor and ceiling
    drop out: a floor cell holds the returns of one beam ring at one height, while the
    beams stacked at one azimuth hit a wall cell at many heights (a 16-beam scanner's
    2-degree spacing is 3.5 cm of height per metre of range). They must drop out,
    because a floor point matched to the nearest floor point of another scan pulls the
    planar ICP toward zero motion. The gap limit keeps out the cells where a ring of
    floor returns and a ring of ceiling returns happen to meet in xy (their extent is
    the room height: a ring of such cells would move with the scanner and pull the ICP
    toward zero motion as the floor does) and doorways (floor and lintel), and keeps a
    box side with the ceiling above it. The 0.5 m default keeps a wall of a 2-degree
    16-beam scanner to 14 m range. This height-extent
    test is the obstacle test of 2.5D elevation maps, a cell's max minus min height
    (e.g. Fankhauser et al. 2014). The edge ICP then runs as for a 2D scan.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Scanner frame, metres.
    cfg : RegistrationConfig

    Returns
    -------
    (M, 3) float64 ndarray
        New array: a 2D scan's points (M = N), or a 3D scan's kept cell means with
        z = 0 (M much smaller than N for a 16-beam scan), cells in
        lexicographic order; with ``graph.voxel_size_m`` 0 the points of the kept
        0.05 m cells themselves.
    """
    p = np.array(points, dtype=np.float64)
    if len(p) == 0 or np.ptp(p[:, 2]) == 0:
        return p
    params = cfg.graph_params
    cell = params.voxel_size_m if params.voxel_size_m > 0 else 0.05
    xy_cells = np.floor(p[:, :2] / cell).astype(np.int64)
    key = cell_keys(xy_cells)
    if key is None:  # an extent beyond the int64 key: the cells' ranks instead
        key = cell_groups(xy_cells)[0]
    order = _cell_height_order(key, p[:, 2])
    z, ks = p[order, 2], key[order]
    new_cell = np.ones(len(ks), dtype=bool)
    new_cell[1:] = ks[1:] != ks[:-1]
    cells = np.cumsum(new_cell) - 1
    inverse = np.empty(len(p), dtype=np.intp)
    inverse[order] = cells
    counts = np.diff(np.append(np.flatnonzero(new_cell), len(ks)))
    g = len(counts)
    # runs: the heights of a cell without a gap wider than max_height_gap_m
    start = np.ones(len(z), dtype=bool)
    start[1:] = (cells[1:] != cells[:-1]) | (np.diff(z) > params.max_height_gap_m)
    first = np.flatnonzero(start)
    last = np.append(first[1:] - 1, len(z) - 1)
    extent = np.zeros(g)
    np.maximum.at(extent, cells[first], z[last] - z[first])
    vertical = extent >= params.vertical_extent_m
    if params.voxel_size_m <= 0:
        q = p[vertical[inverse]]
        q[:, 2] = 0.0
        return q
    xy = np.column_stack([np.bincount(inverse, weights=p[:, i], minlength=g) for i in (0, 1)]) / counts[:, None]
    return np.column_stack([xy[vertical], np.zeros(int(vertical.sum()))])


def _cell_height_order(key: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The order of the points by cell key, then height: ``numpy.lexsort((z, key))``
    up to the order of equal heights in a cell. Heights that are float32 values (as
    ``scans.parquet`` stores them) and keys below 2**31 make one int64 key, the cell
    above the float32 bits mapped to an order-preserving unsigned integer, sorted in
    one argsort: ten times faster than the lexsort, which was most of
    :func:`graph_cloud`'s time."""
    z32 = z.astype(np.float32)
    if len(key) == 0 or int(key.max()) >= 2**31 or not np.array_equal(z32, z):
        return np.lexsort((z, key))
    bits = z32.view(np.uint32).astype(np.int64)
    # IEEE order: negative floats reversed below the positive ones
    ordered = np.where(bits >= 2**31, 2**32 - 1 - bits, bits + 2**31)
    return np.argsort((key.astype(np.int64) << 32) | ordered)


def plane_cloud(cloud: np.ndarray, voxel_size_m: float) -> np.ndarray:
    """A cloud as ICP aligns it: projected to xy (z = 0: Open3D's 6-DoF ICP then stays
    planar), voxel-downsampled; (M, 3) float64."""
    p = np.array(cloud, dtype=np.float64).reshape(-1, 3)
    p[:, 2] = 0.0
    return voxel_downsample(p, voxel_size_m)


class ScanStore:
    """The clouds registration needs per scan (:func:`graph_cloud`, :func:`scan_clouds`
    and its ICP cloud), from the raw points (``raw``, computed on demand) or stored by
    :meth:`add` while streaming, which keeps only these small clouds (memory follows the
    largest scan, not the recording)."""

    def __init__(self, cfg: RegistrationConfig, raw: Mapping[int, np.ndarray] | None = None):
        self.cfg = cfg
        self.raw = raw if raw is not None else {}
        self.stored: dict[str, dict[int, Any]] = {"graph": {}, "clouds": {}, "icp": {}}

    def add(self, sid: int, points: np.ndarray, needs: tuple[str, ...]) -> None:
        for kind in needs:
            self.stored[kind][sid] = self._compute(kind, points)

    def _compute(self, kind: str, points: np.ndarray):
        if kind == "graph":
            return graph_cloud(points, self.cfg)
        if kind == "clouds":
            return scan_clouds(points, self.cfg)
        return scan_clouds(points, self.cfg).icp

    def _get(self, kind: str, sid: int):
        got = self.stored[kind].get(sid)
        return got if got is not None else self._compute(kind, self.raw[sid])

    def graph(self, sid: int) -> np.ndarray:
        return self._get("graph", sid)

    def clouds(self, sid: int) -> ScanClouds:
        return self._get("clouds", sid)

    def icp(self, sid: int) -> np.ndarray:
        return self._get("icp", sid)

    def map_cloud(self, sid: int) -> np.ndarray:
        """The cloud the map's consistency is measured on: the graph cloud, or else the
        stored cloud there is (fitness reference, ICP cloud), or the graph cloud of the
        raw points."""
        for kind in ("graph", "clouds", "icp"):
            got = self.stored[kind].get(sid)
            if got is not None:
                return got.fit_target if kind == "clouds" else got
        return self.graph(sid)
