"""Merged floor plans of the first k scans, orderings side by side over the ground truth
or reference (thesis Fig. 5.5).

:func:`plot_floorplans` draws the panels, given one geometry per wall: its footprint,
as the plan's exports draw it (of a plan folder, the evaluation grid's Parquet tables:
:func:`floorscan.floorplan.footprints.read_plan_footprints`, which the stage's script
calls), or of a floor plan's GeoJSON (footprint, or axis without one:
:func:`read_geojson_geometries`).
"""

from __future__ import annotations

import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from floorscan.figures.style import segments_collection, square_axes, reference_name, save_figure  # noqa: E402


def read_geojson_geometries(path) -> list:
    """Shapely geometries of the walls of a floor plan's GeoJSON, one per wall.

    A floor plan of :func:`floorscan.floorplan.geojson.floorplan_geojson` holds an ``axis``, a
    ``footprint`` and its ``face`` lines for each wall (property ``kind``); a wall is
    drawn as its footprint, or as its axis when it has none, so the list holds one
    geometry per wall (``len`` is the plan's wall count, one row of
    :attr:`floorscan.floorplan.plan.FloorPlan.walls` each). Features without ``kind`` (any
    other GeoJSON) are all returned.

    Parameters
    ----------
    path : path

    Returns
    -------
    list of shapely geometry
        Map metres (or the file's coordinates).
    """
    import shapely.geometry

    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    plain, axes, footprints = [], {}, {}
    for i, feat in enumerate(doc.get("features", [])):
        if not feat.get("geometry"):
            continue
        props = feat.get("properties") or {}
        kind = props.get("kind")
        if kind is None:
            plain.append(shapely.geometry.shape(feat["geometry"]))
        elif kind in ("axis", "footprint"):  # without a wall_id: a wall of its own
            by_wall = axes if kind == "axis" else footprints
            by_wall.setdefault(props.get("wall_id", ("feature", i)), shapely.geometry.shape(feat["geometry"]))
    walls = [footprints.get(w, g) for w, g in axes.items()]
    walls += [g for w, g in footprints.items() if w not in axes]
    return plain + walls


def _draw_geometry(ax, geom, colour, lw=1.2) -> None:
    gt = geom.geom_type
    if gt.startswith("Multi") or gt == "GeometryCollection":
        for g in geom.geoms:
            _draw_geometry(ax, g, colour, lw)
    elif gt == "LineString":
        x, y = geom.xy
        ax.plot(x, y, color=colour, lw=lw)
    elif gt == "Polygon":
        x, y = geom.exterior.xy
        ax.fill(x, y, facecolor=colour, edgecolor=colour, alpha=0.6, lw=0.5)
    elif gt == "Point":
        ax.plot(geom.x, geom.y, ".", color=colour)


def plot_floorplans(panels, reference, reference_kind: str, out, title: str = "") -> None:
    """Fig. 5.5: merged floor plans side by side over the ground truth (reference).

    Parameters
    ----------
    panels : list of (str, list of shapely geometries)
        Panel title and the floor plan's walls, one geometry (footprint polygon or
        axis line) per wall as :func:`read_geojson_geometries` gives them, metres; the
        title counts them.
    reference : (M, 4) array_like
        Ground-truth or reference wall segments, drawn in light grey.
    reference_kind : str
        ``"ground_truth"`` or ``"reference"``, for the legend.
    out : path
        PNG to write.
    """
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(6 * n, 5), squeeze=False)
    for ax, (name, geoms) in zip(axes[0], panels):
        ax.add_collection(
            segments_collection(reference, colors="0.75", linewidths=3,
                                 label=reference_name(reference_kind))
        )
        for g in geoms:
            _draw_geometry(ax, g, "black")
        ax.plot([], [], color="black", label="floor plan walls")
        ax.set_title(f"{name} ({len(geoms)} walls)", fontsize=10)
        ax.autoscale()
        square_axes(ax)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, out)
