"""Objects deeper than a cabinet against a wall whose thickness is seen
(floorscan.floorplan.hidden: backed, body_seen_free; their use in into_corners and
clutter.in_front_of_walls)."""

from __future__ import annotations

import numpy as np
import pytest

from floorscan.floorplan.clutter import in_front_of_walls, object_sides
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.hidden import BACKING_MAX_M, OBJECT_MAX_DEPTH_M, backed, body_seen_free, into_corners

P = StructureParams()
NONE_FREE = lambda xy: np.zeros(len(xy), dtype=bool)  # noqa: E731  (an object's body: never seen free)
ALL_FREE = lambda xy: np.ones(len(xy), dtype=bool)  # noqa: E731  (a corridor: seen free)
CLOSED = lambda p, u, t0, t1: 0.0  # noqa: E731  (no free space on a wall's line)

# a wall 0.3 m thick along y = -0.3..0: its room face (free to the north) seen from x = 0
# to 5, its corridor face (free to the south) from 0 to 8; a desk 3 m long and 1.5 m deep
# stands in the room's south-east corner against it (x 5..8, y 0..1.5), so
# its front at y = 1.5 (free to the north) and its side at x = 5 (free to the west) are
# what the room face shows; the room's east wall face is x = 8, seen from y = 1.5 up
ROOM_FACE = [0.0, 0.0, 5.0, 0.0]
OTHER_FACE = [0.0, -0.3, 8.0, -0.3]
FRONT = [5.0, 1.5, 8.0, 1.5]
SIDE_FACE = [5.0, 0.0, 5.0, 1.5]
EAST = [8.0, 1.5, 8.0, 6.0]


def test_a_wall_is_backed_where_its_other_face_runs_on_behind_the_stretch():
    seg = np.array([[0.0, 0.0, 8.0, 0.0], OTHER_FACE])
    side = np.array([1, -1])  # free north of the first (left of +x), south of the second
    assert backed(seg, side, 0, 5.0, 8.0, P)
    assert not backed(seg[:1], side[:1], 0, 5.0, 8.0, P)  # no other face
    assert not backed(seg, np.array([1, 1]), 0, 5.0, 8.0, P)  # free the same way: a second wall face
    far = np.array([[0.0, 0.0, 8.0, 0.0], [0.0, -BACKING_MAX_M - 0.1, 8.0, -BACKING_MAX_M - 0.1]])
    assert not backed(far, side, 0, 5.0, 8.0, P)  # thicker than a wall: another room's wall
    short = np.array([[0.0, 0.0, 8.0, 0.0], [0.0, -0.3, 6.0, -0.3]])
    assert not backed(short, side, 0, 5.0, 8.0, P)  # covers a third of the stretch
    assert backed(short, side, 0, 5.0, 6.2, P)  # covers 1.0 of 1.2 m, over front_overlap (0.8)


def test_the_share_of_an_objects_body_seen_free():
    p, u, n = np.zeros(2), np.array([1.0, 0.0]), np.array([0.0, 1.0])
    assert body_seen_free(p, u, n, 5.0, 8.0, 1.5, NONE_FREE, 0.15) == 0.0
    assert body_seen_free(p, u, n, 5.0, 8.0, 1.5, ALL_FREE, 0.15) == 1.0
    # free beyond y = 0.75: the samples at 0.15 .. 1.35 m in steps of 0.15, half of them
    assert body_seen_free(p, u, n, 5.0, 8.0, 1.5, lambda xy: xy[:, 1] > 0.75, 0.15) == pytest.approx(4 / 9)


def test_a_deep_object_in_a_corner_hides_the_wall_to_the_corner_only_where_the_wall_is_backed():
    seg = np.array([ROOM_FACE, OTHER_FACE, FRONT, SIDE_FACE, EAST])
    side = np.array([1, -1, 1, 1, 1])  # north, south, north, west (left of +y), west
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    assert np.allclose(out[0], [0.0, 0.0, 8.0, 0.0]) and np.allclose(out[1:], seg[1:])
    # a cabinet's depth only, without the free-space test: the 1.5 m deep desk hides nothing
    assert np.allclose(into_corners(seg, side, CLOSED, P)[0], ROOM_FACE)
    # no other face behind (an outer wall, or a step of the wall): the face stays
    assert np.allclose(into_corners(np.delete(seg, 1, axis=0), np.delete(side, 1), CLOSED, P, NONE_FREE)[0], ROOM_FACE)
    # the "desk" seen through (a corridor between the faces), or deeper than an object
    assert np.allclose(into_corners(seg, side, CLOSED, P, ALL_FREE)[0], ROOM_FACE)
    deeper = seg.copy()
    deeper[2, [1, 3]] = deeper[4, 1] = deeper[3, 3] = OBJECT_MAX_DEPTH_M + 0.2
    assert np.allclose(into_corners(deeper, side, CLOSED, P, NONE_FREE)[0], ROOM_FACE)


def test_an_object_beyond_the_wall_is_no_corner_of_the_room():
    """A chair leg in the corridor south of the wall (x = 6.5, y -1.0..-0.6), square to
    the room face's line and within an object's depth of it, lies wholly behind the
    face: it is no corner of the room, and the face still runs on to the east wall."""
    leg = [6.5, -1.0, 6.5, -0.6]
    seg = np.array([ROOM_FACE, OTHER_FACE, FRONT, SIDE_FACE, EAST, leg])
    side = np.array([1, -1, 1, 1, 1, 1])
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    assert np.allclose(out[0], [0.0, 0.0, 8.0, 0.0]) and np.allclose(out[1:], seg[1:])
    # the same leg in the room, in front of the desk's side: the face stops at its line
    inside = seg.copy()
    inside[5] = [6.5, 2.0, 6.5, 2.4]
    assert np.allclose(into_corners(inside, side, CLOSED, P, NONE_FREE)[0], [0.0, 0.0, 6.5, 0.0])


def test_a_deep_front_is_clutter_only_where_the_wall_is_backed_and_its_body_unseen():
    seg = np.array([[0.0, 0.0, 8.0, 0.0], OTHER_FACE, FRONT])
    side = np.array([1, -1, 1])
    wall = np.array([True, True, True])  # all longer than a piece of furniture
    front, behind = in_front_of_walls(seg, side, wall, P, NONE_FREE)
    assert front.tolist() == [False, False, True] and behind.tolist() == [-1, -1, 0]
    assert not in_front_of_walls(seg, side, wall, P)[0].any()  # 1.5 m: deeper than front_max_m
    assert not in_front_of_walls(seg, side, wall, P, ALL_FREE)[0].any()  # a corridor between
    assert not in_front_of_walls(seg[[0, 2]], side[[0, 2]], wall[[0, 2]], P, NONE_FREE)[0].any()  # not backed
    # a face 1.5 m north of the wall and free to the north as the wall's face is: the
    # far face of a wall across a corridor, when the corridor between them was seen free
    across = np.array([[0.0, 0.0, 8.0, 0.0], OTHER_FACE, [2.0, 1.5, 6.0, 1.5]])
    corridor = lambda xy: (xy[:, 1] > 0.0) & (xy[:, 1] < 1.5)  # noqa: E731
    assert not in_front_of_walls(across, side, wall, P, corridor)[0].any()
    assert in_front_of_walls(across, side, wall, P, NONE_FREE)[0].tolist() == [False, False, True]


def test_the_sides_of_a_cabinet_against_a_wall_go_with_its_front():
    """A cabinet 2 m long and 0.6 m deep against the wall y = 0 (free to the north):
    its front at y = 0.6 and its two sides from the wall to the front's ends are the
    object; a stub as long as the cabinet is deep beside a shorter front, a face free
    towards the cabinet's body, and one running on into the room are not its sides."""
    seg = np.array([
        [0.0, 0.0, 8.0, 0.0],  # the wall face, free to the north
        [3.0, 0.6, 5.0, 0.6],  # the front, free to the north
        [3.0, 0.0, 3.0, 0.6],  # west side, free to the west
        [5.0, 0.6, 5.0, 0.0],  # east side, free to the east
        [3.0, 0.6, 3.0, 1.6],  # a face from the front's end on into the room
    ])  # fmt: skip
    side = np.array([1, 1, 1, 1, 1])
    front = np.array([False, True, False, False, False])
    behind = np.array([-1, 0, -1, -1, -1])
    assert object_sides(seg, side, front, behind, P).tolist() == [False, False, True, True, False]
    # the west face free towards the body (east): a wall's end, not the object's side
    assert object_sides(seg, np.array([1, 1, -1, 1, 1]), front, behind, P).tolist() == [False, False, False, True, False]
    # a front 0.4 m long between faces 0.6 m long: deeper than long, a pier of the wall
    narrow = seg.copy()
    narrow[1] = [3.0, 0.6, 3.4, 0.6]
    narrow[3] = [3.4, 0.6, 3.4, 0.0]
    assert not object_sides(narrow, side, front, behind, P).any()


# a partition 0.2 m thick (faces x = 0, free to the west, and x = 0.2, free to the
# east) from y = 0 to 4, and on its two sides, from y = 4.05 up to the wall at y = 8,
# a cabinet 1.0 m deep to the west and one 0.8 m deep to the east, back to back
# across it; the wall's face at y = 8 is seen west and east of the cabinets
PARTITION_WEST = [0.0, 0.0, 0.0, 4.0]
PARTITION_EAST = [0.2, 0.0, 0.2, 4.0]


def cabinets(east_depth_m: float) -> list[list[float]]:
    """The faces of the two cabinets, the east one ``east_depth_m`` deep, and the wall's."""
    e = 0.2 + east_depth_m
    return [
        [-1.0, 4.05, -1.0, 8.0],  # the west cabinet's front, free to the west
        [-1.0, 4.05, 0.0, 4.05],  # its side, free to the south
        [e, 4.05, e, 8.0],  # the east cabinet's front, free to the east
        [0.2, 4.05, e, 4.05],  # its side, free to the south
        [-5.0, 8.0, -1.0, 8.0],  # the wall's face west of the cabinets, free to the south
        [e, 8.0, 5.0, 8.0],  # east of them
    ]


CABINETS = cabinets(0.8)
CABINET_SIDES = [1, -1, -1, -1, -1, -1]


def test_a_partition_runs_on_behind_cabinets_back_to_back_to_the_wall():
    seg = np.array([PARTITION_WEST, PARTITION_EAST, *CABINETS])
    side = np.array([1, -1, *CABINET_SIDES])
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    # the east face goes on behind the shallow cabinet to the wall's face nearest it
    # (the east piece, 0.8 m from its line, not the west one, 1.2 m), and then the west
    # face, backed by it, behind the deeper one
    assert np.allclose(out[0], [0.0, 0.0, 0.0, 8.0]) and np.allclose(out[1], [0.2, 0.0, 0.2, 8.0])
    assert np.allclose(out[2:], seg[2:])
    # without the east cabinet's front the east face stops at the side; the west face
    # then has no room behind it within an object's depth, nor a backed face: both stay
    alone = np.delete(seg, 4, axis=0)
    out = into_corners(alone, np.delete(side, 4), CLOSED, P, NONE_FREE)
    assert np.allclose(out[:2], alone[:2])


def test_a_step_of_an_outer_wall_is_a_corner():
    # the face x = 0 (free to the west) steps 0.5 m west at y = 4.05 and runs on to the
    # wall at y = 8; nothing behind it (the outside): the step is the face's corner
    seg = np.array([PARTITION_WEST, [-0.5, 4.05, 0.0, 4.05], [-0.5, 4.05, -0.5, 8.0], [-5.0, 8.0, 5.0, 8.0]])
    side = np.array([1, -1, 1, -1])
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    assert out[0, 3] < 4.1


def test_a_face_ending_on_a_wall_is_not_carried_through_it():
    # a cabinet's face along y = 0.3 (free to the south) ends 5 mm inside the east face
    # of a partition (x 0 .. 0.35) whose end face, y = 0, lies 0.3 m in front of it
    seg = np.array([[0.9, 0.3, 0.345, 0.3], [0.0, 0.0, 0.35, 0.0], [0.35, 0.0, 0.35, 4.0], [0.0, 0.0, 0.0, 4.0]])
    side = np.array([1, -1, -1, 1])
    assert np.allclose(into_corners(seg, side, CLOSED, P, NONE_FREE), seg)


# the partition of CABINETS with a cabinet 1.0 m deep on each side, both deeper than
# front_max_m (0.9 m), so neither face is carried behind a shallow one first
DEEP_CABINETS = cabinets(1.0)


def test_a_partition_runs_on_between_deep_cabinets_back_to_back_to_the_wall():
    """Two cabinets 1.0 m deep back to back at a partition's end (office_h of Bormann
    et al.'s benchmark): each face of the partition is backed by the other's cabinet,
    not by its own wall, and both run on to the wall; with the cabinets' sides one face
    flush with the partition's end, 2.2 m long across it, too; a face as long behind
    the partition (a wall it ends on) is its corner."""
    seg = np.array([PARTITION_WEST, PARTITION_EAST, *DEEP_CABINETS])
    side = np.array([1, -1, *CABINET_SIDES])
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    assert np.allclose(out[0], [0.0, 0.0, 0.0, 8.0]) and np.allclose(out[1], [0.2, 0.0, 0.2, 8.0])
    assert np.allclose(into_corners(seg, side, CLOSED, P, ALL_FREE)[:2], seg[:2])  # the "cabinets" seen through
    assert np.allclose(into_corners(np.delete(seg, 4, axis=0), np.delete(side, 4), CLOSED, P, NONE_FREE)[:2], seg[:2])
    flush = np.array([[0.0, 0.0, 0.0, 4.0], [0.2, 0.0, 0.2, 4.0], [-1.0, 4.0, -1.0, 8.0], [-1.0, 4.0, 1.2, 4.0],
                      [1.2, 4.0, 1.2, 8.0], *DEEP_CABINETS[4:]])
    flush_side = np.array([1, -1, 1, -1, -1, -1, -1])
    out = into_corners(flush, flush_side, CLOSED, P, NONE_FREE)
    assert np.allclose(out[0], [0.0, 0.0, 0.0, 8.0]) and np.allclose(out[1], [0.2, 0.0, 0.2, 8.0])
    # the same face running 3.5 m on west behind the partition: a wall, the partition's corner
    wall = flush.copy()
    wall[3, 0] = -3.5
    assert np.allclose(into_corners(wall, flush_side, CLOSED, P, NONE_FREE)[:2], flush[:2])
    # the flush face is the two cabinets' sides, from one front's end across the
    # partition's line to the other's
    carried = out.copy()
    front = np.array([False, False, True, False, True, False, False])
    behind = np.array([-1, -1, 0, -1, 1, -1, -1])
    assert object_sides(carried, flush_side, front, behind, P).tolist() == [False, False, False, True, False, False, False]


def test_a_face_in_an_l_corner_stays_in_its_corner():
    """A partition (x = 0, free to the east) whose end meets, at y = 4, the end of a wall
    2.5 m long running west behind it (y = 4, free to the south, 5 mm past the line): an
    L corner. A block
    on the wall (x -1.2 .. 0.37, y 4.1 .. 4.8, its east side in front of the partition's
    line) does not carry the partition through the corner to its top (intel, the room
    at (-8, -19))."""
    seg = np.array([
        [0.0, 0.0, 0.0, 4.0],  # the partition's east face, free to the east
        [-2.5, 4.0, 0.005, 4.0],  # the wall, free to the south, ending 5 mm past the line
        [0.37, 4.1, 0.37, 4.8],  # the block's east side, free to the east
        [-1.2, 4.8, 0.37, 4.8],  # its top, free to the north
        [-1.2, 4.1, -1.2, 4.8],  # its west side, free to the west
    ])  # fmt: skip
    side = np.array([-1, -1, -1, 1, 1])
    assert np.allclose(into_corners(seg, side, CLOSED, P, NONE_FREE), seg)


def test_cabinets_in_the_two_corners_of_a_partition_s_t_are_fronts_and_the_partition_runs_on_to_the_wall():
    """Two counters 1.05 m deep against a wall, one each side of a partition 0.7 m
    thick that meets it, their fronts flush with its end: the map shows one face 8.5 m
    long at y 1.05 (longer than any object, HIDDEN_MAX_GAP_M) and the wall's room face
    in two pieces, one each side of the partition (Bormann et al.'s office_g and
    office_i with furniture). Run by run between the partition's faces, the face is the
    counters' fronts; the partition runs on to the wall."""
    from floorscan.floorplan.junctions import snap_junctions
    from floorscan.floorplan.partition_fronts import fronts_between_partitions

    seg = np.array([[-1.0, 0.0, 3.85, 0.0], [4.55, 0.0, 9.5, 0.0],  # the wall's room face, in two pieces
                    [-1.0, -0.3, 9.5, -0.3],  # its corridor face
                    [0.0, 1.05, 8.5, 1.05],  # the counters' fronts and the partition's end
                    [3.85, 1.05, 3.85, 5.0], [4.55, 1.05, 4.55, 5.0],  # the partition's faces
                    [0.0, 1.05, 0.0, 0.0], [8.5, 1.05, 8.5, 0.0]])  # the counters' outer sides  # fmt: skip
    side = np.array([1, 1, -1, 1, 1, -1, -1, 1])
    anchor = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) >= P.clutter_max_length_m
    _, junctions = snap_junctions(seg, P)
    front, behind = in_front_of_walls(seg, side, anchor, P, NONE_FREE)
    assert not front[3]  # as one face, longer than any object
    front, behind, runs, runs_behind, carried = fronts_between_partitions(seg, side, anchor, junctions, front, behind,
                                                                          P, NONE_FREE)  # fmt: skip
    assert front[3] and behind[3] in (0, 1)
    assert np.round(runs, 2).tolist() == [[0.0, 1.05, 3.85, 1.05], [4.55, 1.05, 8.5, 1.05]]
    assert np.round(runs_behind[:, 1], 2).tolist() == [0.0, 0.0]
    assert sorted((g, k) for g, k, _ in carried) == [(4, 0), (5, 0)]
    assert all(xy[1] == pytest.approx(0.0, abs=1e-9) for _, _, xy in carried)
    # a corridor between the fronts and the wall (the bodies seen free): no fronts
    front, behind = in_front_of_walls(seg, side, anchor, P, ALL_FREE)
    assert not fronts_between_partitions(seg, side, anchor, junctions, front, behind, P, ALL_FREE)[0][3]


def test_the_walls_behind_an_l_of_desks_in_a_corner_run_into_the_corner_and_the_desks_are_fronts():
    # a room's south-west corner at (0, 0), its walls 0.2 m thick, their other faces seen;
    # an L of desks in the corner: one leg against the west wall (front x = 0.7, y 0.8
    # .. 4), the other against the south wall (front y = 0.8, x 0.7 .. 2). The room shows
    # each wall's face past the desk (x 2 .. 6, y 4 .. 6) and the desks' fronts and ends,
    # and each wall face meets the other leg's front first: both run on to the corner
    south, west = [2.0, 0.0, 6.0, 0.0], [0.0, 6.0, 0.0, 4.0]
    seg = np.array([south, west, [-0.2, -0.2, 6.0, -0.2], [-0.2, 6.0, -0.2, -0.2],
                    [0.7, 0.8, 0.7, 4.0], [0.7, 4.0, 0.0, 4.0], [2.0, 0.8, 0.7, 0.8], [2.0, 0.0, 2.0, 0.8]])  # fmt: skip
    side = np.array([1, 1, -1, -1, -1, -1, -1, -1])  # free sides: into the room; out of it for the other faces
    out = into_corners(seg, side, CLOSED, P, NONE_FREE)
    assert np.allclose(out[0], [0.0, 0.0, 6.0, 0.0]) and np.allclose(out[1], [0.0, 6.0, 0.0, 0.0])
    assert np.allclose(out[[2, 3, 5, 6, 7]], seg[[2, 3, 5, 6, 7]])  # (before: out[0] from 0.7, out[1] to 0.8)
    front, behind = in_front_of_walls(out, side, np.array([True] * 4 + [False] * 4), P, NONE_FREE)
    assert front[[4, 6]].all() and behind[4] == 1 and behind[6] == 0
