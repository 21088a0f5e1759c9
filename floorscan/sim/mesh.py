"""The building as a closed triangle mesh, its horizontal sections and its STL file.

The walls' plan outline (:mod:`floorscan.sim.footprint`) is extruded from the floor to
the ceiling with trimesh, each opening's prism is subtracted, and every solid (walls,
furniture, a table's top and legs, the floor and ceiling slabs) is united with
manifold3d in float64, so the mesh is watertight and a horizontal section gives clean
polygons (thesis 5.2: a slice of the model is the floor plan). The scanner's rays hit
this mesh (:mod:`floorscan.sim.raycast`); :func:`write_stl` stores it as binary STL.
"""

from __future__ import annotations

import os
from functools import reduce

import numpy as np
import trimesh
from shapely.geometry import MultiLineString, Polygon
from shapely.ops import polygonize, unary_union

from floorscan.core.files import atomic_path
from floorscan.sim.building import TABLE_TOP_M, Building, Furniture
from floorscan.sim.footprint import CUT_MARGIN_M, building_outline, opening_polygon, walls_union

#: Thickness of the floor and ceiling slabs, metres.
SLAB_THICKNESS_M = 0.05


def _extrude(poly, z0: float, z1: float) -> list[trimesh.Trimesh]:
    parts = getattr(poly, "geoms", [poly])
    out = []
    for p in parts:
        if p.is_empty or p.area <= 0:
            continue
        m = trimesh.creation.extrude_polygon(p, z1 - z0)
        m.apply_translation([0.0, 0.0, z0])
        out.append(m)
    return out


def _furniture_meshes(f: Furniture) -> list[trimesh.Trimesh]:
    z0, z1 = f.z_min_m, f.z_min_m + f.size[2]
    if f.legs_m <= 0:
        return _extrude(f.footprint(), z0, z1)
    top = _extrude(f.footprint(), z1 - TABLE_TOP_M, z1)
    # legs reach 1 mm into the top so the union is one solid
    return top + [m for leg in f.legs() for m in _extrude(leg, z0, z1 - TABLE_TOP_M + 1e-3)]


def wall_mesh(building: Building) -> trimesh.Trimesh:
    """The walls as one closed triangle mesh: footprints extruded, openings cut out.

    Uses manifold3d booleans (via trimesh) to subtract each opening's prism (its 2D
    cutter from :func:`opening_polygon`, from ``sill_m`` to ``head_m``; doors start
    below the floor) from the extruded wall footprints.

    Parameters
    ----------
    building : Building

    Returns
    -------
    trimesh.Trimesh
        Watertight, metres, z up, floor at z = 0.
    """
    solid = _extrude(walls_union(building), 0.0, building.height_m)
    cutters = []
    for w in building.walls:
        for op in w.openings:
            z0 = -CUT_MARGIN_M if op.sill_m <= 0 else op.sill_m
            z1 = op.head_m + (CUT_MARGIN_M if op.head_m >= building.height_m else 0.0)
            cutters += _extrude(opening_polygon(w, op), z0, z1)
    return _boolean(solid, "add") if not cutters else _boolean(
        [_boolean(solid, "add"), *cutters], "subtract"
    )


def _boolean(meshes: list[trimesh.Trimesh], op: str) -> trimesh.Trimesh:
    """Union ("add") or difference ("subtract": head minus the rest) with manifold3d,
    in float64 (trimesh's manifold engine rounds vertices to float32)."""
    if len(meshes) == 1:
        return meshes[0]
    from manifold3d import Manifold, Mesh64, OpType

    ms = [
        Manifold(
            mesh=Mesh64(
                vert_properties=np.array(m.vertices, dtype=np.float64, order="C"),
                tri_verts=np.array(m.faces, dtype=np.uint64, order="C"),
            )
        )
        for m in meshes
    ]
    out = Manifold.batch_boolean(ms, OpType.Add if op == "add" else OpType.Subtract).to_mesh64()
    return trimesh.Trimesh(
        vertices=np.asarray(out.vert_properties)[:, :3],
        faces=np.asarray(out.tri_verts, dtype=np.int64),
        process=False,
    )


def building_mesh(building: Building) -> trimesh.Trimesh:
    """The whole building: walls with openings, furniture, floor and ceiling slabs.

    The floor slab spans z in [-SLAB_THICKNESS_M, 0] and the ceiling slab
    [height_m, height_m + SLAB_THICKNESS_M] under and over :func:`building_outline`.
    All solids are united with manifold3d, so a horizontal section gives clean
    polygons (thesis 5.2: a slice of the model is the floor plan).

    Parameters
    ----------
    building : Building

    Returns
    -------
    trimesh.Trimesh
        Watertight triangle mesh, metres.
    """
    parts = [wall_mesh(building)]
    parts += [m for f in building.furniture for m in _furniture_meshes(f)]
    outline = building_outline(building)
    if building.floor:
        parts += _extrude(outline, -SLAB_THICKNESS_M, 0.0)
    if building.ceiling:
        parts += _extrude(outline, building.height_m, building.height_m + SLAB_THICKNESS_M)
    return _boolean(parts, "add")


def mesh_section(mesh: trimesh.Trimesh, z: float):
    """A horizontal section of a closed mesh at height ``z`` as 2D polygons.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        A closed mesh, metres.
    z : float
        Height of the cutting plane, metres.

    Returns
    -------
    shapely Polygon or MultiPolygon
        The region inside the mesh at ``z`` (even-odd rule over the section's loops).
    """
    segs = trimesh.intersections.mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z])
    if len(segs) == 0:
        return Polygon()
    segs = np.round(segs[:, :, :2], 9)
    # node the segments first: a section can have T-junctions where triangles meet
    lines = unary_union(MultiLineString(list(segs)))
    loops = [Polygon(p.exterior) for p in polygonize(lines)]
    if not loops:
        return Polygon()
    return reduce(lambda a, b: a.symmetric_difference(b), loops)


def write_stl(mesh, path: str | os.PathLike) -> None:
    """Binary STL of ``mesh``, written atomically (no time stamp in the header).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Metres.
    path : path
    """
    data = trimesh.exchange.stl.export_stl(mesh)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
