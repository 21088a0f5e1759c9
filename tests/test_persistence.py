"""Rooms by persistence (:mod:`floorscan.floorplan.persistence`): the regions of the
distance to the walls merged across every passage that is no framed door at most three
quarters as wide as the space on each side of it."""

import numpy as np
import pytest

from floorscan.floorplan.persistence import DOOR_SHARE, persistent_rooms, saddles
from floorscan.floorplan.room_space import RoomParams, RoomRaster, space_regions

RES = 0.05


def regions(space: np.ndarray):
    raster = RoomRaster(np.zeros(2), RES, ~space, space, ~space, ~space)
    return space_regions(raster, RoomParams())


def two_rooms(gap_m: float, room_m: float = 4.0) -> np.ndarray:
    """Two square rooms side by side, a wall of one cell between them with a gap of
    ``gap_m`` in its middle; one cell of wall around."""
    n = int(round(room_m / RES))
    space = np.zeros((n + 2, 2 * n + 3), dtype=bool)
    space[1:-1, 1 : n + 1] = True
    space[1:-1, n + 2 : 2 * n + 2] = True
    g = int(round(gap_m / RES))
    lo = (n + 2 - g) // 2
    space[lo : lo + g, n + 1] = True
    return space


def n_rooms(space: np.ndarray, framed=None) -> int:
    labels, distance = regions(space)
    root = persistent_rooms(labels, distance, RoomParams().door_max_m, framed)
    return len(np.unique(root[labels[labels > 0]]))


@pytest.mark.parametrize(("gap_m", "rooms"), [(0.9, 2), (1.2, 2), (1.9, 2), (2.5, 1), (3.5, 1)])
def test_a_door_keeps_two_rooms_and_a_passage_wider_than_a_door_joins_them(gap_m, rooms):
    assert n_rooms(two_rooms(gap_m)) == rooms


def test_a_door_needs_its_frame():
    """The same narrowing, not framed by walls (the caller says which pairs are), is no
    door: the shadow of a table does not cut a room in two."""
    space = two_rooms(0.9)
    labels, _ = regions(space)
    assert n_rooms(space) == 2
    assert n_rooms(space, framed=set()) == 1
    assert labels.max() >= 2


def test_a_corridor_narrowed_by_less_than_a_quarter_is_one_corridor():
    """A 1.8 m corridor, 12 m long, narrowed to 1.5 m for 0.3 m halfway (a jamb, a
    pillar): 1.5 / 1.8 is above DOOR_SHARE, one room; narrowed to 0.9 m it is a door."""
    assert 1.5 / 1.8 > DOOR_SHARE > 0.9 / 1.8
    for width_m, rooms in ((1.5, 1), (0.9, 2)):
        space = np.zeros((40, 244), dtype=bool)
        space[2:38, 2:242] = True  # 1.8 m wide
        cut = int(round((1.8 - width_m) / 2 / RES))
        space[2 : 2 + cut, 118:124] = False
        space[38 - cut : 38, 118:124] = False
        assert n_rooms(space) == rooms, width_m


def corridor_between_halls(narrow_m: float) -> np.ndarray:
    """Two halls 4 m square joined by a corridor 2.1 m wide and 12 m long, entered from
    each hall through a throat 1.6 m wide and 0.5 m long, narrowed to ``narrow_m`` for
    0.3 m halfway. One cell of wall around."""
    hall, throat, corridor = 80, 10, 240  # cells: 4 m, 0.5 m, 12 m
    width, throat_w = 42, 32  # 2.1 m, 1.6 m
    length = 2 * hall + 2 * throat + corridor
    space = np.zeros((hall + 2, length + 2), dtype=bool)
    space[1 : 1 + hall, 1 : 1 + hall] = True
    space[1 : 1 + hall, 1 + length - hall : 1 + length] = True
    top, ttop = 1 + (hall - width) // 2, 1 + (hall - throat_w) // 2
    space[ttop : ttop + throat_w, 1 + hall : 1 + length - hall] = True
    space[top : top + width, 1 + hall + throat : 1 + length - hall - throat] = True
    cut = int(round((2.1 - narrow_m) / 2 / RES))
    mid = 1 + length // 2
    space[top : top + cut, mid - 3 : mid + 3] = False
    space[top + width - cut : top + width, mid - 3 : mid + 3] = False
    return space


def test_a_corridor_narrowed_by_less_than_a_quarter_is_one_corridor_between_two_halls():
    """The corridor of :func:`corridor_between_halls`: its two halves are basins of their
    own (1.05 m to their walls, 0.2 m above the narrowing) and join their halls through
    the throats (a saddle of 0.8 m, 0.76 of the corridor's 1.05: no door). Narrowed to
    1.7 m (a saddle of 0.85 m, 0.81 of 1.05) the corridor is one room with its halls:
    the passage is compared with the basins beside it. Compared with the peak of the
    room each half had joined, its hall's 2 m (ToMATo's order, the tree before), it was a
    door and the rooms two halves: aces' corridors were cut so. Narrowed to 1.1 m by a
    door's jambs (0.55 m, 0.52 of 1.05) it is a door."""
    for narrow_m, rooms in ((1.7, 1), (1.1, 2)):
        space = corridor_between_halls(narrow_m)
        labels, _ = regions(space)
        assert labels.max() >= 4, narrow_m  # the halls and the corridor's halves
        assert n_rooms(space) == rooms, narrow_m


def test_the_rooms_do_not_depend_on_the_raster_orientation():
    """Transposed, mirrored and turned a quarter: the same rooms, cell for cell."""
    space = two_rooms(1.0)
    space[20:30, 30:60] = False  # something in the first room
    labels, distance = regions(space)
    root = persistent_rooms(labels, distance, 2.0)
    base = root[labels]
    for f, inv in ((np.transpose, np.transpose), (np.fliplr, np.fliplr), (np.rot90, lambda a: np.rot90(a, -1))):
        lab2, dist2 = regions(f(space))
        root2 = persistent_rooms(lab2, dist2, 2.0)
        back = inv(root2[lab2])
        # the same partition: each room of one is one room of the other
        pairs = {(int(a), int(b)) for a, b in zip(base[space], back[space])}
        assert len(pairs) == len(np.unique(base[space])) == len(np.unique(back[space]))


def test_saddles_are_the_widest_contact_of_each_pair():
    labels = np.array([[1, 1, 2, 2], [1, 1, 2, 2], [3, 3, 3, 3]])
    distance = np.array([[1.0, 2.0, 3.0, 1.0], [1.0, 0.5, 0.7, 1.0], [4.0, 4.0, 4.0, 4.0]])
    pairs, height = saddles(labels, distance)
    got = {tuple(p): h for p, h in zip(pairs.tolist(), height)}
    assert got == {(1, 2): 2.0, (1, 3): 1.0, (2, 3): 1.0}
