"""Wall hypotheses of the global layout read from the map itself (issue 44): the
building's dominant directions, then on each direction its *representative lines*, the
offsets at which many occupied cells line up.

A map's walls are the lines along which its occupied cells gather. Projected on the
normal of a wall direction, the occupied cells of every wall on that direction fall in
a few narrow bins, however dashed, faint or broken the wall is drawn; the cells of
furniture and clutter spread out. So:

1. **Dominant directions**: the plan's walls' (:func:`floorscan.floorplan.hypotheses.dominant_directions`,
   ROSE^2's first step: Luperto et al., RA-L 2022). The plan misses walls, not
   directions: a tenth of its walls' length on a direction is enough to find it.
2. **Representative lines** (:func:`representative_lines`): on each direction, the
   peaks of the profile (ROSE^2's spatial clusters of collinear segments: one line per
   offset, the cells within :data:`LINE_HALF_WIDTH_M` of it its support), each kept
   where its occupied cells cover at least :data:`MIN_SUPPORT_M` of its length, laid
   from its first to its last supporting cell. Its support is counted in *runs*: cells
   no more than :data:`RUN_GAP_M` apart along the line, a run at least
   :data:`MIN_RUN_M` long and half occupied (a dashed wall is a run; a map's speckle
   and a row of chairs are not).
3. **Onto the plan's walls** (:func:`onto_walls`): a line that runs along a wall of
   the plan takes that wall's line, so that the two are one hypothesis.
4. **Extended lines and closed openings** (:func:`extended_lines`,
   :func:`map_hypotheses`): each line extended across the frame (ROSE^2's extended
   lines), without evidence of its own: whether it divides two cells of the complex is
   measured edge by edge on the occupied cells along it
   (:func:`floorscan.floorplan.arrangement.edges_evidence`). A gap of at most
   ``door_max_m`` between two runs of wall (each at least :data:`JAMB_MIN_M`) is a
   closed opening, evidence of a boundary as a wall is (the rule of
   :func:`floorscan.floorplan.hypotheses.layout_lines` for the plan's walls).

To use: :func:`map_hypotheses` on a grid and the plan's walls gives the lines the
layout adds to its complex (:func:`floorscan.floorplan.layout.layout_rooms` calls it).
"""

from __future__ import annotations

import numpy as np

#: The cells of a wall lie within this of its line, metres: half a common wall's
#: thickness and a cell (walls drawn as a band of two or three cells, blurred maps).
LINE_HALF_WIDTH_M = 0.15
#: Along a line, occupied cells this close (metres) are one run of a wall: the gaps
#: of a wall drawn dashed or seen in pieces (four 5 cm cells), not a door.
RUN_GAP_M = 0.2
#: A run is a piece of wall when it is at least this long, metres (a door's jamb), and
#: at least half of it occupied; the scattered cells of clutter and of a map's
#: speckle line up in shorter runs, or sparser ones.
MIN_RUN_M = 0.5
#: A line is a wall hypothesis when its occupied cells cover at least this much of
#: its length, metres: a short office wall; a chair's or a desk's side is less.
MIN_SUPPORT_M = 1.0
#: A gap between two runs closes an opening (a door) when both runs are at least this
#: long, metres: walls. The gaps between pieces of furniture in a row (desks, the
#: chairs of a table, 0.5 to 1 m each) close rooms into pieces otherwise (measured:
#: benchmarks/README.md, seventh session).
JAMB_MIN_M = MIN_SUPPORT_M


def representative_lines(xy: np.ndarray, resolution_m: float, directions: np.ndarray, door_max_m: float = 2.0):
    """The representative lines of the occupied cells on each direction (module
    docstring, step 2), each from its first to its last supporting cell.

    Parameters
    ----------
    xy : (N, 2) float ndarray
        The occupied cells' centres, metres.
    resolution_m : float
        Metres.
    directions : (D,) float ndarray
        Radians (:func:`floorscan.floorplan.hypotheses.dominant_directions`).
    door_max_m : float
        The widest gap between two runs that closes an opening, metres.

    Returns
    -------
    lines : (M, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres, on the line's first and last supporting cell.
    support_m : (M,) float64 ndarray
        The length of each line its occupied cells cover, metres (distinct cells along it).
    openings : (K, 4) float64 ndarray
        The gaps between consecutive runs of wall along a line no longer than
        ``door_max_m`` (a door, a passage the wall closes), ``x0, y0, x1, y1`` metres:
        evidence of a boundary, as a wall is (the closed openings of
        :func:`floorscan.floorplan.hypotheses.layout_lines`).
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    lines, support, openings = [], [], []
    half = max(int(round(LINE_HALF_WIDTH_M / resolution_m)), 1)
    for a in np.asarray(directions, dtype=np.float64).reshape(-1):
        d = np.array([np.cos(a), np.sin(a)])
        nrm = np.array([-d[1], d[0]])
        s, t = xy @ nrm, xy @ d
        s0 = s.min()
        b = np.floor((s - s0) / resolution_m).astype(np.int64)
        counts = np.bincount(b)
        # the peaks of the profile, the strongest first; the cells within the half
        # width of a peak are its support and no other peak's
        taken = np.zeros(len(counts), dtype=bool)
        for k in np.argsort(-counts, kind="stable"):
            if counts[k] * resolution_m < MIN_SUPPORT_M:
                break
            if taken[k]:
                continue
            lo, hi = max(k - half, 0), min(k + half + 1, len(counts))
            taken[lo:hi] = True
            near = (b >= lo) & (b < hi)
            tb = np.unique(np.floor(t[near] / resolution_m).astype(np.int64))
            runs = _runs(tb, resolution_m)
            cover = sum(n for _, _, n in runs) * resolution_m
            if cover < MIN_SUPPORT_M:
                continue
            # the line through the support's mean offset
            off = float(np.mean(s[near]))
            t0, t1 = runs[0][0] * resolution_m, (runs[-1][1] + 1) * resolution_m
            p, q = off * nrm + t0 * d, off * nrm + t1 * d
            lines.append(np.r_[p, q])
            support.append(cover)
            for (s0, end, _), (start, e1, _) in zip(runs[:-1], runs[1:]):
                g0, g1 = (end + 1) * resolution_m, start * resolution_m
                jambs = min(end - s0 + 1, e1 - start + 1) * resolution_m
                if g1 - g0 <= door_max_m and jambs >= JAMB_MIN_M:
                    openings.append(np.r_[off * nrm + g0 * d, off * nrm + g1 * d])
    return (np.array(lines, dtype=np.float64).reshape(-1, 4), np.array(support, dtype=np.float64),
            np.array(openings, dtype=np.float64).reshape(-1, 4))


def _runs(tb: np.ndarray, resolution_m: float) -> list[tuple[int, int, int]]:
    """The runs of a line's occupied cells ``tb`` (sorted distinct cell indices along
    it) that are pieces of wall (:data:`RUN_GAP_M`, :data:`MIN_RUN_M`): ``(first,
    last, occupied)`` cell indices and count."""
    if not len(tb):
        return []
    gap = max(int(round(RUN_GAP_M / resolution_m)), 0)
    cut = np.flatnonzero(np.diff(tb) > gap + 1) + 1
    out = []
    for piece in np.split(tb, cut):
        span = int(piece[-1] - piece[0] + 1)
        if span * resolution_m >= MIN_RUN_M and 2 * len(piece) >= span:
            out.append((int(piece[0]), int(piece[-1]), len(piece)))
    return out


def extended_lines(lines: np.ndarray, frame) -> np.ndarray:
    """Each line extended across ``frame`` (ROSE^2's extended lines): the part of its
    infinite line inside the frame's box, metres, (M, 4); a line that misses the frame
    is left out."""
    from shapely.geometry import LineString

    out = []
    x0, y0, x1, y1 = frame.bounds
    reach = 2 * float(np.hypot(x1 - x0, y1 - y0))
    for a in np.asarray(lines, dtype=np.float64).reshape(-1, 4):
        p, q = a[:2], a[2:]
        d = (q - p) / max(float(np.hypot(*(q - p))), 1e-12)
        seg = LineString([p - reach * d, q + reach * d]).intersection(frame)
        if seg.geom_type == "LineString" and not seg.is_empty:
            c = np.asarray(seg.coords)
            out.append(np.r_[c[0], c[-1]])
    return np.array(out, dtype=np.float64).reshape(-1, 4)


def onto_walls(lines: np.ndarray, axes: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """Each line that runs along a wall of the plan moved onto that wall's axis line:
    the plan's wall and the map's line are one hypothesis, not two a sliver apart
    (whose sliver, free at a door, would join the rooms on either side).

    A line runs along a wall when the wall is parallel to it (within 1e-6 rad: the
    walls on the dominant directions, :func:`floorscan.floorplan.hypotheses.dominant_axes`)
    and its axis lies within :data:`LINE_HALF_WIDTH_M` and half the wall's thickness of
    the line; the longest such wall wins.

    Parameters
    ----------
    lines : (M, 4) float ndarray
        Metres.
    axes : (N, 4) float ndarray
        The plan's wall axes on the dominant directions, metres.
    thickness : (N,) float ndarray
        Metres.

    Returns
    -------
    (M, 4) float64 ndarray
        A new array.
    """
    lines = np.asarray(lines, dtype=np.float64).reshape(-1, 4).copy()
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    if not len(lines) or not len(axes):
        return lines
    wd = axes[:, 2:] - axes[:, :2]
    wlen = np.hypot(*wd.T)
    wu = wd / np.maximum(wlen, 1e-12)[:, None]
    for m, a in enumerate(lines):
        d = a[2:] - a[:2]
        u = d / max(float(np.hypot(*d)), 1e-12)
        nrm = np.array([-u[1], u[0]])
        parallel = (np.abs(wu[:, 0] * u[1] - wu[:, 1] * u[0]) < 1e-6) & (wlen > 0)
        off = ((axes[:, :2] + axes[:, 2:]) / 2 - a[:2]) @ nrm
        near = parallel & (np.abs(off) <= LINE_HALF_WIDTH_M + thickness / 2)
        if near.any():
            k = np.flatnonzero(near)[np.argmax(wlen[near])]
            lines[m] += np.r_[off[k] * nrm, off[k] * nrm]
    return lines


def map_hypotheses(grid, axes: np.ndarray, thickness: np.ndarray, frame, door_max_m: float):
    """The wall hypotheses of ``grid``'s occupied cells for the cell complex: the
    representative lines on the plan's dominant directions, moved onto the plan's
    walls they run along (:func:`onto_walls`) and extended across ``frame``, and the
    openings between their runs (module docstring).

    Parameters
    ----------
    grid : OccupancyGrid
        Its occupied cells (a map's, or the scans').
    axes : (N, 4) float ndarray
        The plan's wall axes, metres (their dominant directions are the lines').
    thickness : (N,) float ndarray
        Metres.
    frame : shapely.Polygon
        The box the complex fills.
    door_max_m : float
        The widest opening a wall closes, metres.

    Returns
    -------
    lines : (M, 4) float64 ndarray
        Extended lines, without evidence of their own (measured on the grid edge by edge).
    openings : (K, 4) float64 ndarray
        Closed openings: evidence of a boundary.
    """
    from floorscan.floorplan.hypotheses import dominant_axes, dominant_directions

    directions, _ = dominant_directions(axes)
    xy = grid.cell_centres(grid.occupied())
    lines, _, openings = representative_lines(xy, grid.resolution_m, directions, door_max_m)
    on_dominant = dominant_axes(axes)
    lines = onto_walls(lines, on_dominant, thickness)
    openings = onto_walls(openings, on_dominant, thickness)
    return extended_lines(lines, frame), openings
