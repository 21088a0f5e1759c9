"""The raster the rooms of a floor plan are cut from (:mod:`floorscan.floorplan.rooms`,
steps 1 and 2): :class:`RoomParams` (config ``floorplan.rooms`` and constants), the space the plan's
scans saw free bounded by its walls (:func:`room_space`, a :class:`RoomRaster`) and its
watershed regions (:func:`space_regions`). Source: the distance-transform room
segmentation of Bormann et al., ICRA 2016 (see :mod:`floorscan.floorplan.rooms`).
"""


from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.config import schema_defaults
from floorscan.core.grid import raster_cells, unique_ints
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.free_space import passable
from floorscan.floorplan.outline import building_outside


# The room segmentation's thresholds (floorscan.floorplan.rooms; Bormann et al., ICRA 2016); the door widths and
# the smallest room are options (config floorplan.rooms).
#: Cell of the room raster, metres (rounded to whole occupancy cells): finer than a door, coarse enough for a quick watershed.
RESOLUTION_M = 0.1
#: The seen free space is opened by a disc of this radius, metres: fans of rays narrower than 0.3 m (windows) are no space.
FREE_OPEN_M = 0.15
#: The space is closed with the walls by a disc of this radius, metres: unseen strips behind furniture join the room.
CLOSE_M = 0.4
#: A maximum of the distance to the walls seeds a region when this far above the saddles around it, metres: a door's jambs.
MARKER_DEPTH_M = 0.15
#: A door lies in a wall's line: their directions differ by at most this, degrees: jambs seen over a short span, not a diagonal.
DOOR_ANGLE_DEG = 20.0
#: Two walls are in one line when the shorter's ends lie within this plus half the thicker of the longer's, metres: a frame's step.
LINE_OFFSET_M = 0.12
#: Each end of a door lies within this of a wall, metres: a door frame and the scan's gap at its edge.
JAMB_M = 0.35
#: A region walled along less than this fraction of its edge, seen through a door, is outside: a room is walled on most sides.
MIN_ENCLOSURE = 0.25
#: Space no scan was taken in is a room only if walled along at least this fraction of
#: its edge (unless a door leads into it). Seen from outside through an opening, it is
#: a fan of rays: its two sides are the rays' limits, which no wall bounds, and only its
#: far end can be walled; a sector of angle a is walled along at most a / (2 + a) of its
#: edge, less than half for a < 2 rad (115 degrees). A room is walled on most sides.
MIN_ENCLOSURE_UNENTERED = 0.5
#: A room whose length (area over width) is at least this times its width (a corridor is long and narrow, Bormann et al.) ...
CORRIDOR_ELONGATION = 4.0
#: ... and at least this long, metres (shorter: a closet or an entrance) ...
CORRIDOR_MIN_LENGTH_M = 3.0
#: ... is a corridor when at most this wide (median local thickness), metres; a wider
#: one is a corridor only when longer in proportion to its width beyond this (a main
#: hallway 4.5 m wide runs 6 widths or more), else a hall.
CORRIDOR_MAX_WIDTH_M = 3.0
#: A room is mostly at least this wide (its median local thickness), metres: the
#: narrowest walkway, the minimum clear width of a walking surface (36 in, 2010 ADA
#: Standards 403.5.1; 0.9 m, the narrowest escape route of European building codes).
#: A narrower strip of space is the gap between two walls or a fan of rays along a
#: wall, not a room.
MIN_ROOM_WIDTH_M = 0.9


@dataclass(frozen=True)
@schema_defaults("floorplan.rooms")
class RoomParams:
    """Parameters of the room segmentation (see the module docstring): the door widths
    and the smallest room from config ``floorplan.rooms``, the others the module's
    constants. Lengths in metres, areas in square metres, angles in degrees."""

    resolution_m: float = RESOLUTION_M
    free_open_m: float = FREE_OPEN_M
    close_m: float = CLOSE_M
    marker_depth_m: float = MARKER_DEPTH_M
    door_min_m: float
    door_max_m: float
    door_angle_deg: float = DOOR_ANGLE_DEG
    line_offset_m: float = LINE_OFFSET_M
    jamb_m: float = JAMB_M
    min_enclosure: float = MIN_ENCLOSURE
    min_room_area_m2: float
    corridor_elongation: float = CORRIDOR_ELONGATION
    corridor_min_length_m: float = CORRIDOR_MIN_LENGTH_M
    corridor_max_width_m: float = CORRIDOR_MAX_WIDTH_M


@dataclass
class RoomRaster:
    """The raster the rooms are segmented on.

    Attributes
    ----------
    origin_xy : (2,) float ndarray
        Map-frame corner of cell (row 0, column 0), metres.
    resolution_m : float
        Cell size, metres.
    walls : (H, W) bool ndarray
        Cells of the plan's wall footprints.
    space : (H, W) bool ndarray
        The space to segment (module docstring, step 1).
    occupied : (H, W) bool ndarray
        Cells the scans saw occupied (walls, the plan's or not, and furniture).
    bounds : (H, W) bool ndarray
        Cells that bound the space: the scans' occupied cells; for a map (a grid
        without scan positions), every cell the map does not mark free.
    beyond : (H, W) bool ndarray or None
        Cells beyond the building's closed outline
        (:func:`~floorscan.floorplan.outline.building_outside`); None: none.
    under : (H, W) bool ndarray or None
        Cells of floor under objects standing against walls, and of seen floor the
        closing of the walls took (the corners between walls, slits narrower than a
        door), outside ``space``: they join the room beside them after the
        segmentation; None: none.
    """

    origin_xy: np.ndarray
    resolution_m: float
    walls: np.ndarray
    space: np.ndarray
    occupied: np.ndarray
    bounds: np.ndarray
    beyond: np.ndarray | None = None
    under: np.ndarray | None = None

    def centres(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Map-frame centres of cells.

        Parameters
        ----------
        rows, cols : (N,) int ndarray

        Returns
        -------
        (N, 2) float64 ndarray
            Metres.
        """
        return (np.column_stack([cols, rows]) + 0.5) * self.resolution_m + self.origin_xy

    def cells_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The cell of each map-frame point (as
        :meth:`floorscan.core.occupancy.OccupancyGrid.cells_of`).

        Parameters
        ----------
        xy : (N, 2) float ndarray
            Metres.

        Returns
        -------
        rows, cols : (N,) int64 ndarray
        inside : (N,) bool ndarray
            Whether the cell lies on the raster.
        """
        return raster_cells(xy, self.origin_xy, self.resolution_m, self.space.shape)

    def at(self, image: np.ndarray, xy: np.ndarray, outside=0) -> np.ndarray:
        """Values of a raster image at points.

        Parameters
        ----------
        image : (H, W) ndarray
            On the raster's cells.
        xy : (N, 2) float ndarray
            Map metres.
        outside : scalar
            The value for a point off the raster.

        Returns
        -------
        (N,) ndarray
            ``image``'s dtype.
        """
        rows, cols, inside = self.cells_of(xy)
        out = np.full(len(rows), outside, dtype=image.dtype)
        out[inside] = image[rows[inside], cols[inside]]
        return out

    def clearance(self) -> np.ndarray:
        """(H, W) float64: metres from each cell of the space to the nearest cell
        outside it (0 outside the space; the raster's border counts as outside)."""
        from scipy import ndimage

        return ndimage.distance_transform_edt(np.pad(self.space, 1))[1:-1, 1:-1] * self.resolution_m


def surrounded(mask: np.ndarray, structure: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The connected components of ``mask`` ((H, W) bool; SciPy's ``ndimage.label``
    with ``structure``, 4-connected by default): their labels ((H, W) int, 0 off the
    mask) and, per label, whether the raster's border misses it ((n + 1,) bool, False
    for label 0): the parts the rest of the raster surrounds."""
    from scipy import ndimage

    labels, n = ndimage.label(mask, structure=structure)
    inner = np.ones(n + 1, dtype=bool)
    inner[0] = False
    inner[np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = False
    return labels, inner


def dilate(mask: np.ndarray, radius_cells: float) -> np.ndarray:
    """``mask`` dilated by a disc of ``radius_cells``: the cells within that Euclidean
    distance of a True cell (an exact distance transform, SciPy: time linear in the
    cells, whatever the radius)."""
    from scipy import ndimage

    if not mask.any():
        return mask.copy()
    return ndimage.distance_transform_edt(~mask) <= radius_cells


def _erode(mask: np.ndarray, radius_cells: float) -> np.ndarray:
    """``mask`` eroded by a disc of ``radius_cells`` (cells beyond the border count as
    outside the mask)."""
    from scipy import ndimage

    return ndimage.distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1] > radius_cells


def _closing(mask: np.ndarray, radius_cells: float) -> np.ndarray:
    """Morphological closing of ``mask`` by a disc (radius in cells), the border
    padded so that it does not erode the edges."""
    if radius_cells <= 0:
        return mask.copy()
    r = int(np.ceil(radius_cells)) + 1
    grown = dilate(np.pad(mask, r), radius_cells)
    return (~dilate(~grown, radius_cells))[r:-r, r:-r]


def disc_opening(mask: np.ndarray, radius_cells: float) -> np.ndarray:
    """Morphological opening of ``mask`` by a disc (radius in cells): what discs of
    that radius inside the mask cover."""
    if radius_cells <= 0:
        return mask.copy()
    return dilate(_erode(mask, radius_cells), radius_cells) & mask


def enclosure_cells(raster: RoomRaster) -> tuple[np.ndarray, np.ndarray]:
    """The cells that measure how enclosed a room is.

    Returns
    -------
    edge : (H, W) bool ndarray
        The space's cells next to cells outside it (8-neighbours).
    solid : (H, W) bool ndarray
        The cells within two cells of a wall or a seen obstacle.
    """
    from scipy import ndimage

    solid = ndimage.binary_dilation(raster.walls | raster.occupied, structure=np.ones((3, 3)), iterations=2)
    edge = raster.space & ~ndimage.binary_erosion(raster.space, structure=np.ones((3, 3)))
    return edge, solid


def wall_footprints(axes: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """Each wall axis buffered by half its thickness, flat ends (shapely).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.

    Returns
    -------
    (N,) object ndarray of shapely Polygon
    """
    import shapely

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    if not len(axes):
        return np.array([], dtype=object)
    return shapely.buffer(shapely.linestrings(axes.reshape(-1, 2, 2)), np.asarray(thickness, dtype=np.float64) / 2.0,
                          cap_style="flat")


def wall_mask(axes: np.ndarray, thickness: np.ndarray, origin_xy: np.ndarray, res: float, shape) -> np.ndarray:
    """The cells of the walls' footprints (:func:`polygon_mask`; each at least 0.75 cell
    to each side of its axis), each axis also drawn as an 8-connected line, so a wall
    blocks the 4-connected space (scikit-image ``draw.line``).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    origin_xy, res, shape
        The raster, as :func:`polygon_mask`'s.

    Returns
    -------
    (H, W) bool ndarray
    """
    from skimage.draw import line

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    d = axes[:, 2:] - axes[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    keep = length > 0
    axes, d, length, thickness = axes[keep], d[keep], length[keep], thickness[keep]
    n = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None] * np.maximum(0.5 * thickness, 0.75 * res)[:, None]
    corners = np.stack([axes[:, :2] + n, axes[:, 2:] + n, axes[:, 2:] - n, axes[:, :2] - n], axis=1)
    mask = polygon_mask(corners, origin_xy, res, shape)
    for x0, y0, x1, y1 in axes:
        e = np.round((np.array([[x0, y0], [x1, y1]]) - origin_xy) / res - 0.5).astype(np.int64)
        rr, cc = line(e[0, 1], e[0, 0], e[1, 1], e[1, 0])
        ok = (rr >= 0) & (cc >= 0) & (rr < shape[0]) & (cc < shape[1])
        mask[rr[ok], cc[ok]] = True
    return mask


def polygon_mask(polygons: np.ndarray, origin_xy: np.ndarray, res: float, shape) -> np.ndarray:
    """The cells whose centres lie in any of the polygons (scikit-image ``draw.polygon``).

    Parameters
    ----------
    polygons : (K, V, 2) float ndarray
        Corners, map metres.
    origin_xy : (2,) float ndarray
        Map-frame corner of cell (0, 0), metres.
    res : float
        Cell size, metres.
    shape : (int, int)
        (H, W).

    Returns
    -------
    (H, W) bool ndarray
    """
    from skimage.draw import polygon

    mask = np.zeros(shape, dtype=bool)
    for corners in np.asarray(polygons, dtype=np.float64):
        c = (corners - origin_xy) / res - 0.5  # cell-centre coordinates
        rr, cc = polygon(c[:, 1], c[:, 0], shape)
        mask[rr, cc] = True
    return mask


def room_space(grid: OccupancyGrid, axes: np.ndarray, thickness: np.ndarray, params: RoomParams,
               under: np.ndarray | None = None) -> RoomRaster:  # fmt: skip
    """The space the rooms are cut from (module docstring, step 1).

    Parameters
    ----------
    grid : OccupancyGrid
        The free space of the plan's scans.
    axes : (N, 4) float ndarray
        The plan's wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Their thickness, metres.
    params : RoomParams
    under : (K, 4, 2) float ndarray, optional
        Quadrilaterals of floor under the objects standing against walls
        (:func:`~floorscan.floorplan.structure.floor_under`), metres: its cells no
        longer bound the space and are :attr:`RoomRaster.under`, whatever the scans saw
        there.

    Returns
    -------
    RoomRaster
        At ``resolution_m`` rounded to a whole number of the grid's cells, over the part
        of the grid that holds space or walls.
    """
    f = max(1, int(round(params.resolution_m / grid.resolution_m)))
    res = grid.resolution_m * f
    free = passable(grid)
    h, w = -(-free.shape[0] // f), -(-free.shape[1] // f)
    padded = np.zeros((h * f, w * f), dtype=bool)
    padded[: free.shape[0], : free.shape[1]] = free
    free = padded.reshape(h, f, w, f).any(axis=(1, 3))
    walls = wall_mask(axes, thickness, grid.origin_xy, res, (h, w))
    opened = disc_opening(free, params.free_open_m / res)
    padded[:] = False
    padded[: grid.shape[0], : grid.shape[1]] = grid.structure()
    occupied = padded.reshape(h, f, w, f).any(axis=(1, 3))
    # what bounds the space: the cells the scans saw occupied; in a map, every cell it
    # does not mark free (a map may draw its walls in a shade its thresholds read as
    # unknown: light grey in ipa's maps, blurred by resampling in others)
    bounds = occupied if grid.scan_xy is not None else ~free
    # the rest on the part of the raster that holds space or walls (and a margin the
    # closings reach across): the same cells, fewer of them
    origin = np.asarray(grid.origin_xy, dtype=np.float64)
    used = opened | walls
    if used.any():
        m = int(np.ceil(max(params.close_m, params.door_min_m / 2) / res)) + 2
        rows, cols = np.flatnonzero(used.any(axis=1)), np.flatnonzero(used.any(axis=0))
        r0, r1 = max(int(rows[0]) - m, 0), min(int(rows[-1]) + m + 1, h)
        c0, c1 = max(int(cols[0]) - m, 0), min(int(cols[-1]) + m + 1, w)
        walls, opened, occupied, bounds = (a[r0:r1, c0:c1] for a in (walls, opened, occupied, bounds))
        origin = origin + np.array([c0, r0]) * res
    # gaps between walls narrower than a door are wall: nobody passes them
    drawn = walls
    walls = _closing(walls, params.door_min_m / 2 / res) | walls
    # the seen floor that closing takes: the corner between two walls (a fillet of the
    # closing's disc, wider where a turned raster draws the walls in steps), a slit
    taken = walls & ~drawn & opened
    space = opened & ~walls
    space = _closing(space | walls, params.close_m / res) & ~walls
    # the closing fills unseen cells, never the cells that bound the space (a wall
    # the plan lacks stays a boundary)
    space &= ~bounds | opened
    # the floor under the objects standing against walls is the room's (a room's area is
    # its floor area): their cells no longer bound the space, and join the room in front
    # of them once the rooms are cut (not a passage between two rooms: a cabinet row
    # runs on behind a partition)
    beneath = None
    if under is not None and len(under):
        floor = polygon_mask(under, origin, res, space.shape)
        bounds = bounds & ~floor
        beneath = floor & ~walls
    # the seen space outside the building's closed outline: rays through windows, open doors
    outside, beyond, _ = building_outside(walls | occupied, res, origin, grid.scan_xy, params.door_max_m, seen=space,
                                          walls=walls)
    space &= ~outside
    # holes without a wall in them: the floor under furniture, shadows of objects
    holes, fill = surrounded(~space)
    fill[unique_ints(holes[walls])] = False
    space |= fill[holes]
    # the seen floor the closing of the walls took joins the room beside it the same way
    beneath = (taken & ~outside if beneath is None else beneath | taken & ~outside) & ~space
    return RoomRaster(origin_xy=origin, resolution_m=res, walls=walls, space=space, occupied=occupied, bounds=bounds,
                      beyond=beyond, under=beneath)


def space_regions(raster: RoomRaster, params: RoomParams) -> tuple[np.ndarray, np.ndarray]:
    """The watershed regions of the space (module docstring, step 2).

    Parameters
    ----------
    raster : RoomRaster
    params : RoomParams
        ``marker_depth_m`` and the seeds' settings.

    Returns
    -------
    labels : (H, W) int32 ndarray
        0 outside the space, else the region (1..R).
    distance : (H, W) float64 ndarray
        Distance from each space cell to the nearest cell outside it, metres.
    """
    from scipy import ndimage
    from skimage.morphology import h_maxima
    from skimage.segmentation import watershed

    space = raster.space
    distance = raster.clearance()
    if not space.any():
        return np.zeros(space.shape, dtype=np.int32), distance
    # the seeds: h-maxima (in whole centimetres, an integer image) of the distance's
    # 2 x 2 block maxima, a quarter of the cells to sort; each seed back on the cells of
    # its block where the distance is within a cell of the block's maximum
    h, w = space.shape
    cm = np.round(distance * 100).astype(np.uint16)
    blocks = np.zeros((-(-h // 2) * 2, -(-w // 2) * 2), dtype=np.uint16)
    blocks[:h, :w] = cm
    coarse = blocks.reshape(blocks.shape[0] // 2, 2, blocks.shape[1] // 2, 2).max(axis=(1, 3))
    seeds = h_maxima(coarse, max(1, int(round(params.marker_depth_m * 100))))
    up = np.repeat(np.repeat(seeds, 2, axis=0), 2, axis=1)[:h, :w].astype(bool)
    top = np.repeat(np.repeat(coarse, 2, axis=0), 2, axis=1)[:h, :w].astype(np.int32)
    peaks = up & (cm.astype(np.int32) >= top - int(round(raster.resolution_m * 100)))
    markers, _ = ndimage.label(peaks & space, structure=np.ones((3, 3)))
    labels = watershed(-distance, markers, mask=space, connectivity=1)
    # space cells no marker reached (a component without a peak): a region each
    rest, _ = ndimage.label(space & (labels == 0))
    labels = np.where(rest > 0, rest + labels.max(), labels)
    return labels.astype(np.int32), distance
