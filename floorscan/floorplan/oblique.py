"""Structure step 6's second rule: a short face hanging from the wall graph by one end
into the free space, turned away from every direction of the building's long faces, is
furniture (a desk turned in the room against a wall's end, a line the map extractor
fitted through a row of chairs and a table up to a wall).

A building's walls run in the directions of its long walls, parallel or square to them
(the dominant directions of ROSE^2, Luperto et al., RA-L 2022, whose first step finds
them; Manhattan or not, a wall shares its direction with the walls it meets). A face
that runs in none of them is no wall when nothing but one end holds it: it is shorter
than ``clutter_max_length_m``, the free space lies on both its sides, exactly one of
its ends is at a junction and no face crosses it. A face held at both ends is part of
the wall graph (a curved wall's facet, a partition's stub between two walls); one held
at neither is judged by step 6's first rule
(:func:`~floorscan.floorplan.clutter.loose_in_free_space`), which keeps it when its
ends were not seen past; one crossed by another is an X junction.

Every long face (``clutter_max_length_m`` or longer) gives a direction, however short
its share of the walls, so a building's one diagonal wing keeps its walls (intel's
north-east room), where the dominant directions, each at least a tenth of the walls'
length, would not.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.free_space import StructureParams

#: A face is in a long face's direction when the two differ by at most this, parallel or
#: square, degrees: the pieces of one wall on a map bent by odometry drift or by SLAM,
#: and a wall's end stub fitted on few cells, turn by up to about ten degrees from its
#: line; a furniture line stands at any angle, and is caught from here to 45 degrees.
OBLIQUE_MIN_DEG = 15.0


def oblique_in_free_space(seg: np.ndarray, ends: np.ndarray, crossed: np.ndarray, both_free: np.ndarray,
                          params: StructureParams = StructureParams()) -> np.ndarray:  # fmt: skip
    """Which faces stand in the free space in no direction of the building's long faces
    (the module docstring).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces ``x0, y0, x1, y1`` after the junction snap, metres.
    ends : (F, 2) bool ndarray
        Whether each end is at a junction
        (:func:`~floorscan.floorplan.junctions.junction_ends`).
    crossed : (F,) bool ndarray
        Which faces another face crosses away from their ends (an X junction).
    both_free : (F,) bool ndarray
        Which faces have free space on both sides
        (:func:`~floorscan.floorplan.structure.border_and_support`, ``both_free``).
    params : StructureParams
        ``clutter_max_length_m``: a long face; a short one.

    Returns
    -------
    (F,) bool ndarray
        True: furniture; all False when no face is long (no direction known).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    long = length >= params.clutter_max_length_m
    if not long.any():
        return np.zeros(len(seg), dtype=bool)
    angle = np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0])
    turn = np.mod(angle[:, None] - angle[None, long], np.pi / 2)
    turn = np.minimum(turn, np.pi / 2 - turn).min(axis=1)  # parallel or square: mod 90 degrees
    return (
        ~long & (turn > np.radians(OBLIQUE_MIN_DEG)) & (np.asarray(ends, dtype=bool).sum(axis=1) == 1)
        & ~np.asarray(crossed, dtype=bool) & np.asarray(both_free, dtype=bool)
    )  # fmt: skip
