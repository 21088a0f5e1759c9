"""What a finished run prints: where the answer of each dataset is
(:func:`answer_lines`, called at the end of a run by
:func:`floorscan.figures.run_end.finish_run`), and ``summary.md``, the same answer in
Markdown."""

from __future__ import annotations

import json
import os
from pathlib import Path


def answer_lines(
    datasets, results: str | os.PathLike = "results", failed: dict | None = None, report: str = ""
) -> list[str]:
    """What a finished run prints: the answer of each of its datasets.

    One dataset: at most 10 lines: k of the kept and recorded scans, the verdict, and
    where the floor plan, the occupancy map (``map.pgm``, ``map.yaml``), the scan list,
    the reduced recording, the points, ``summary.md`` and the front page are. Several:
    one line each and the index page (``results/index.html``). An occupancy map's
    answer is its plan and the map as read
    (:func:`map_answer_lines`). A dataset in
    ``failed`` gets its error instead of an answer, even when an older answer is on
    disk; a dataset whose selection was not made yet gets one line saying so.

    Parameters
    ----------
    datasets : list of str
    results : path
        The results folder.
    failed : dict, optional
        ``{dataset: error paragraph}`` of the datasets whose run failed.
    report : str
        The command that makes the report of these datasets (``floorscan report``, or
        the run's own ``snakemake ... --report``), named when one of them has an
        answer; empty: no report is named (an older ``results/report.html`` may not
        hold them).

    Returns
    -------
    list of str
    """
    from floorscan.figures.index_page import registration_verdict, verdict_class
    from floorscan.core.selection import read_selection

    failed = dict(failed or {})
    root = Path(results)
    lines = []
    many = len(datasets) > 1
    answered = 0  # datasets with an answer: a report of them can be made
    for ds in datasets:
        if ds in failed:
            lines.append(f"{ds}: FAILED: {failed[ds]}")
            continue
        map_lines = map_answer_lines(ds, root, many)  # an occupancy map: its plan, no scans
        if map_lines:
            lines += map_lines
            answered += 1
            continue
        summary_path = root / ds / "selection" / "selection.json"
        if not summary_path.is_file():
            lines.append(f"{ds}: not finished: no answer yet ({summary_path} is not made: the run stopped before it, "
                         "or its targets do not include the plan); run it again to go on")
            continue
        s = read_selection(summary_path)
        answered += 1
        v = registration_verdict(root / ds)
        head = f"{ds}: {s['k']} of {s['n_kept']} kept scans ({s['n_recorded']} recorded), {s['ordering']}"
        front = root / ds / "front.html"
        if many:
            lines.append(f"{head}; {verdict_class(v) or 'no verdict'}" + (f"; {front}" if front.is_file() else ""))
            continue
        verdict = v.get("line") or "no verdict"
        rec = s["recording"]
        lines += [head, f"  verdict:            {verdict}"]
        plan = root / ds / "floorplan.svg"
        if plan.is_file():
            lines.append(f"  floor plan:         {root / ds}/floorplan.{{geojson,svg,dxf,ifc}}{plan_counts(root / ds / 'floorplan.geojson')}")
        if (root / ds / "map.pgm").is_file():
            lines.append(f"  occupancy map:      {root / ds}/map.pgm, map.yaml (ROS map_server, Nav2)")
        # selection.json's paths are from the workflow's folder, the results folder's parent
        at = root.parent.joinpath
        lines.append(f"  scan list:          {at(s['scans'])}")
        lines.append(
            f"  reduced recording:  {at(rec['path'])} ({format_bytes(rec['bytes_out'])} of {format_bytes(rec['bytes_in'])}, "
            f"{rec['scan_messages_out']} scans)"
        )
        lines.append(f"  points (PLY, PCD):  {at(s['points'][0])}, {at(s['points'][1])}")
        summary = root / ds / "summary.md"
        if summary.is_file():
            lines.append(f"  {'summary:':<20}{summary}" + evaluation_note(root / ds))
        if front.is_file():
            lines.append(f"  {'front page:':<20}{front}")
    if many and (root / "index.html").is_file():
        lines.append(f"index: {root / 'index.html'}")
    if answered and report:
        lines.append(f"report: {report}")
    return lines


def evaluation_note(folder: str | os.PathLike) -> str:
    """`` (with the evaluation: every plan and score in <folder>/evaluation/)`` when the
    dataset's ``summary.md`` holds its evaluation (``evaluation/summary.md`` of the
    score stage, which it ends with), else empty: what ``--evaluate`` adds, said in the
    answer.

    Parameters
    ----------
    folder : path
        ``results/<dataset>``.

    Returns
    -------
    str
    """
    folder = Path(folder)
    try:
        part = (folder / "evaluation" / "summary.md").read_text(encoding="utf-8")
        evaluated = bool(part.strip()) and (folder / "summary.md").read_text(encoding="utf-8").endswith(part)
    except OSError:
        return ""
    return f" (with the evaluation: every plan and score in {folder}/evaluation/)" if evaluated else ""


#: What the answer of a recording has and a map's has not.
NOT_FROM_A_MAP = (
    "a map holds no scans: no registration or verdict, no scan selection, scan list, reduced recording "
    "or points, no evaluation against the scans"
)


def map_answer_lines(dataset: str, root: str | os.PathLike, many: bool = False) -> list[str]:
    """The answer of a map dataset as the run prints it (one line when the run has
    several datasets).

    Parameters
    ----------
    dataset : str
    root : path
        The results folder.
    many : bool
        One line (a run of several datasets).

    Returns
    -------
    list of str
        Empty when ``<root>/<dataset>/map/map.json`` is not made yet.
    """
    from floorscan.core.map_info import map_line, read_map_info

    folder = Path(root) / dataset
    info_path = folder / "map" / "map.json"
    if not info_path.is_file():
        return []
    info = read_map_info(info_path)
    front = folder / "front.html"
    counts = plan_counts(folder / "floorplan.geojson")
    head = f"{dataset}: floor plan of an occupancy map, {info['width']} x {info['height']} cells of {info['resolution_m']:g} m"
    if many:
        return [f"{head}{counts}" + (f"; {front}" if front.is_file() else "")]
    lines = [head, f"  read:               {map_line(info)}"]
    if (folder / "floorplan.svg").is_file():
        lines.append(f"  floor plan:         {folder}/floorplan.{{geojson,svg,dxf,ifc}}{counts}")
    if (folder / "map.pgm").is_file():
        lines.append(f"  occupancy map:      {folder}/map.pgm, map.yaml (the map as read: occupied, free, unknown)")
    lines.append(f"  not from a map:     {NOT_FROM_A_MAP}")
    for label, path in (("summary:", folder / "summary.md"), ("front page:", front)):
        if path.is_file():
            lines.append(f"  {label:<20}{path}")
    return lines


def plan_counts(geojson: str | os.PathLike) -> str:
    """`` (172 walls, 109 junctions, 105 clutter pieces)`` from a plan's GeoJSON
    metadata (``floorscan`` member), with ``, 12 rooms, 11 doors`` when the plan has
    rooms (``n_rooms``, ``n_doors``).

    Parameters
    ----------
    geojson : path

    Returns
    -------
    str
        Empty when the file cannot be read or names no count.
    """
    from floorscan.core.messages import count_text

    try:
        meta = json.loads(Path(geojson).read_text()).get("floorscan") or {}
    except (OSError, ValueError):
        return ""
    parts = [f"{meta['n_walls']} walls"] if "n_walls" in meta else []
    parts += [count_text(meta[k], noun) for k, noun in (("n_junctions", "junction"), ("n_clutter", "clutter piece")) if k in meta]
    parts += [count_text(meta[k], noun) for k, noun in (("n_rooms", "room"), ("n_doors", "door")) if k in meta]
    return f" ({', '.join(parts)})" if parts else ""


def format_bytes(n: int) -> str:
    """``n`` bytes for people, SI units: ``812 B``, ``12.3 kB``, ``4.56 MB``, ``120 MB``.

    Parameters
    ----------
    n : int

    Returns
    -------
    str
    """
    n = int(n)
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            v = n / size
            return f"{v:.3g} {unit}" if v < 100 else f"{v:.0f} {unit}"
    return f"{n} B"


def summary_header(dataset: str, verdict=None, recording=None, mode: str = "") -> list[str]:
    """The lines that head ``summary.md``: the title, the registration's verdict and
    what the recording was found to be.

    Parameters
    ----------
    dataset : str
    verdict : dict, optional
        :meth:`floorscan.register.consistency.Verdict.as_dict`.
    recording : mapping, optional
        Ingest's detection, the scan index's metadata
        (:func:`floorscan.core.io.describe_recording`).
    mode : str
        The register mode used.

    Returns
    -------
    list of str
    """
    from floorscan.core.io import describe_recording

    lines = [f"# Scan reduction summary: {dataset}" if dataset else "# Scan reduction summary", ""]
    if verdict:
        lines += [f"**Verdict: {verdict['line']}**", ""]
    if recording or mode:
        lines += [f"Recording: {describe_recording(recording or {}, mode)}.", ""]
    return lines


def write_summary_markdown(
    path: str | os.PathLike,
    dataset: str,
    selection: str | os.PathLike,
    registration: str | os.PathLike,
    index: str | os.PathLike,
    evaluation: str | os.PathLike | None = None,
) -> str:
    """Write ``summary.md``, the answer in Markdown: the registration's verdict, what
    ingest detected (:func:`summary_header`), k and why, where
    the answer's files are; then the evaluation's part (``evaluation/summary.md`` of
    the score stage) when the dataset was evaluated.

    Parameters
    ----------
    path : path
        ``results/<dataset>/summary.md``.
    dataset : str
    selection, registration, index : path
        ``selection/selection.json``, ``registration.parquet`` (verdict and mode in its
        metadata), ``scan_index.parquet`` (what ingest detected, in its metadata).
    evaluation : path, optional
        ``evaluation/summary.md``.

    Returns
    -------
    str
        The Markdown written.
    """
    from floorscan.core.files import atomic_path
    from floorscan.core.io import read_metadata
    from floorscan.core.selection import read_selection

    s = read_selection(selection)
    reg = read_metadata(registration)
    verdict = json.loads(reg["verdict"]) if "verdict" in reg else None
    root = Path(path).parent
    rec = s["recording"]
    lines = summary_header(dataset, verdict, read_metadata(index), reg.get("mode", ""))
    lines += [
        "## The answer", "",
        f"{s['reason']} (ordering {s['ordering']}; {s['n_recorded']} scans recorded).", "",
        f"- floor plan: `{root}/floorplan.{{geojson,svg,dxf,ifc}}`{plan_counts(root / 'floorplan.geojson')}",
        f"- occupancy map of the selected scans: `{root}/map.pgm`, `map.yaml` (ROS map_server, Nav2)",
        f"- scan list: `{s['scans']}`",
        f"- reduced recording: `{rec['path']}` ({format_bytes(rec['bytes_out'])} of "
        f"{format_bytes(rec['bytes_in'])}, {rec['scan_messages_out']} scans)",
        f"- points of the selected scans: `{s['points'][0]}`, `{s['points'][1]}`",
        f"- front page: `{root}/front.html`", "",
    ]  # fmt: skip
    text = "\n".join(lines)
    if evaluation is not None:
        text += "\n" + Path(evaluation).read_text(encoding="utf-8")
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return text
