"""Where each room's label goes on a drawing of the plan (the SVG and the DXF): inside its
room, as large as fits up to the drawing's own size, and clear of every other label.

The rules are the cartographer's for area names (Imhof, "Positioning names on maps",
The American Cartographer 2(2), 1975: a name lies inside its area, at its visual centre
where it fits, and never over another name), placed greedily in order of preference
as in Christensen, Marks and Shieber ("An empirical study of algorithms for point-feature
label placement", ACM Transactions on Graphics 14(3), 1995): the rooms from the largest,
each taking the first place that works of

1. its name and area at full size, then at each smaller size of :data:`LABEL_SCALES`,
   centred at the pole of inaccessibility
   (:attr:`~floorscan.floorplan.footprints.PlanExports.room_labels`), else at the point
   nearest it, on a grid of :data:`LABEL_GRID_STEPS` steps a line high, where the label's
   box lies inside the room and clear of the labels placed: level at any of these
   sizes first (level text reads best), then along the room's length (the long side of
   its minimum rotated rectangle, read from the left or from below, as a plan names a
   corridor along it) when that length runs more than :data:`LABEL_TURN_MIN_DEG` off
   the level;
   at each size a place clear of what the drawing asks (the SVG: its doors' swings)
   first, then one over it;
2. the same with the name alone (a room too small for two lines);
3. the name alone, level, at the least size, where it overlaps the labels placed least
   (inside the room if any grid point is), so a label is never dropped.

A label's box is its text's: :data:`CHAR_WIDTH_EM` of the font size a character and the
lines' heights. Two labels inside their rooms have a wall between them; one that spills
out of its room keeps :data:`LABEL_MARGIN_EM` from the labels placed before it where it
can.

To use it: :func:`place_room_labels` with the rooms' polygons, their poles and the two
boxes of each label at full size, in the drawing's units (metres for the DXF; the SVG
gives its boxes in metres too, its pixels divided by its scale).
"""

from __future__ import annotations

import numpy as np

#: The sizes a label may take, as fractions of the drawing's own, largest first; the
#: least (2/3) is the size the drawing's other text was laid out at (the SVG's 12 px
#: before :data:`~floorscan.floorplan.svg.SVG_TEXT_SCALE`), so no label reads smaller
#: than the scale bar's.
LABEL_SCALES = (1.0, 5 / 6, 2 / 3)
#: The average advance of a sans-serif character, em: DejaVu Sans' and Helvetica's digits
#: and lower case letters are 0.5 to 0.64 em wide; the box errs wide.
CHAR_WIDTH_EM = 0.6
#: Free space a label that spills out of its room keeps round its box, em of its font (a
#: quarter line: it does not touch another label).
LABEL_MARGIN_EM = 0.25
#: Candidate places of a label that does not fit at the pole: a grid of this many steps a
#: line (the label's first line) high, the nearest the pole first.
LABEL_GRID_STEPS = 4
#: A label is turned along its room only where the room's length runs more than this off
#: the level, degrees: a room a few degrees off the drawing's axes reads level.
LABEL_TURN_MIN_DEG = 20.0
#: The most candidate places tried per room and size (the nearest the pole); a room's
#: label lies near its centre, and a large room fits its label at the pole.
LABEL_MAX_CANDIDATES = 4000


def text_box(lines: list[tuple[str, float]], gap: float = 0.0) -> tuple[float, float]:
    """The box of a label of ``lines`` (text and font size, stacked ``gap`` apart), in
    the units of the font sizes: width (:data:`CHAR_WIDTH_EM` a character of the widest
    line) and height (the sum of the sizes and the gaps)."""
    width = max(len(text) * CHAR_WIDTH_EM * size for text, size in lines)
    height = sum(size for _, size in lines) + gap * (len(lines) - 1)
    return width, height


def room_label_boxes(rooms, name_size: float, area_size: float, gap: float):
    """The texts of each room's label and their boxes at full size (:func:`text_box`):
    its name, and its area in m\u00b2 on a second line ``gap`` below.

    Parameters
    ----------
    rooms : pandas.DataFrame
        ``name`` and ``area_m2`` (:attr:`~floorscan.floorplan.plan.FloorPlan.rooms`).
    name_size, area_size, gap : float
        The lines' font sizes and the gap between them, the drawing's units.

    Returns
    -------
    names, areas : list of str
    full, name_only : (R, 2) float64 ndarray
        Width and height of the label with its area, and of the name alone.
    """
    names = [str(v) for v in rooms["name"].tolist()]
    areas = [f"{float(v):.1f} m\u00b2" for v in rooms["area_m2"].tolist()]
    full = np.array([text_box([(n, name_size), (a, area_size)], gap) for n, a in zip(names, areas)]).reshape(-1, 2)
    name_only = np.array([text_box([(n, name_size)]) for n in names]).reshape(-1, 2)
    return names, areas, full, name_only


def place_room_labels(polys, poles: np.ndarray, full: np.ndarray, name_only: np.ndarray, line: np.ndarray,
                      avoid=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Each room's label place and size (the module docstring).

    Parameters
    ----------
    polys : (R,) sequence of shapely Polygon or None
        The rooms, in the drawing's units (metres); a missing or empty polygon gets no
        label.
    poles : (R, 2) float ndarray
        Each room's pole of inaccessibility (NaN for a missing polygon).
    full, name_only : (R, 2) float ndarray
        Width and height of each room's label at full size: its name and area, and its
        name alone (:func:`text_box`), the drawing's units.
    line : (R,) float ndarray
        The height of each label's first line at full size (its font size), the
        drawing's units: the grid step and the margin are in lines.
    avoid : shapely geometry, optional
        What the labels keep clear of where they can (the doors' swings): each form,
        direction and size of a label is tried clear of it first, then over it (a label
        moves off a door's swing, it does not shrink for it).

    Returns
    -------
    xy : (R, 2) float64 ndarray
        The centre of each label's box (NaN where there is no label).
    scale : (R,) float64 ndarray
        Its size, one of :data:`LABEL_SCALES` (NaN where there is no label).
    with_area : (R,) bool ndarray
        Whether the label holds the area as well as the name.
    angle : (R,) float64 ndarray
        The direction its text runs, radians counter-clockwise from +x, in (-pi/2,
        pi/2]: 0 level (NaN where there is no label).
    """
    import shapely

    n = len(polys)
    poles = np.asarray(poles, dtype=np.float64).reshape(n, 2)
    full = np.asarray(full, dtype=np.float64).reshape(n, 2)
    name_only = np.asarray(name_only, dtype=np.float64).reshape(n, 2)
    line = np.asarray(line, dtype=np.float64).reshape(n)
    xy, scale, with_area = np.full((n, 2), np.nan), np.full(n, np.nan), np.zeros(n, dtype=bool)
    angle = np.full(n, np.nan)
    ok = [k for k in range(n) if polys[k] is not None and not polys[k].is_empty and np.isfinite(poles[k]).all()]
    placed: list = []  # the boxes placed
    for k in sorted(ok, key=lambda k: (-polys[k].area, k)):
        poly = polys[k]
        shapely.prepare(poly)
        taken = shapely.union_all(placed) if placed else None
        clear_of = [avoid, None] if avoid is not None and not avoid.is_empty else [None]
        # the first preference at the pole, the first of the candidate places: most rooms
        # take it, and need no grid
        box = _boxes(poles[k][None], full[k], 0.0)[0]
        if poly.contains(box) and not any(g is not None and g.intersects(box) for g in (taken, clear_of[0])):
            xy[k], scale[k], with_area[k], angle[k] = poles[k], LABEL_SCALES[0], True, 0.0
            placed.append(box)
            continue
        pts = _candidates(poly, poles[k], line[k] * LABEL_SCALES[-1] / LABEL_GRID_STEPS)
        turns = [0.0] + [a for a in [_length_angle(poly)] if abs(a) > np.radians(LABEL_TURN_MIN_DEG)]
        choice = None
        for size, area in ((full[k], True), (name_only[k], False)):
            for turn in turns:
                for f, other in ((f, o) for f in LABEL_SCALES for o in clear_of):
                    boxes = _boxes(pts, size * f, 0.0, turn)
                    good = shapely.contains(poly, boxes)
                    if taken is not None:
                        good &= ~shapely.intersects(taken, boxes)
                    if other is not None:
                        good &= ~shapely.intersects(other, boxes)
                    if good.any():
                        i = int(np.argmax(good))
                        choice = (pts[i], f, area, turn, boxes[i])
                        break
                if choice is not None:
                    break
            if choice is not None:
                break
        if choice is None:  # nowhere clear: the name alone, level, least size, least overlap
            f = LABEL_SCALES[-1]
            grown = _boxes(pts, name_only[k] * f, LABEL_MARGIN_EM * line[k] * f, 0.0)
            overlap = shapely.area(shapely.intersection(taken, grown)) if taken is not None else np.zeros(len(pts))
            i = int(np.argmin(overlap))  # the first (nearest the pole) of the least
            choice = (pts[i], f, False, 0.0, _boxes(pts[i : i + 1], name_only[k] * f, 0.0, 0.0)[0])
        xy[k], scale[k], with_area[k], angle[k] = choice[:4]
        placed.append(choice[4])
    return xy, scale, with_area, angle


def _length_angle(poly) -> float:
    """The direction of ``poly``'s length, the long side of its minimum rotated
    rectangle (``shapely.oriented_envelope``), radians in (-pi/2, pi/2]."""
    import shapely

    box = shapely.oriented_envelope(poly)
    if box.geom_type != "Polygon":
        return 0.0
    c = np.asarray(box.exterior.coords)[:3]
    sides = np.diff(c, axis=0)
    dx, dy = sides[int(np.argmax(np.hypot(sides[:, 0], sides[:, 1])))]
    a = float(np.arctan2(dy, dx))
    if a <= -np.pi / 2:
        a += np.pi
    elif a > np.pi / 2:
        a -= np.pi
    return a


def _candidates(poly, pole: np.ndarray, step: float) -> np.ndarray:
    """The pole, then the points of a grid of ``step`` through it that lie in ``poly``,
    nearest the pole first (ties in grid order), at most :data:`LABEL_MAX_CANDIDATES`."""
    import shapely

    x0, y0, x1, y1 = poly.bounds
    step = max(step, max(x1 - x0, y1 - y0) / 1000.0, 1e-9)  # at most ~10^6 grid points
    gx = pole[0] + step * np.arange(np.floor((x0 - pole[0]) / step), np.ceil((x1 - pole[0]) / step) + 1)
    gy = pole[1] + step * np.arange(np.floor((y0 - pole[1]) / step), np.ceil((y1 - pole[1]) / step) + 1)
    X, Y = np.meshgrid(gx, gy)
    pts = np.c_[X.ravel(), Y.ravel()]
    d2 = ((pts - pole) ** 2).sum(axis=1)
    order = np.argsort(d2, kind="stable")
    pts = pts[order]
    pts = pts[shapely.contains_xy(poly, pts[:, 0], pts[:, 1])][:LABEL_MAX_CANDIDATES]
    return np.vstack([pole[None, :], pts])


def _boxes(pts: np.ndarray, size: np.ndarray, margin: float, turn: float = 0.0):
    """Boxes of ``size`` (width, height) centred at ``pts``, grown by ``margin``, their
    width along ``turn`` (radians)."""
    import shapely

    hw, hh = size[0] / 2 + margin, size[1] / 2 + margin
    if turn == 0.0:
        return shapely.box(pts[:, 0] - hw, pts[:, 1] - hh, pts[:, 0] + hw, pts[:, 1] + hh)
    u, v = np.array([np.cos(turn), np.sin(turn)]), np.array([-np.sin(turn), np.cos(turn)])
    corners = np.array([-hw * u - hh * v, hw * u - hh * v, hw * u + hh * v, -hw * u + hh * v, -hw * u - hh * v])
    return shapely.polygons(pts[:, None, :] + corners[None, :, :])
