"""The structure cells searched on the grid give the KD-tree's floats and the brute-force
definitions exactly (floorscan.score.structure_grid)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

import floorscan.score.against_reference as A
from floorscan.core.geometry import point_segment_dist2, sample_segments, samples_per_segment
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams
from floorscan.score import curves as C
from floorscan.score.structure_grid import StructureGrid


def _grid(seed=0, shape=(70, 90), origin=(-1.2345, 0.5678)):
    """A grid whose structure is walls along rows and columns, a diagonal and scattered
    cells, hit by three scans; the other cells free or unknown."""
    rng = np.random.default_rng(seed)
    mask = rng.random(shape) < 0.06
    mask[10, 5:60] = mask[11, 5:60] = mask[5:65, 40] = mask[40:65, 70] = True
    i = np.arange(20, 60)
    mask[i, i + 10] = True
    hit = np.where(mask, 3, 0).astype(np.int32)
    miss = np.where(mask, 0, rng.integers(0, 4, shape)).astype(np.int32)
    return OccupancyGrid(np.array(origin), 0.05, hit, miss, OccupancyParams())


def _faces(grid, rng, n=150):
    """Faces of every kind: random, along rows and columns (some through cell centres),
    diagonal, short, of zero length, partly or wholly off the grid."""
    (x0, y0), r = grid.origin_xy, grid.resolution_m
    h, w = grid.shape
    a = rng.uniform([x0 - 0.3, y0 - 0.3], [x0 + w * r + 0.3, y0 + h * r + 0.3], (n, 2))
    d = rng.normal(0, 1.0, (n, 2))
    d[: n // 4, 1] = 0.0  # along a row
    d[n // 4 : n // 2, 0] = 0.0  # along a column
    d[n // 2 : n // 2 + 10, 1] = d[n // 2 : n // 2 + 10, 0]  # diagonal
    d[-5:] = 0.0  # zero length
    d[-10:-5] *= 0.01
    seg = np.hstack([a, a + d])
    centre_row = y0 + (rng.integers(0, h, 8) + 0.5) * r  # exactly on rows of cell centres
    seg[:8, 1] = seg[:8, 3] = centre_row
    seg[8:12] = [x0 - 2.0, y0 - 2.0, x0 - 1.0, y0 - 2.5]  # far off the grid
    along = rng.uniform(-0.06, 0.06, 20)  # along the walls of the rows 10-11 and the column 40
    seg[12:22] = np.column_stack([x0 + rng.uniform(0, 1, 10), y0 + 11 * r + along[:10], x0 + rng.uniform(2, 3.5, 10),
                                  y0 + 11 * r + along[:10] + rng.normal(0, 0.02, 10)])
    seg[n // 4 : n // 4 + 10] = np.column_stack([x0 + 40.5 * r + along[10:], y0 + rng.uniform(0, 1, 10),
                                                 x0 + 40.5 * r + along[10:], y0 + rng.uniform(2, 3.5, 10)])
    return seg


def _brute_nearest(xy, points, bound):
    d2 = ((points[:, None, 0] - xy[None, :, 0]) ** 2 + (points[:, None, 1] - xy[None, :, 1]) ** 2).min(axis=1)
    d = np.sqrt(d2)
    return np.where(d < bound, d, np.inf)


class _CountingTree:
    def __init__(self, tree):
        self.tree, self.asked = tree, 0

    def query(self, points, **kw):
        self.asked += len(points)
        return self.tree.query(points, **kw)


def test_nearest_is_the_kd_trees_query_to_the_bit():
    """Points anywhere (on cell centres and edges, off the grid, beyond the bound) get
    the KD-tree's distances exactly, most of them without the tree."""
    rng = np.random.default_rng(1)
    for seed in range(3):
        grid = _grid(seed)
        ref = A.Structure(grid)
        tree = _CountingTree(ref.tree)
        cells = StructureGrid(grid, grid.structure(), tree)
        (x0, y0), r = grid.origin_xy, grid.resolution_m
        h, w = grid.shape
        pts = rng.uniform([x0 - 0.2, y0 - 0.2], [x0 + w * r + 0.2, y0 + h * r + 0.2], (20000, 2))
        # cell centres and edges
        on_lattice = np.column_stack([x0 + rng.integers(-2, 2 * w + 2, 3000) * r / 2,
                                      y0 + rng.integers(-2, 2 * h + 2, 3000) * r / 2])
        pts = np.vstack([pts, on_lattice, sample_segments(_faces(grid, rng), 0.02)])
        for bound in (1.0, 0.2, 0.03, np.inf):
            tree.asked = 0
            got = cells.nearest(pts, bound)
            assert np.array_equal(got, ref.tree.query(pts, k=1, distance_upper_bound=bound)[0])
            assert np.array_equal(got, _brute_nearest(ref.xy, pts, bound))
            assert tree.asked < 0.4 * len(pts) if bound > 0.1 else tree.asked > 0.5 * len(pts)  # the grid settles most
        assert np.isinf(cells.nearest(pts, 1.0)).any() and (cells.nearest(pts, 1.0) == 0).any()


def test_near_cells_of_faces_are_the_definition():
    """The cells within the bound of a face's samples (and their distance to the nearest
    sample) are those of every sample against every cell, by face and by cell; the
    candidates hold every cell within reach of the face's segment."""
    rng = np.random.default_rng(2)
    for seed in range(3):
        grid = _grid(seed)
        ref = A.Structure(grid)
        seg = _faces(grid, rng)
        for sample_m, tau in ((0.02, 0.10), (0.02, 0.05), (0.05, 0.03)):
            bound = A.within_bound(tau, sample_m)
            n = samples_per_segment(seg, sample_m)
            starts = np.r_[0, np.cumsum(n)]
            samples = sample_segments(seg, sample_m)
            cell, face, distance = A._cells_near_samples(ref, seg, samples, starts, bound)
            want_cell, want_face, want_distance = [], [], []
            for f in range(len(seg)):
                s = samples[starts[f] : starts[f + 1]]
                dx, dy = ref.xy[:, None, 0] - s[None, :, 0], ref.xy[:, None, 1] - s[None, :, 1]
                d = np.sqrt(dx * dx + dy * dy).min(axis=1)
                near = np.flatnonzero(d <= bound)
                want_cell.append(near), want_face.append(np.full(len(near), f)), want_distance.append(d[near])
            assert np.array_equal(cell, np.concatenate(want_cell))
            assert np.array_equal(face, np.concatenate(want_face))
            assert np.array_equal(distance, np.concatenate(want_distance))
            assert len(cell) > 300
            reach = bound * (1 + 1e-6) + 1e-9
            cand_cell, cand_face = ref.cells.segment_cells(seg, reach)
            key = cand_face * len(ref.xy) + cand_cell
            assert np.all(np.diff(key) > 0)  # by face, by cell, once each
            f, c = np.divmod(np.arange(len(seg) * len(ref.xy)), len(ref.xy))
            within = point_segment_dist2(ref.xy[c, 0], ref.xy[c, 1], seg[f]) <= reach * reach
            assert np.isin(f[within] * len(ref.xy) + c[within], key).all()


def test_scan_cover_is_the_pairs_of_the_kd_trees():
    """Each scan's covered cells are those cKDTree.sparse_distance_matrix pairs with its
    segments' samples."""
    rng = np.random.default_rng(3)
    grid = _grid(4)
    structure = A.Structure(grid)
    seg = _faces(grid, rng, 200)
    per_scan = pd.DataFrame(seg, columns=["x0", "y0", "x1", "y1"])
    per_scan.insert(0, "scan_id", np.sort(rng.integers(0, 30, len(seg))))
    for tau, sample_m in ((0.05, 0.05), (0.10, 0.02)):
        got = C.scan_cover(per_scan, list(range(32)), structure, tau, sample_m)
        samples = sample_segments(seg, sample_m)
        scan = np.repeat(per_scan["scan_id"].to_numpy(), samples_per_segment(seg, sample_m))
        bound = A.within_bound(tau, sample_m)
        pairs = cKDTree(samples).sparse_distance_matrix(structure.tree, bound, output_type="ndarray")
        for s in range(32):
            want = np.unique(pairs["j"][scan[pairs["i"]] == s])
            assert np.array_equal(got[s], want), s
        assert sum(len(v) for v in got.values()) > 500
