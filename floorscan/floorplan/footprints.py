"""What the exports of a floor plan share (:class:`PlanExports`): the wall footprints
(each axis buffered by half its thickness) oriented as RFC 7946 wants them, their
exterior rings in map metres (:func:`_exterior_rings`) and the plan's extent, each made
once for all formats, and the IFC model, kept for a plan written again.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

if TYPE_CHECKING:
    from floorscan.floorplan.plan import FloorPlan


@dataclass
class PlanExports:
    """A plan and what its exports share, each made once, on first use: the oriented
    footprints, their rings, the extent and the IFC model
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
        """:func:`_exterior_rings` of :attr:`polys`, map metres."""
        return _exterior_rings(self.polys)

    @functools.cached_property
    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Least and greatest ``(x, y)`` of the wall axes and footprints, metres (a
        plan with walls)."""
        import shapely

        xy = self.plan.walls[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64).reshape(-1, 2)
        b = shapely.total_bounds(self.polys)  # NaN when every footprint is empty
        return np.fmin(xy.min(axis=0), b[:2]), np.fmax(xy.max(axis=0), b[2:])


def _exterior_rings(polys, transform: Callable[[np.ndarray], np.ndarray] | None = None) -> list:
    """Exterior ring of each footprint as a list of ``[x, y]`` (closed: the first
    point repeated last), or None for a missing or empty footprint.

    The coordinates of all the rings come from one ``shapely.get_coordinates`` call
    (the same doubles as ``poly.exterior.coords``), not a coordinate sequence per wall;
    ``transform`` ((P, 2) -> (P, 2) array, e.g. to longitude and latitude) is applied
    to all of them at once.
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
