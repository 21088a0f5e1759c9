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

import html
import json
import os
import re
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

_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; color: #1e293b; background: #f8fafc;
  font-size: 14px; line-height: 1.45; margin: 1.5em auto; max-width: 72rem; padding: 0 1em; }
h1 { font-size: 1.5em; margin: 0 0 0.2em; }
.counts { color: #475569; margin: 0 0 1em; }
.card { display: flex; gap: 1.2em; align-items: flex-start; background: #fff; border: 1px solid #cbd5e1;
  border-radius: 6px; padding: 0.8em 1em; margin: 0 0 0.8em; }
.thumb { flex: 0 0 auto; width: %(w)dpx; }
.thumb img { display: block; width: %(w)dpx; height: auto; max-height: 220px; object-fit: contain;
  border: 1px solid #e2e8f0; background: #fff; }
.noplan { width: %(w)dpx; height: 6em; display: flex; align-items: center; justify-content: center;
  border: 1px dashed #cbd5e1; color: #94a3b8; }
.facts { flex: 1 1 auto; min-width: 0; }
.facts h2 { font-size: 1.2em; margin: 0 0 0.3em; }
.facts p { margin: 0.3em 0; }
a { color: #1d4ed8; }
.verdict { padding: 0.3em 0.6em; border-left: 4px solid #64748b; background: #f1f5f9; }
.verdict b { margin-right: 0.3em; }
.verdict.good { border-color: #16a34a; background: #f0fdf4; }
.verdict.good b { color: #15803d; }
.verdict.warning { border-color: #d97706; background: #fffbeb; }
.verdict.warning b { color: #b45309; }
.verdict.poor { border-color: #dc2626; background: #fef2f2; }
.verdict.poor b { color: #b91c1c; }
.error { padding: 0.5em 0.7em; border: 1px solid #fca5a5; border-left: 4px solid #dc2626; background: #fef2f2;
  color: #7f1d1d; white-space: pre-wrap; overflow-wrap: anywhere; font-family: ui-monospace, monospace;
  font-size: 0.9em; }
.error b { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; color: #b91c1c; }
""" % {"w": THUMB_WIDTH}


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
    """The page :func:`write_index` writes, as text.

    Parameters
    ----------
    statuses : list of dict
        One per dataset, in page order.
    title : str

    Returns
    -------
    str
    """
    esc = html.escape
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        "<head>",
        '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{esc(title)}</title>",
        f"<style>{_STYLE}</style>",
        "</head>",
        "<body>",
        f"<h1>{esc(title)}</h1>",
        f'<p class="counts">{esc(counts_line(statuses))}</p>',
    ]
    parts += [_card(s) for s in statuses]
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)


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


def _card(s: dict) -> str:
    esc = html.escape
    name = esc(str(s["name"]))
    if s.get("front"):
        name = f'<a href="{_url(s["front"])}">{name}</a>'
    if s.get("floorplan"):
        img = f'<img src="{_url(s["floorplan"])}" width="{THUMB_WIDTH}" alt="{esc("floor plan of " + str(s["name"]))}">'
        thumb = f'<a href="{_url(s.get("front") or s["floorplan"])}">{img}</a>'
    else:
        thumb = '<div class="noplan">no floor plan</div>'
    facts = [f"<h2>{name}</h2>"]
    if s.get("failed"):
        facts.append(f'<div class="error"><b>Failed:</b> {esc(str(s["failed"]))}</div>')
    if s.get("verdict"):
        cls = f"verdict {s['verdict_class'].lower()}" if s.get("verdict_class") else "verdict"
        word = esc(s.get("verdict_class") or "Verdict")
        line = str(s["verdict"])
        head, sep, rest = line.partition(":")
        text = rest.strip() if sep and head.strip().upper() == s.get("verdict_class") else line
        facts.append(f'<p class="{esc(cls)}"><b>{word}</b>{esc(text)}</p>')
    scans = _scans_text(s)
    if scans:
        facts.append(f"<p>{esc(scans)}</p>")
    nouns = (("n_walls", "wall"), ("n_rooms", "room"), ("n_doors", "door"))
    plan = ", ".join(count_text(s[k], noun) for k, noun in nouns if s.get(k) is not None)
    if plan:
        facts.append(f"<p>{esc(plan)}</p>")
    return (f'<section class="card" id="{esc(str(s["name"]))}">\n<div class="thumb">{thumb}</div>\n'
            f'<div class="facts">\n' + "\n".join(facts) + "\n</div>\n</section>")


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
    """A relative path as an attribute value: percent-encoded, then HTML-escaped."""
    return html.escape(quote(str(rel), safe="/"), quote=True)


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
