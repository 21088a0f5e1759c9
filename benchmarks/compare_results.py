"""Compare two results folders file by file: ``python -m benchmarks.compare_results OLD NEW``.

For a change that must not change the outputs (a refactoring, a faster implementation):
run the workflow with the old tree and with the new one on the same datasets, then
compare ``results/`` of both. Every file under ``OLD/<dataset>/`` and ``NEW/<dataset>/``
is compared by its sha256, except what holds timing by design (the ``logs/`` and
``benchmarks/`` folders and the timing figures; ``tests/test_reproducible.py`` uses the
same :func:`digests`).

The files the answer and the stages exchange are the *required* ones: floor plans
(GeoJSON, SVG, DXF, IFC), orderings, walls, registered points and poses, the selection
and the scores. A difference there fails (exit status 1); a difference elsewhere (a
figure, the report's HTML) is listed and passes unless ``--strict``.

Options: ``--datasets a b ...`` (default: every dataset folder in both), ``--strict``.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

#: Folders of results/<dataset>/ that hold timing by design.
TIMING_FOLDERS = {"logs", "benchmarks"}
#: Figures that show time, measured anew by every run.
TIMING_FIGURES = {
    "figures/selection_time.png",
    "figures/stage_times.png",
    "figures/stage_times.tsv",
    "figures/wall_extraction_per_scan.png",
}
#: Suffixes and folders of the required files (relative to results/<dataset>/).
REQUIRED_SUFFIXES = {".geojson", ".svg", ".dxf", ".ifc", ".parquet", ".csv", ".json", ".pgm", ".yaml",
                     ".ply", ".pcd", ".bag", ".db3", ".mcap", ".log", ".md"}


def digests(folder: Path) -> dict[str, str]:
    """sha256 of every file under ``folder`` outside the timing folders and figures,
    by path relative to ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder)
        if p.is_dir() or TIMING_FOLDERS & set(rel.parts[:-1]) or rel.as_posix() in TIMING_FIGURES:
            continue
        if any(part.startswith(".") for part in rel.parts):  # hidden temporaries
            continue
        out[rel.as_posix()] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def required(rel: str) -> bool:
    """Is ``rel`` (a path under results/<dataset>/) one of the files that must not change?"""
    name = rel.lower()
    if name.endswith(".log.gz"):
        return True
    return Path(name).suffix in REQUIRED_SUFFIXES and not name.startswith("figures/")


def compare(old: Path, new: Path, datasets: list[str] | None = None) -> dict[str, dict]:
    """Per dataset: ``{"required": [...], "other": [...], "only_old": [...], "only_new": [...],
    "n_same": int}``, the paths (relative to the dataset's folder) that differ or exist on
    one side only, and the count of identical files."""
    if datasets is None:
        datasets = sorted(p.name for p in old.iterdir() if p.is_dir() and (new / p.name).is_dir())
    report = {}
    for ds in datasets:
        a, b = digests(old / ds), digests(new / ds)
        differ = sorted(k for k in a.keys() & b.keys() if a[k] != b[k])
        report[ds] = {
            "required": [k for k in differ if required(k)],
            "other": [k for k in differ if not required(k)],
            "only_old": sorted(a.keys() - b.keys()),
            "only_new": sorted(b.keys() - a.keys()),
            "n_same": sum(1 for k in a.keys() & b.keys() if a[k] == b[k]),
        }
    return report


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--datasets", nargs="*")
    ap.add_argument("--strict", action="store_true", help="fail on any difference, figures and report too")
    args = ap.parse_args(argv)
    report = compare(args.old, args.new, args.datasets)
    failed = False
    for ds, r in report.items():
        bad = r["required"] + r["only_old"] + r["only_new"] + (r["other"] if args.strict else [])
        failed |= bool(bad)
        print(f"{ds}: {r['n_same']} files identical, {len(r['required'])} required files differ, "
              f"{len(r['other'])} other files differ, {len(r['only_old'])} only in old, {len(r['only_new'])} only in new")
        for key in ("required", "other", "only_old", "only_new"):
            for rel in r[key]:
                print(f"  {key}: {rel}")
    if not report:
        print("no dataset folder in both", file=sys.stderr)
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
