"""What a finished run prints: where the answer of each dataset is (the Snakefile's
``onsuccess``)."""

from __future__ import annotations

import json
import os
from pathlib import Path


def answer_lines(datasets, results: str | os.PathLike = "results") -> list[str]:
    """What a finished run prints: per dataset, where the floor plan, the scan list,
    the reduced recording and the report are, and k with its size reduction. Datasets
    whose selection was not made are skipped."""
    lines = []
    root = Path(results)
    for ds in datasets:
        summary_path = root / ds / "selection" / "selection.json"
        if not summary_path.is_file():
            continue
        s = json.loads(summary_path.read_text())
        rec = s["recording"]
        lines.append(f"{ds}: {s['k']} of {s['n_kept']} kept scans ({s['n_recorded']} recorded), {s['ordering']}")
        plan = root / ds / "floorplan.svg"
        if plan.is_file():
            lines.append(f"  floor plan:         {root / ds}/floorplan.{{geojson,svg,dxf,ifc}}{plan_counts(root / ds / 'floorplan.geojson')}")
        if (root / ds / "map.yaml").is_file():
            lines.append(f"  occupancy map:      {root / ds}/map.yaml (ROS map_server, Nav2)")
        lines.append(f"  scan list:          {s['scans']}")
        lines.append(
            f"  reduced recording:  {rec['path']} ({format_bytes(rec['bytes_out'])} of {format_bytes(rec['bytes_in'])}, "
            f"{rec['scan_messages_out']} scans)"
        )
        lines.append(f"  points (PLY, PCD):  {s['points'][0]}, {s['points'][1]}")
        front = root / ds / "front.html"
        if front.is_file():
            lines.append(f"  front page:         {front}")
    report = root / "report.html"
    if lines and report.is_file():
        lines.append(f"report: {report}")
    return lines


def plan_counts(geojson: str | os.PathLike) -> str:
    """`` (172 walls, 109 junctions, 105 clutter pieces)`` from a plan's GeoJSON
    metadata (``floorscan`` member), with ``, 12 rooms, 11 doors`` when the plan has
    rooms (``n_rooms``, ``n_doors``); empty when it cannot be read."""
    from floorscan.floorplan.metadata import count_text

    try:
        meta = json.loads(Path(geojson).read_text()).get("floorscan") or {}
    except (OSError, ValueError):
        return ""
    parts = [f"{meta['n_walls']} walls"] if "n_walls" in meta else []
    parts += [f"{meta[k]} {label}" for k, label in (("n_junctions", "junctions"), ("n_clutter", "clutter pieces")) if k in meta]
    parts += [count_text(meta[k], noun) for k, noun in (("n_rooms", "room"), ("n_doors", "door")) if k in meta]
    return f" ({', '.join(parts)})" if parts else ""


def format_bytes(n: int) -> str:
    """``n`` bytes for people, SI units: ``812 B``, ``12.3 kB``, ``4.56 MB``, ``120 MB``."""
    n = int(n)
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            v = n / size
            return f"{v:.3g} {unit}" if v < 100 else f"{v:.0f} {unit}"
    return f"{n} B"
