"""What the exports of a floor plan share (:class:`PlanExports`): the wall footprints
(each axis buffered by half its thickness) oriented as RFC 7946 wants them, their
exterior rings in map metres (:func:`exterior_rings`), the plan's extent, the room
polygons oriented the same way and a label point inside each room, each made once for
all formats, and the IFC model, kept for a plan written again; the footprints of a plan
folder (:func:`read_plan_footprints`), which the figures draw.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

if TYPE_CHECKING:
    from floorscan.floorplan.plan import FloorPlan


#: How near the pole of inaccessibility a room's label point is found, metres.
ROOM_LABEL_TOLERANCE_M = 0.01


@dataclass
class PlanExports:
    """A plan and what its exports share, each made once, on first use: the oriented
    footprints, their rings, the extent, the oriented room polygons and their label
    points, and the IFC model
    (:func:`floorscan.floorplan.ifc._ifc_model`, kept by
    :class:`~floorscan.floorplan.writer.FloorplanWriter` for a plan it writes again).
    The writers of the export formats (:data:`floorscan.floorplan.EXPORT_FORMATS`)
    take one."""

    plan: FloorPlan
    model: Any = None

    @functools.cached_property
    def polys(self):
        """The wall polygons (:meth:`~floorscan.floorplan.plan.FloorPlan.footprints`)
        oriented as RFC 7946 wants them (``shapely.orient_polygons``): counter-clockwise
        exterior rings, clockwise holes (a buffer's exterior is clockwise). Every
        export draws these."""
        import shapely

        return shapely.orient_polygons(self.plan.footprints(), exterior_cw=False)

    @functools.cached_property
    def rings(self) -> list:
        """:func:`exterior_rings` of :attr:`polys`, map metres."""
        return exterior_rings(self.polys)

    @functools.cached_property
    def room_polys(self) -> np.ndarray:
        """The room polygons (``plan.rooms["polygon"]``, map metres), (R,) object
        ndarray of shapely Polygons oriented as RFC 7946 wants them
        (``shapely.orient_polygons``): counter-clockwise exterior rings, clockwise
        holes. A missing polygon stays None; every export skips it and an empty one."""
        import shapely

        polys = np.empty(len(self.plan.rooms), dtype=object)
        polys[:] = self.plan.rooms["polygon"].tolist()
        return shapely.orient_polygons(polys, exterior_cw=False) if len(polys) else polys

    @functools.cached_property
    def room_labels(self) -> np.ndarray:
        """A point inside each room where its label goes, (R, 2) float64 ndarray, map
        metres: the pole of inaccessibility (``shapely.ops.polylabel``, to
        :data:`ROOM_LABEL_TOLERANCE_M`; Agafonkin's polylabel), the point farthest from
        the room's boundary, so a ring corridor's label lies in the corridor, not in
        its hole; NaN for a missing or empty polygon."""
        from shapely.ops import polylabel

        out = np.full((len(self.room_polys), 2), np.nan)
        for k, poly in enumerate(self.room_polys.tolist()):
            if poly is not None and not poly.is_empty:
                p = polylabel(poly, tolerance=ROOM_LABEL_TOLERANCE_M)
                out[k] = p.x, p.y
        return out

    @functools.cached_property
    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Least and greatest ``(x, y)`` of the wall axes, footprints and rooms, metres
        (a plan with walls or rooms, :attr:`has_extent`)."""
        import shapely

        xy = self.plan.walls[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64).reshape(-1, 2)
        lo, hi = np.full(2, np.nan), np.full(2, np.nan)
        if len(xy):
            b = shapely.total_bounds(self.polys)  # NaN when every footprint is empty
            lo, hi = np.fmin(xy.min(axis=0), b[:2]), np.fmax(xy.max(axis=0), b[2:])
        if len(self.room_polys):
            r = shapely.total_bounds(self.room_polys)
            lo, hi = np.fmin(lo, r[:2]), np.fmax(hi, r[2:])
        return lo, hi

    @property
    def has_extent(self) -> bool:
        """Whether the plan has walls or rooms to frame (:attr:`extent` is finite)."""
        return bool(np.isfinite(self.extent[0]).all())


def exterior_rings(polys, transform: Callable[[np.ndarray], np.ndarray] | None = None) -> list:
    """Exterior ring of each footprint as a list of ``[x, y]`` (closed: the first
    point repeated last), or None for a missing or empty footprint.

    The coordinates of all the rings come from one ``shapely.get_coordinates`` call
    (the same doubles as ``poly.exterior.coords``), not a coordinate sequence per wall;
    ``transform`` ((P, 2) -> (P, 2) array, e.g. to longitude and latitude) is applied
    to all of them at once.

    Parameters
    ----------
    polys : (N,) object ndarray of shapely Polygon
        Missing (None) or empty allowed.
    transform : callable, optional
        (P, 2) float64 -> (P, 2), applied to the map metres.

    Returns
    -------
    list
        Per polygon a list of ``[x, y]`` lists, or None.
    """
    import shapely

    out: list = [None] * len(polys)
    ok = np.flatnonzero(~(shapely.is_missing(polys) | shapely.is_empty(polys)))
    if not len(ok):
        return out
    coords, index = shapely.get_coordinates(shapely.get_exterior_ring(polys[ok]), return_index=True)
    if transform is not None:
        coords = transform(coords)
    bounds = np.r_[0, np.cumsum(np.bincount(index, minlength=len(ok)))].tolist()
    pts = coords.tolist()
    for n, k in enumerate(ok.tolist()):
        out[k] = pts[bounds[n] : bounds[n + 1]]
    return out


def read_plan_footprints(folder) -> list:
    """The wall footprints of a plan folder (the evaluation grid's Parquet tables,
    :func:`floorscan.floorplan.scans.read_plan`), one per wall, as the plan's exports
    draw them (:attr:`PlanExports.polys`): the floor plans figure's walls (thesis Fig.
    5.5, :func:`floorscan.figures.floorplans.plot_floorplans`).

    Parameters
    ----------
    folder : path

    Returns
    -------
    list of shapely Polygon
        Map metres, one per row of the plan's walls.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    from floorscan.floorplan.scans import read_plan

    return list(PlanExports(read_plan(folder)).polys)
