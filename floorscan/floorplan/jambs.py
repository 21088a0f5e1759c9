"""Where a door's jambs can stand (:mod:`floorscan.floorplan.doors`): the cells near the
building's structure (:func:`jamb_cells`), less the objects standing free in the space
(:func:`standing_free`, :func:`furniture_islands`), and the contacts between two regions
that run from a wall's face to an object (:func:`face_to_object`) or from a column in a
partition's line past the wall it crosses (:func:`stub_past_crossing`), which are
narrowings of the space, not openings in a wall.

A door is an opening in the building's structure, so its two jambs are walls or the
seen obstacles that bound the space; a desk, a table and its chairs, a plant or a
cabinet in a room frame none (Bormann et al., ICRA 2016, ipa_room_segmentation: a room
boundary is a narrow passage between two wall points), and neither does the furniture
the structure passes found standing loose in the space (structure step 6,
:func:`~floorscan.floorplan.clutter.loose_in_free_space`), away from the walls: the
plan and its rooms agree on what is furniture.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import ray_meets_lines
from floorscan.floorplan.doors import footprint_distance, near_walls, wall_units
from floorscan.floorplan.free_space import CLUTTER_MAX_LENGTH_M, LOOSE_IN_FREE_SPACE
from floorscan.floorplan.room_space import RoomParams, RoomRaster, dilate, surrounded, wall_mask

#: The cells of loose furniture (:func:`jamb_cells`): those within this many cells of its
#: faces (past their ends too), the band a face traced on the raster lies in (a cell each
#: way) and the cell of the object behind it.
FURNITURE_BAND_CELLS = 2


def jamb_cells(raster: RoomRaster, jamb_m: float, axes: np.ndarray | None = None, thickness: np.ndarray | None = None,
               params: RoomParams | None = None, furniture: np.ndarray | None = None) -> np.ndarray:
    """(H, W) bool: the cells within ``jamb_m`` (metres) of a wall's footprint or of a
    cell that bounds the space (:attr:`RoomRaster.bounds`), but of no object standing
    free in the space, nor within ``jamb_m`` of loose furniture farther than that and a
    cell from every wall: where a door's jamb can stand. A door is an opening in the
    building's structure; the narrowing between a desk and a wall is none, nor the one
    between a desk against a wall and a cabinet across the room.

    An object standing free is a component of the cells outside the space (walls,
    obstacles, what was not seen free) that the space surrounds and that is shorter
    than the longest piece of furniture (:func:`standing_free`): a desk or a table in a
    room, whether the plan took its faces for walls or not; or, however long, one that
    holds no wall of the plan longer than that piece and encloses no room's floor
    (:func:`furniture_islands`, given the plan's walls): a row or an L of desks, a table
    and its chairs, a cabinet with less floor inside than ``params.min_room_area_m2``.
    A stub of wall whose junction the scans did not see belongs with the unseen cells
    beyond it, so it stays a jamb; so does a piece of wall between two doors, in a wall's
    line a door's width from its ends, or with a door in a wall's line off one end and
    a door to a wall across its line off the other (:func:`_pieces_between_doors`),
    given the walls.

    Parameters
    ----------
    raster : RoomRaster
    jamb_m : float
        Metres.
    axes : (N, 4) float ndarray, optional
        The plan's wall axes ``x0, y0, x1, y1``, metres; without them (or ``thickness``
        or ``params``) no object standing free is a piece of wall.
    thickness : (N,) float ndarray, optional
        Metres.
    params : RoomParams, optional
        ``door_max_m``, ``door_angle_deg``, ``line_offset_m``, ``min_room_area_m2``.
    furniture : (K, 4) float ndarray, optional
        Faces of furniture standing loose in the space, metres (the structure passes'
        ``loose_in_free_space`` clutter shorter than the longest piece of furniture,
        :func:`loose_furniture`); their cells are those within
        :data:`FURNITURE_BAND_CELLS` of them, past their ends too.
    """
    res = raster.resolution_m
    solid = raster.walls | raster.bounds
    free = standing_free(~raster.space, res)
    if axes is not None and len(axes):
        free |= furniture_islands(raster, axes, params.min_room_area_m2 if params is not None else 0.0)
    if axes is not None and thickness is not None and params is not None and len(axes) and free.any():
        free &= ~_pieces_between_doors(free, raster, axes, thickness, params)
    jambs = dilate(solid & ~free, jamb_m / res)
    if furniture is not None and len(furniture):
        band = dilate(wall_mask(furniture, np.zeros(len(furniture)), raster.origin_xy, res, solid.shape),
                      FURNITURE_BAND_CELLS)  # fmt: skip
        jambs &= ~dilate(band & ~dilate(raster.walls, jamb_m / res + 1), jamb_m / res)
    return jambs


def loose_furniture(clutter) -> np.ndarray:
    """The faces of furniture standing loose in the space, which frame no door
    (:func:`jamb_cells`): the clutter the structure passes found loose in the free space
    (``reason`` ``loose_in_free_space``, structure step 6,
    :func:`~floorscan.floorplan.clutter.loose_in_free_space`) shorter than the longest
    piece of furniture (:data:`~floorscan.floorplan.free_space.CLUTTER_MAX_LENGTH_M`; a
    longer chain may be a wall that rule took for furniture, and keeps its jambs).

    Parameters
    ----------
    clutter : pandas.DataFrame
        :attr:`~floorscan.floorplan.plan.FloorPlan.clutter`'s columns.

    Returns
    -------
    (F, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres.
    """
    loose = clutter[(clutter["reason"] == LOOSE_IN_FREE_SPACE) & (clutter["length_m"] < CLUTTER_MAX_LENGTH_M)]
    return loose[["x0", "y0", "x1", "y1"]].to_numpy(np.float64).reshape(-1, 4)


def furniture_islands(raster: RoomRaster, axes: np.ndarray, min_room_area_m2: float = 0.0) -> np.ndarray:
    """(H, W) bool: the groups of furniture standing in the space, whatever their
    extent: the 8-connected components of the cells outside the space (walls, obstacles,
    what was not seen free) that

    - the space surrounds: none of their cells lies on the raster's border (the
      outside of the building and every wall joined to its outer walls are one
      component that reaches it);
    - hold no wall of the plan (``axes``, (N, 4) metres) at least
      :data:`~floorscan.floorplan.free_space.CLUTTER_MAX_LENGTH_M` long, the longest
      piece of furniture: the structure passes' anchors
      (:mod:`floorscan.floorplan.structure`, step 4); a core of rooms or a partition
      standing free of the outer walls holds one;
    - enclose no more space than ``min_room_area_m2`` (square metres; SciPy's
      ``ndimage.binary_fill_holes``): a core of rooms closed all round holds its rooms'
      floor, and a room is no smaller than that; less is the inside of a cabinet or a
      shelf the map saw through. 0 (the default): no space at all.

    Desks in a row, an L of desks, a table and its chairs are one component longer
    than any one of them (:func:`standing_free` measures a component against a single
    piece). A wall is held where a point of its axis, every half cell, falls on the
    component."""
    from scipy import ndimage

    labels, island = surrounded(~raster.space, np.ones((3, 3), dtype=bool))
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1])
    r = raster.resolution_m
    anchors = length >= CLUTTER_MAX_LENGTH_M
    for a, steps in zip(axes[anchors], np.ceil(length[anchors] / (r / 2)).astype(np.int64)):  # every half cell
        rows, cols, inside = raster.cells_of(a[:2] + np.linspace(0.0, 1.0, steps + 1)[:, None] * (a[2:] - a[:2]))
        island[labels[rows[inside], cols[inside]]] = False
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is not None and island[k]:
            part = labels[box] == k
            enclosed = (ndimage.binary_fill_holes(part) & ~part & raster.space[box]).sum() * r**2
            island[k] = not enclosed or enclosed < min_room_area_m2
    return island[labels]


def _pieces_between_doors(free: np.ndarray, raster: RoomRaster, axes: np.ndarray, thickness: np.ndarray,
                   params: RoomParams) -> np.ndarray:
    """(H, W) bool: the components of ``free`` ((H, W) bool, 8-connected) that are
    pieces of a wall between two doors: along the component's principal axis, each of
    its ends faces the end of a wall in its line (the wall within ``door_angle_deg`` of
    the axis, the end within ``line_offset_m`` plus half the wall of the wall's line)
    across a gap no wider than ``door_max_m``, as a door's jambs stand in one line
    (:func:`~floorscan.floorplan.doors.wall_gaps`); or one end faces such a wall end
    across a gap ``door_min_m`` to ``door_max_m`` wide, a wall crosses the line
    ahead of the other end, its face as far off, and the piece is at least as long as
    each gap (a partition with a door in its line and a door beside the wall it runs
    to: more wall than opening, as :mod:`~floorscan.floorplan.extensions` asks of a
    partition's line). A desk between two walls faces their sides, not a wall's end in
    its line, and stays an object; the edge of a table in line with a wall's stub is
    shorter than the openings beside it."""
    from scipy import ndimage

    labels, n = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
    u_w, len_w = wall_units(axes)
    n_w = np.column_stack([-u_w[:, 1], u_w[:, 0]])
    ends = axes.reshape(-1, 2, 2)
    tol = np.asarray(thickness, dtype=np.float64) / 2 + params.line_offset_m
    cos_max = np.cos(np.radians(params.door_angle_deg))
    r = raster.resolution_m
    keep = np.zeros(n + 1, dtype=bool)
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        rr, cc = np.nonzero(labels[box] == k)
        if len(rr) < 2:
            continue
        xy = raster.origin_xy + (np.column_stack([cc + box[1].start, rr + box[0].start]) + 0.5) * r
        c = xy.mean(axis=0)
        u = np.linalg.eigh((xy - c).T @ (xy - c))[1][:, -1]  # the principal axis
        t = (xy - c) @ u
        along = np.abs(u_w @ u) >= cos_max
        faced, wide, crossed = [], [], []  # per end; wide, crossed: the gap's width, metres, or inf
        for sign, e in ((-1.0, c + u * t.min()), (1.0, c + u * t.max())):
            in_line = along & (np.abs(np.einsum("ij,ij->i", e - ends[:, 0], n_w)) <= tol)
            ahead = ((ends - e) @ (sign * u)).min(axis=1)  # the nearer end of each wall, ahead of this end
            faced.append(bool((in_line & (ahead >= 0) & (ahead <= params.door_max_m + r)).any()))
            door = in_line & (ahead >= params.door_min_m) & (ahead <= params.door_max_m + r)
            wide.append(float(ahead[door].min()) if door.any() else np.inf)
            crossed.append(_crossed_ahead(e, sign * u, axes[:, :2], u_w, len_w, thickness, params.door_min_m,
                                          params.door_max_m + r))
        length = float(t.max() - t.min()) + r
        keep[k] = all(faced) or any(max(wide[i], crossed[1 - i]) <= length for i in (0, 1))
    return keep[labels]


def _crossed_ahead(e: np.ndarray, v: np.ndarray, start: np.ndarray, u: np.ndarray, length: np.ndarray,
                   thickness: np.ndarray, near_m: float, reach_m: float) -> float:
    """The distance, metres, from ``e`` along the unit ``v`` ((2,)) to the face of the
    nearest wall (axes from ``start`` (N, 2) along the unit ``u`` (N, 2) for ``length``
    (N,), :func:`~floorscan.floorplan.doors.wall_units`; ``thickness`` (N,); metres)
    that crosses that ray ``near_m`` to ``reach_m`` (metres) off, as far as a door is
    wide; inf when none does."""
    cross, t, s, _ = ray_meets_lines(e, v, start, u)
    with np.errstate(invalid="ignore", divide="ignore"):
        face = t - thickness / 2 / np.abs(cross)  # from the axis back to the face, along the ray
        hit = (s >= 0) & (s <= length) & (face >= near_m) & (face <= reach_m)
    return float(face[hit].min()) if hit.any() else np.inf


def standing_free(solid: np.ndarray, resolution_m: float, max_extent_m: float = CLUTTER_MAX_LENGTH_M) -> np.ndarray:
    """(H, W) bool: the cells of the 8-connected components of ``solid`` ((H, W) bool)
    whose extent, the largest distance between two of their cells plus one cell, is
    below ``max_extent_m`` (metres; by default the longest piece of furniture,
    :data:`~floorscan.floorplan.free_space.CLUTTER_MAX_LENGTH_M`). The extent is the
    component's diameter, so the test does not depend on the raster's orientation
    (SciPy's ``ndimage.label`` and ``ConvexHull``)."""
    from scipy import ndimage
    from scipy.spatial import ConvexHull, QhullError

    labels, n = ndimage.label(solid, structure=np.ones((3, 3), dtype=bool))
    boxes = ndimage.find_objects(labels)
    size = np.array([(b[0].stop - b[0].start, b[1].stop - b[1].start) for b in boxes], dtype=np.float64).reshape(-1, 2)
    limit = max_extent_m / resolution_m - 1.0  # in cells, between cell centres
    out = np.zeros(n + 1, dtype=bool)
    out[1:] = np.hypot(size[:, 0] - 1, size[:, 1] - 1) < limit  # the box's diagonal bounds the diameter
    # the diameter is at least the box's longer side: between the two, measure it
    for k in np.flatnonzero(~out[1:] & (size.max(axis=1) - 1 < limit)) + 1:
        box = boxes[k - 1]
        xy = np.column_stack(np.nonzero(labels[box] == k)).astype(np.float64)
        try:
            xy = xy[ConvexHull(xy).vertices]
        except QhullError:  # collinear cells: the ends are among them all
            pass
        out[k] = float(np.sqrt(((xy[:, None] - xy[None]) ** 2).sum(-1)).max()) < limit
    out[0] = False
    return out[labels]


def on_wall_face(point: np.ndarray, axes: np.ndarray, thickness: np.ndarray, params: RoomParams) -> bool:
    """Whether ``point`` ((2,) metres) lies on the face of a wall: within ``jamb_m`` of
    its footprint and at least ``door_min_m`` from both its ends along its axis (a door's
    width in, where no jamb of an opening in it stands). ``axes`` (N, 4) and
    ``thickness`` (N,) are the plan's walls, metres; False without walls."""
    if not len(axes):
        return False
    u, length = wall_units(axes)
    dist = footprint_distance(point, axes, thickness)
    t = ((point - axes[:, :2]) * u).sum(axis=1)
    return bool(((dist <= params.jamb_m) & (t >= params.door_min_m) & (t <= length - params.door_min_m)).any())


def wall_line_index(axes: np.ndarray, thickness: np.ndarray, params: RoomParams) -> np.ndarray:
    """(N,) int64: the line of each wall, as :func:`~floorscan.floorplan.corridor_lines.wall_lines`
    groups them (its ends within ``line_offset_m`` plus half the thicker wall of the
    line's longest wall), whatever pieces a wall was found in; ``axes`` (N, 4) and
    ``thickness`` (N,) in metres."""
    from floorscan.floorplan.corridor_lines import wall_lines

    u, length = wall_units(axes)
    line_of = np.full(len(axes), -1, dtype=np.int64)
    for k, walls in enumerate(wall_lines(axes, thickness, u, length, params.line_offset_m)):
        line_of[walls] = k
    return line_of


def face_to_object(raster: RoomRaster, p: np.ndarray, q: np.ndarray, axes: np.ndarray, thickness: np.ndarray,
                   params: RoomParams) -> bool:
    """Whether the contact ``p``-``q`` between two regions runs from the face of a wall,
    at least ``door_min_m`` from its ends, to an object that is no wall and no partition
    in the contact's line: a narrowing of the space (a plant or a cabinet against the
    opposite wall), not an opening in a wall, so no door. The contact's direction is
    not tested: it follows the raster's cells, not the wall (a contact square to a wall
    on one raster runs 25 degrees off on the raster turned by 30 degrees).

    The object is the run of cells outside the space across the contact, just beyond
    its end (up to ``jamb_m`` on); a partition stub the plan holds no wall of is at
    most the thickest wall (:data:`~floorscan.floorplan.params.PAIR_MAX_M`) and a cell
    on each side across, and continues the opening's line as a door's jamb does.

    ``raster`` is the space the contact lies in; ``p`` and ``q`` (2,) its ends, ``axes``
    (N, 4) and ``thickness`` (N,) the plan's walls, all in metres; ``params``:
    ``door_min_m``, ``door_max_m``, ``jamb_m``. False without walls.
    """
    from floorscan.floorplan.params import PAIR_MAX_M

    if not len(axes):
        return False
    d = q - p
    v = d / max(float(np.hypot(*d)), 1e-12)
    r = raster.resolution_m
    for a, b, w in ((p, q, v), (q, p, -v)):
        if near_walls(b, axes, thickness, params.jamb_m) or not on_wall_face(a, axes, thickness, params):
            continue
        # the object's width across the contact, just beyond its end
        n = np.array([-w[1], w[0]])
        s = np.arange(-round(params.door_max_m / r), round(params.door_max_m / r) + 1) * r
        mid = len(s) // 2
        for ahead in np.arange(1, round(params.jamb_m / r) + 2) * r:
            solid = ~raster.at(raster.space, b + w * ahead + s[:, None] * n, outside=False)
            if solid[mid]:
                break
        else:
            continue
        lo, hi = mid, mid
        while lo > 0 and solid[lo - 1]:
            lo -= 1
        while hi < len(s) - 1 and solid[hi + 1]:
            hi += 1
        if (hi - lo + 1) * r > PAIR_MAX_M + 2 * r:
            return True
    return False


def stub_past_crossing(raster: RoomRaster, p: np.ndarray, q: np.ndarray, axes: np.ndarray, thickness: np.ndarray,
                       params: RoomParams) -> bool:
    """Whether the contact ``p``-``q`` between two regions runs on from the end of a
    wall's piece past a wall it crosses that stands in the space: no door's jamb, but an
    object in the wall's line against the wall crossed (a column, whose side faces the
    plan joined to the partition they are in line with), so the contact is a narrowing,
    not an opening in a wall.

    Such a piece is a wall ``i`` in the contact's line (within ``door_angle_deg``) whose
    end lies within its half thickness and ``jamb_m`` of an end of the contact, with the
    contact running on from that end, that crosses a wall ``j``: ``i``'s axis meets
    ``j``'s at least ``i``'s half thickness and ``jamb_m`` from ``j``'s ends (``j`` goes
    on both sides: a corner is no crossing), ``i`` runs on at least a door's width
    (``door_min_m``, past ``j``'s half thickness) on the other side, and the piece
    reaches past ``j``'s face by more than nothing and at most ``door_min_m``. It stands
    in the space when the space lies on both sides of its middle within ``jamb_m`` of
    its faces; a wall's piece along an object against the wall crossed (a pier by a
    cabinet) has the object on one side and frames a door.

    Parameters
    ----------
    raster : RoomRaster
        The space the contact lies in.
    p, q : (2,) float ndarray
        The contact's ends, metres.
    axes : (N, 4) float ndarray
        The plan's wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    params : RoomParams
        ``door_min_m``, ``door_angle_deg``, ``jamb_m``.

    Returns
    -------
    bool
        False without walls.
    """
    if not len(axes):
        return False
    u, length = wall_units(axes)
    ends = axes.reshape(-1, 2, 2)
    cos_max = np.cos(np.radians(params.door_angle_deg))
    r = raster.resolution_m
    d = q - p
    v = d / max(float(np.hypot(*d)), 1e-12)
    for b, a in ((p, q), (q, p)):
        near = np.hypot(*(b[None, None] - ends).transpose(2, 0, 1))  # (N, 2) metres to each end
        for i in np.flatnonzero((near.min(axis=1) <= thickness / 2 + params.jamb_m) & (np.abs(u @ v) >= cos_max)):
            k = int(np.argmin(near[i]))
            e, far = ends[i, k], ends[i, 1 - k]
            g = (e - far) / max(length[i], 1e-12)  # along i, towards its end at the contact
            if (a - e) @ g <= 0:
                continue  # the contact does not run on from i's end
            _, t_i, s_j, _ = ray_meets_lines(far, g, ends[:, 0], u)  # metres along i from far, along each j
            piece = length[i] - t_i  # from the crossing to i's end
            margin = thickness[i] / 2 + params.jamb_m
            with np.errstate(invalid="ignore"):  # NaN: j parallel to i
                crossed = ((np.abs(u @ g) < cos_max) & (s_j >= margin) & (s_j <= length - margin)
                           & (t_i >= thickness / 2 + params.door_min_m)
                           & (piece > thickness / 2) & (piece <= thickness / 2 + params.door_min_m))  # fmt: skip
            for j in np.flatnonzero(crossed):
                mid = e - g * (piece[j] - thickness[j] / 2) / 2
                n = np.array([-g[1], g[0]])
                off = thickness[i] / 2 + np.arange(1, round(params.jamb_m / r) + 2) * r
                if all(raster.at(raster.space, mid[None] + side * off[:, None] * n[None], outside=False).any()
                       for side in (1, -1)):
                    return True
    return False
