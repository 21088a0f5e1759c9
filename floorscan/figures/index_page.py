"""The index of a run over several recordings: one static page, ``results/index.html``,
with a card per dataset (its verdict, scans, plan counts and a thumbnail of its floor
plan, or the error of a run that failed).

- :func:`dataset_status`: what the index shows of one dataset, read from its results;
- :func:`failure_text`: the error paragraph of a dataset whose run failed, from its logs
  (written by :func:`floorscan.core.stage.stage_log`);
- :func:`write_index`: the page.

The page has no JavaScript and no external assets; its links and images are relative
to the results folder, so the folder can be moved or copied whole. The same statuses
give the same bytes.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

from floorscan.core.files import atomic_path
from floorscan.core.messages import count_text

#: Verdict classes, as :meth:`floorscan.register.consistency.Verdict.line` begins.
VERDICT_CLASSES = ("GOOD", "WARNING", "POOR")

#: Width of a floor plan's thumbnail, CSS pixels.
THUMB_WIDTH = 280

#: A record of a stage log (:data:`floorscan.core.stage.LOG_FORMAT`): time, level, logger, message.
_RECORD = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} (?P<level>[A-Z]+) (?P<name>\S+): (?P<message>.*)$")

_TRACEBACK = "Traceback (most recent call last):"

def dataset_status(dataset: str, results: str | os.PathLike = "results") -> dict:
    """What the index shows of one dataset, read from ``<results>/<dataset>/``.

    Reads ``selection/selection.json`` (k and the scan counts), the ``verdict`` of
    ``registration.parquet``'s schema metadata (else the ``verdict:`` line of
    ``logs/register.log``, which a register stage that failed on a poor verdict leaves),
    the ``floorscan`` member of ``floorplan.geojson`` (the plan's counts) and whether
    ``floorplan.svg`` and ``front.html`` exist. A file that is missing or cannot be
    read leaves its values None.

    Parameters
    ----------
    dataset : str
        The dataset's name, the folder under ``results``.
    results : path
        The results folder.

    Returns
    -------
    dict
        ``name``; ``verdict_class`` (one of :data:`VERDICT_CLASSES`) and ``verdict`` (its
        line); ``k``, ``n_kept``, ``n_recorded`` (scans selected, kept by registration,
        recorded); ``n_walls``, ``n_rooms``, ``n_doors``; ``floorplan`` and ``front``,
        the paths of ``floorplan.svg`` and ``front.html`` relative to ``results``
        (POSIX separators); ``failed``: None, or the error paragraph
        (:func:`failure_text`, or why there is no plan) when the dataset has no floor
        plan or a stage logged an error after its plan was written.
    """
    root = Path(results)
    folder = root / dataset
    sel = _read_json(folder / "selection" / "selection.json")
    meta = _read_json(folder / "floorplan.geojson").get("floorscan") or {}
    verdict = registration_verdict(folder)
    plan, front = folder / "floorplan.svg", folder / "front.html"
    return {
        "name": dataset,
        "verdict_class": verdict_class(verdict) if verdict else None,
        "verdict": (str(verdict.get("line", "")) or None) if verdict else None,
        "k": _int(sel.get("k")),
        "n_kept": _int(sel.get("n_kept")),
        "n_recorded": _int(sel.get("n_recorded")),
        "n_walls": _int(meta.get("n_walls")),
        "n_rooms": _int(meta.get("n_rooms")),
        "n_doors": _int(meta.get("n_doors")),
        "floorplan": plan.relative_to(root).as_posix() if plan.is_file() else None,
        "front": front.relative_to(root).as_posix() if front.is_file() else None,
        "failed": _failure(dataset, root, plan),
    }


def verdict_class(verdict: dict) -> str | None:
    """``GOOD``, ``WARNING`` or ``POOR`` of a verdict: from ``ok`` and ``warnings`` when
    it has them, else the first word of its ``line``.

    Parameters
    ----------
    verdict : dict
        :meth:`floorscan.register.consistency.Verdict.as_dict`.

    Returns
    -------
    str or None
        None when neither tells.
    """
    if "ok" in verdict:
        if not verdict["ok"]:
            return "POOR"
        return "WARNING" if verdict.get("warnings") else "GOOD"
    word = str(verdict.get("line", "")).split(":", 1)[0].strip().upper()
    return word if word in VERDICT_CLASSES else None


def failure_text(dataset: str, results: str | os.PathLike = "results") -> str | None:
    """The error paragraph of a dataset whose run failed, from ``<results>/<dataset>/logs/*.log``.

    The newest log (by modification time, then name) holding an error is read: its
    last ``ERROR`` or ``CRITICAL`` record with the lines that continue it (the
    paragraph of :func:`floorscan.core.stage.failure_message`); a record followed by a
    traceback (a bug) gives its first line and the traceback's last (the exception).
    A log holding only a bare traceback gives that last line.

    Parameters
    ----------
    dataset : str
    results : path
        The results folder.

    Returns
    -------
    str or None
        The paragraph; ``"failed at <stage>; see <log>"`` (the newest log's stage and
        path) when no log holds an error; None when the dataset has no log.
    """
    logs = [p for _, p in _logs(Path(results) / dataset / "logs")]
    if not logs:
        return None
    for log in reversed(logs):
        text = log_error(log)
        if text:
            return text
    newest = logs[-1]
    return f"failed at {newest.stem}; see {newest}"


def log_error(path: str | os.PathLike) -> str | None:
    """The last error paragraph of one stage log (as :func:`failure_text` reads it).

    Parameters
    ----------
    path : path

    Returns
    -------
    str or None
        None when the log holds none or cannot be read.
    """
    try:
        lines = Path(path).read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return None
    records: list[tuple[str, list[str]]] = []  # (level, lines of the message)
    for line in lines:
        m = _RECORD.match(line)
        if m:
            records.append((m["level"], [m["message"]]))
        elif records:
            records[-1][1].append(line)
        else:
            records.append(("", [line]))
    for level, body in reversed(records):
        if level in ("ERROR", "CRITICAL") or (not level and _TRACEBACK in body):
            return _paragraph(body)
    return None


def write_index(statuses: list[dict], path: str | os.PathLike = "results/index.html",
                title: str = "floorscan results") -> None:
    """Write the index page of a run: a line of counts, then one card per status
    (:func:`dataset_status`), in the order given.

    A card shows the dataset's name and a thumbnail of its floor plan (both linked to
    its front page when it has one; the thumbnail else to the plan itself), its
    verdict coloured by class, ``"<k> of <kept> kept of <recorded> recorded scans"``
    and the plan's walls, rooms and doors; a failed dataset shows its error paragraph
    in a red block. The paths of the statuses are written as they are, relative to the
    page's folder: write the page into the results folder. Written atomically; no
    clock, so the same statuses give the same bytes.

    Parameters
    ----------
    statuses : list of dict
        As :func:`dataset_status` returns; keys other than ``name`` may be missing.
    path : path
        The page, ``results/index.html``.
    title : str
        The page's title and heading.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(index_html(statuses, title), encoding="utf-8")


def index_html(statuses: list[dict], title: str = "floorscan results") -> str:
    """The page :func:`write_index` writes, as text: the template
    ``templates/index_page.html.j2`` given one :class:`IndexPage`.

    Parameters
    ----------
    statuses : list of dict
        One per dataset, in page order.
    title : str

    Returns
    -------
    str
    """
    from floorscan.figures.pages import render

    return render("index_page.html.j2", IndexPage(tuple(statuses), title))


@dataclass(frozen=True)
class IndexCard:
    """One dataset's card on the index, as the template shows it.

    Attributes
    ----------
    name : str
    front, plan : str or None
        ``front.html`` and ``floorplan.svg`` relative to the results folder,
        percent-encoded for an attribute (the template escapes them for HTML).
    failed : str or None
        The error paragraph of a dataset whose run failed.
    verdict : str or None
        The verdict's line without its leading class word.
    verdict_word, verdict_css : str
        ``GOOD`` / ``WARNING`` / ``POOR`` (``Verdict`` when unknown), and the
        paragraph's CSS classes (``verdict good``).
    scans : str
        ``"10 of 76 kept of 321 recorded scans"``, or empty.
    plan_counts : str
        ``"14 walls, 5 rooms, 1 door"``, or empty.
    """

    name: str
    front: str | None
    plan: str | None
    failed: str | None
    verdict: str | None
    verdict_word: str
    verdict_css: str
    scans: str
    plan_counts: str

    @classmethod
    def of(cls, s: dict) -> "IndexCard":
        """The card of a status (:func:`dataset_status`; keys but ``name`` may be missing)."""
        verdict, word, css = None, s.get("verdict_class") or "Verdict", "verdict"
        if s.get("verdict"):
            line = str(s["verdict"])
            head, sep, rest = line.partition(":")
            verdict = rest.strip() if sep and head.strip().upper() == s.get("verdict_class") else line
            css = f"verdict {s['verdict_class'].lower()}" if s.get("verdict_class") else "verdict"
        nouns = (("n_walls", "wall"), ("n_rooms", "room"), ("n_doors", "door"))
        return cls(
            name=str(s["name"]),
            front=_url(s["front"]) if s.get("front") else None,
            plan=_url(s["floorplan"]) if s.get("floorplan") else None,
            failed=str(s["failed"]) if s.get("failed") else None,
            verdict=verdict,
            verdict_word=word,
            verdict_css=css,
            scans=_scans_text(s),
            plan_counts=", ".join(count_text(s[k], noun) for k, noun in nouns if s.get(k) is not None),
        )


@dataclass(frozen=True)
class IndexPage:
    """What the index shows: given to its template as one object (:func:`index_html`).

    Attributes
    ----------
    statuses : tuple of dict
        :func:`dataset_status` of each dataset, in page order.
    title : str
        The page's title and heading.
    thumb_width : int
        Width of a plan's thumbnail, CSS pixels.
    """

    statuses: tuple
    title: str = "floorscan results"
    thumb_width: int = THUMB_WIDTH

    @property
    def counts(self) -> str:
        return counts_line(list(self.statuses))

    @property
    def cards(self) -> list[IndexCard]:
        return [IndexCard.of(s) for s in self.statuses]


def counts_line(statuses: list[dict]) -> str:
    """``"3 recordings: 2 with a plan, 1 failed"``: a dataset has a plan when it has a
    ``floorplan`` and did not fail.

    Parameters
    ----------
    statuses : list of dict

    Returns
    -------
    str
    """
    failed = sum(1 for s in statuses if s.get("failed"))
    planned = sum(1 for s in statuses if s.get("floorplan") and not s.get("failed"))
    return f"{count_text(len(statuses), 'recording')}: {planned} with a plan, {failed} failed"


# ------------------------------------------------------------------------ parts


def _scans_text(s: dict) -> str:
    """``"10 of 76 kept of 321 recorded scans"``, with what is known of it."""
    k, kept, recorded = s.get("k"), s.get("n_kept"), s.get("n_recorded")
    if k is None:
        return ""
    text = f"{k}"
    if kept is not None:
        text += f" of {kept} kept"
    if recorded is not None:
        text += f" of {recorded} recorded"
    return text + " scans"


def _url(rel: str) -> str:
    """A relative path as an attribute value, percent-encoded (the template escapes it
    for HTML)."""
    return quote(str(rel), safe="/")


def _paragraph(body: list[str]) -> str:
    """A record's lines as one paragraph; a traceback cut to its first and last lines."""
    lines = [line.rstrip() for line in body]
    if _TRACEBACK in lines:
        i = lines.index(_TRACEBACK)
        head = " ".join(x.strip() for x in lines[:i] if x.strip())
        tail = [x.strip() for x in lines[i + 1:] if x.strip()]
        exc = tail[-1] if tail else ""
        return ": ".join(x for x in (head, exc) if x)
    return "\n".join(lines).strip()


def _logs(folder: Path) -> list[tuple[int, Path]]:
    """The ``*.log`` files of ``folder`` with their modification times (ns), oldest
    first (time, then name)."""
    if not folder.is_dir():
        return []
    found = []
    for p in folder.glob("*.log"):
        try:
            found.append((p.stat().st_mtime_ns, p))
        except OSError:
            continue
    return sorted(found, key=lambda tp: (tp[0], tp[1].name))


def _failure(dataset: str, root: Path, plan: Path) -> str | None:
    """:func:`dataset_status`'s ``failed``: the error when the dataset has no plan, or
    when a log holding an error is newer than the plan."""
    folder = root / dataset
    if plan.is_file():
        t_plan = plan.stat().st_mtime_ns
        newer = [p for t, p in _logs(folder / "logs") if t > t_plan]
        errors = [e for e in (log_error(p) for p in reversed(newer)) if e]
        return errors[0] if errors else None
    return failure_text(dataset, root) or f"no floor plan and no log in {folder}"


def registration_verdict(folder: Path) -> dict:
    """A dataset's registration verdict.

    Parameters
    ----------
    folder : Path
        ``results/<dataset>``.

    Returns
    -------
    dict
        The verdict of ``registration.parquet``'s metadata (``line``, ``ok``,
        ``warnings``, ...); else the ``verdict:`` line of ``logs/register.log`` as
        ``{"line": ...}`` (a register stage that stopped on a poor verdict leaves it);
        else ``{}``.
    """
    import pyarrow as pa

    from floorscan.core.io import read_metadata

    try:
        meta = read_metadata(folder / "registration.parquet")
        if "verdict" in meta:
            v = json.loads(meta["verdict"])
            if isinstance(v, dict):
                return v
    except (OSError, ValueError, pa.ArrowException):
        pass
    try:
        lines = (folder / "logs" / "register.log").read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return {}
    for line in reversed(lines):
        m = _RECORD.match(line)
        if m and m["message"].startswith("verdict: "):
            return {"line": m["message"][len("verdict: "):]}
    return {}


def _read_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _int(value) -> int | None:
    try:
        return int(value)
    except (TypeError, ValueError):
        return None
