"""Convex hulls of many point groups at once with GEOS (thesis Algorithm 2 step 4).

The hulls stage hands every cluster of every scan to :class:`HullBuilder`, which
makes their convex hulls (Shapely/GEOS, vectorised over all clusters of all scans at
once, in batches of ``batch_points``) and, on demand, the convex hull of each whole
scan (the naive coverage of thesis Fig. 3.2a). A cluster with fewer than 3 points or
only collinear points has no area: it comes out as an empty polygon with area 0.

Exact shortcuts, giving the hulls GEOS gives for the points themselves, bit for bit:

- the points of a group go to GEOS as one LineString (one coordinate sequence)
  instead of a MultiPoint of point geometries: the same convex hull without a
  geometry object per point;
- the convex hull of a scan is that of its cluster hulls' vertices and of its points
  in no cluster hull (outliers): a vertex of the scan's hull is a vertex of the hull
  of the cluster holding it, and GEOS gives the same ring for any point set with the
  same hull (its vertices without collinear points, from the lowest point);
- rows gathered with ``np.take`` / ``np.compress`` rather than fancy indexing, and
  cluster sizes from the sorted labels.

Usage::

    builder = HullBuilder(convex=True)
    builder.add(xy, labels, k)            # per scan: (n, 2) points, labels in -1..k-1
    geoms, areas = builder.finish()       # one hull per group, in order
    convex, convex_areas = builder.finish_convex()  # one hull per scan
"""

from __future__ import annotations

import numpy as np
import shapely


class HullBuilder:
    """Collects the points of groups (scan clusters) and makes their convex
    hulls with GEOS in batches: one LineString per group (the group's points as one
    coordinate sequence; its convex hull is that of the points).

    With ``convex=True`` it also makes the convex hull of every scan added, from the
    vertices of the scan's group hulls and the points in no group hull (outliers,
    groups of one point): a vertex of the scan's hull is a vertex of the hull of the
    group holding it, so these few points have the same hull as the whole scan
    (GEOS keeps the hull's vertices, without collinear points, and starts the ring
    at the lowest point: the same polygon bit for bit).

    Parameters
    ----------
    batch_points : int
        Points handed to GEOS at once (memory against calls).
    convex : bool
        Also make the convex hull of every scan added (:meth:`finish_convex`).
    """

    def __init__(self, batch_points: int = 1 << 20, convex: bool = False):
        self.batch_points = batch_points
        self.convex = convex
        self._xy: list[np.ndarray] = []
        self._n: list[np.ndarray] = []
        self._out: list[np.ndarray] = []
        self._pending = 0
        self.geoms: list[np.ndarray] = []
        self.convex_geoms: list[np.ndarray] = []

    def add(self, xy: np.ndarray, labels: np.ndarray, k: int) -> None:
        """Add the ``k`` groups of one scan.

        Parameters
        ----------
        xy : (n, 2) float ndarray
            The scan's points, metres.
        labels : (n,) int ndarray
            Group of each point in 0..k-1, or -1 (in no group, but inside the scan's convex
            hull).
        k : int
            Number of groups; a group may be empty.
        """
        ok = labels >= 0
        if ok.all():
            keep = None
            lab = labels
        else:
            keep = np.flatnonzero(ok)
            lab = labels[keep]
        # stable sort of small ints: radix sort for int16 (timsort for int64)
        order = np.argsort(lab.astype(np.int16) if k < 2**15 else lab, kind="stable")
        # np.take: faster row gathers than xy[idx] / xy[mask] on (n, 2) arrays
        pts = np.take(xy, order if keep is None else np.take(keep, order), axis=0)
        counts = np.diff(np.searchsorted(np.take(lab, order), np.arange(k + 1)))  # bincount
        self._xy.append(pts)
        self._n.append(counts)
        if self.convex:
            self._out.append(np.zeros((0, 2)) if keep is None else np.compress(~ok, xy[:, :2], axis=0))
        self._pending += len(pts)
        if self._pending >= self.batch_points:
            self._flush()

    @staticmethod
    def _hulls(xy: np.ndarray, counts: np.ndarray) -> np.ndarray:
        """Convex hull of each run of ``counts`` rows of ``xy`` (GEOS geometry: Polygon,
        or LineString/Point when degenerate); an empty Polygon for a run of < 2 rows."""
        geoms = np.full(len(counts), shapely.Polygon(), dtype=object)
        line = counts >= 2  # fewer than 2 points: no LineString, and no area anyway
        n_line = int(line.sum())
        if n_line == len(counts):
            geoms[:] = shapely.convex_hull(shapely.linestrings(xy, indices=np.repeat(np.arange(n_line), counts)))
        elif n_line:
            # points of the groups with a line, and the line's number among them
            sel = np.repeat(line, counts)
            idx = np.repeat(np.arange(n_line), counts[line])
            geoms[line] = shapely.convex_hull(shapely.linestrings(np.compress(sel, xy, axis=0), indices=idx))
        return geoms

    def _flush(self) -> None:
        if not self._n:
            return
        counts = np.concatenate(self._n)
        xy = np.concatenate(self._xy) if len(self._xy) > 1 else self._xy[0]
        geoms = self._hulls(xy, counts)
        self.geoms.append(geoms)
        if self.convex:
            k = np.array([len(n) for n in self._n])
            scan = np.repeat(np.arange(len(k)), k)  # the scan (in this batch) of each group
            line = counts >= 2
            hull_xy, hull_i = shapely.get_coordinates(geoms[line], return_index=True)
            single = counts == 1
            n_out = np.array([len(o) for o in self._out])
            pts = np.concatenate([hull_xy, np.compress(np.repeat(single, counts), xy, axis=0), *self._out])
            sid = np.concatenate([scan[line][hull_i], scan[single], np.repeat(np.arange(len(k)), n_out)])
            order = np.argsort(sid, kind="stable")
            self.convex_geoms.append(self._hulls(np.take(pts, order, axis=0), np.bincount(sid, minlength=len(k))))
        self._xy, self._n, self._out, self._pending = [], [], [], 0

    @staticmethod
    def _polygons(parts: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        geoms = np.concatenate(parts) if parts else np.zeros(0, dtype=object)
        areas = shapely.area(geoms) if len(geoms) else np.zeros(0)
        poly = (shapely.get_type_id(geoms) == 3) & (areas > 0) if len(geoms) else np.zeros(0, bool)
        geoms = np.where(poly, geoms, shapely.Polygon())
        return geoms, np.where(poly, areas, 0.0).astype(np.float64)

    def finish(self) -> tuple[np.ndarray, np.ndarray]:
        """The hulls of every group added, in order.

        Returns
        -------
        geometries : (G,) object ndarray of shapely Polygon
            A hull without area (fewer than 3 points, collinear) is an empty Polygon.
        areas : (G,) float64 ndarray
            Square metres; 0 for an empty Polygon.
        """
        self._flush()
        out = self._polygons(self.geoms)
        self.geoms = []
        return out

    def finish_convex(self) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`finish`, for the convex hull of every scan added (``convex=True``).

        Returns
        -------
        geometries : (S,) object ndarray of shapely Polygon
        areas : (S,) float64 ndarray
            Square metres.
        """
        self._flush()
        out = self._polygons(self.convex_geoms)
        self.convex_geoms = []
        return out
