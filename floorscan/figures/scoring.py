"""Figures of the scoring stage: the thesis's Chapter 5 figures for every dataset.

- :func:`plot_metrics_vs_k`: correct match, false positive, false negative (section 5.1)
  and F1 against the number of scans, per ordering (Fig. 5.4);
- :func:`plot_floorplans`: merged floor plans of the first k scans, orderings side by
  side (Fig. 5.5);
- :func:`plot_bitmap_overlay`: inferred (red) over ground-truth (blue) bitmaps, both in
  purple (Fig. 5.1);
- :func:`plot_walls_over_points`: wall segments over the registered points
  (Figs. 5.11, 5.12);
- :func:`plot_reference_map`: the occupancy-grid reference map of a recording;
- :func:`plot_quality_vs_k`: plan F1 against k for every ordering, random's seeds and the oracle;
- :func:`stage_times` / :func:`plot_stage_times`: time and memory per stage from the
  Snakemake benchmark files (Table 5.1);
- :func:`plot_wall_extraction`: time per scan and cumulative walls per scan of each
  extractor (Fig. 5.10).

Matplotlib with the Agg backend; every figure is written atomically
(:func:`floorscan.core.io.atomic_path`). On real recordings the walls scored against are a
*reference* (walls from all kept scans), never called ground truth.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from floorscan.score import metrics as M  # noqa: E402
from floorscan.core.io import atomic_path  # noqa: E402

DPI = 110
ORDERING_COLOURS = {
    "cluster_hull": "tab:red",
    "convex_hull": "tab:orange",
    "random": "tab:green",
    "sequential": "tab:blue",
    "motion_filter": "tab:purple",
    "wall_coverage": "tab:brown",
    "surface_coverage": "tab:pink",
}
EXTRACTOR_COLOURS = {"ransac": "tab:blue", "cluster_ransac": "tab:red"}
#: Stage names recognised in benchmark file names (first token otherwise).
STAGES = (
    "ingest", "poses", "simulate", "register", "hulls", "select", "walls",
    "floorplan", "score",
)  # fmt: skip


def reference_name(reference_kind: str) -> str:
    """``"ground truth"`` or ``"reference (all scans)"`` for titles and legends."""
    return "ground truth" if reference_kind == M.GROUND_TRUTH else "reference (all scans)"


def _save(fig, path, dpi=DPI) -> None:
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)


def _segments_collection(segments, **kw) -> LineCollection:
    seg = M.as_segments(segments)
    return LineCollection(seg.reshape(-1, 2, 2), **kw)


def _square(ax) -> None:
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


# ----------------------------------------------------------------------- Fig. 5.4


def plot_metrics_vs_k(metrics: pd.DataFrame, out, tau: float = 0.05) -> None:
    """Fig. 5.4: metrics against the number of scans, a line per ordering.

    Columns: the thesis's correct match, false positive and false negative (fractions
    of the map area), the wall-cell correct match (IoU of wall cells) and F1 at ``tau``;
    a row per extractor. Correct match over the map area stays near 1 because empty
    cells dominate it, hence the wall-cell version beside it.

    Parameters
    ----------
    metrics : pandas.DataFrame
        ``metrics.parquet`` (:func:`floorscan.score.metrics.score_dataset`).
    out : path
        PNG to write.
    tau : float
        Tolerance of the F1 column, metres.
    """
    f1 = f"f1_{M.tau_label(tau)}"
    cols = [
        ("correct_match", "correct match\n(fraction of map)"),
        ("false_positive", "false positive\n(fraction of map)"),
        ("false_negative", "false negative\n(fraction of map)"),
        ("wall_correct_match", "correct match\n(fraction of wall cells)"),
        (f1, f"F1 at {M.tau_label(tau)}"),
    ]
    extractors = sorted(metrics["extractor"].unique()) if len(metrics) else [""]
    fig, axes = plt.subplots(
        len(extractors), len(cols), figsize=(3.2 * len(cols), 2.8 * len(extractors)),
        squeeze=False,
    )
    kind = metrics["reference_kind"].iloc[0] if len(metrics) else M.GROUND_TRUTH
    for r, ext in enumerate(extractors):
        sub = metrics[metrics["extractor"] == ext]
        for c, (col, label) in enumerate(cols):
            ax = axes[r, c]
            for ordering, g in sub.groupby("ordering", sort=True):
                g = g.sort_values("n_scans")
                ax.plot(
                    g["n_scans"], g[col], marker="o", ms=3,
                    color=ORDERING_COLOURS.get(ordering), label=ordering,
                )
            ax.set_xscale("log")
            ticks = sorted(sub["n_scans"].unique())
            ax.set_xticks(ticks, [str(t) for t in ticks], fontsize=7)
            ax.minorticks_off()
            ax.set_title(f"{ext}: {label}" if c == 0 else label, fontsize=9)
            ax.grid(alpha=0.3)
            if r == len(extractors) - 1:
                ax.set_xlabel("number of scans k")
    axes[0, -1].legend(fontsize=7, loc="lower right")
    ds = metrics["dataset"].iloc[0] if len(metrics) else ""
    fig.suptitle(f"{ds}: walls of the first k scans against the {reference_name(kind)}")
    fig.tight_layout()
    _save(fig, out)


# ----------------------------------------------------------------------- Fig. 5.5


def read_geojson_geometries(path) -> list:
    """Shapely geometries of the walls of a floor plan's GeoJSON, one per wall.

    A floor plan of :func:`floorscan.floorplan.geojson.floorplan_geojson` holds an ``axis``, a
    ``footprint`` and its ``face`` lines for each wall (property ``kind``); a wall is
    drawn as its footprint, or as its axis when it has none, so the list holds one
    geometry per wall (``len`` is the plan's wall count, one row of
    :attr:`floorscan.floorplan.plan.FloorPlan.walls` each). Features without ``kind`` (any
    other GeoJSON) are all returned.
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
            _segments_collection(reference, colors="0.75", linewidths=3,
                                 label=reference_name(reference_kind))
        )
        for g in geoms:
            _draw_geometry(ax, g, "black")
        ax.plot([], [], color="black", label="floor plan walls")
        ax.set_title(f"{name} ({len(geoms)} walls)", fontsize=10)
        ax.autoscale()
        _square(ax)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, out)


# ----------------------------------------------------------------------- Fig. 5.1


def overlay_image(inferred: np.ndarray, ground_truth: np.ndarray) -> np.ndarray:
    """RGB image of two bitmaps (Fig. 5.1): ground truth only blue (false negative),
    inferred only red (false positive), both purple (correct match), neither white.

    Returns
    -------
    (ny, nx, 3) float ndarray
    """
    bi = np.asarray(inferred, bool)
    bg = np.asarray(ground_truth, bool)
    img = np.ones(bi.shape + (3,))
    img[bg & ~bi] = (0.1, 0.2, 1.0)
    img[bi & ~bg] = (1.0, 0.1, 0.1)
    img[bi & bg] = (0.55, 0.0, 0.65)
    return img


def block_any(bitmap: np.ndarray, factor: int) -> np.ndarray:
    """Downsample a bool bitmap by ``factor`` (a cell is set if any of its block is), so
    that walls one cell wide stay visible in a figure; ``factor`` 1 returns a copy."""
    b = np.asarray(bitmap, bool)
    if factor <= 1:
        return b.copy()
    ny, nx = b.shape
    py, px = (-ny) % factor, (-nx) % factor
    b = np.pad(b, ((0, py), (0, px)))
    return b.reshape(b.shape[0] // factor, factor, b.shape[1] // factor, factor).any(axis=(1, 3))


def plot_bitmap_overlay(
    panels, reference, reference_kind: str, grid: M.Grid, wall_width_m: float, out,
    title: str = "",
) -> None:
    """Fig. 5.1: the inferred bitmap overlaid on the ground-truth (reference) bitmap.

    Parameters
    ----------
    panels : list of (str, (M, 4) segments)
        Panel title and inferred wall segments, metres.
    reference : (K, 4) segments
        Ground truth or reference, metres.
    grid : floorscan.score.metrics.Grid
        The scoring grid (the same as ``metrics.parquet``'s).
    wall_width_m : float
        Drawn wall width, metres.
    """
    bg = M.rasterize_segments(reference, grid, wall_width_m)
    # About 900 pixels across a panel: larger grids are shown block-reduced (any).
    factor = max(1, int(np.ceil(max(grid.nx, grid.ny) / 900)))
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(7 * n, 6), squeeze=False, dpi=150)
    ref = reference_name(reference_kind)
    for ax, (name, seg) in zip(axes[0], panels):
        bi = M.rasterize_segments(seg, grid, wall_width_m)
        m = M.bitmap_metrics(bi, bg)
        img = overlay_image(block_any(bi, factor), block_any(bg, factor))
        x0, _, y0, _ = grid.extent
        step = grid.cell_m * factor
        extent = (x0, x0 + img.shape[1] * step, y0, y0 + img.shape[0] * step)
        ax.imshow(img, origin="lower", extent=extent, interpolation="nearest")
        ax.set_title(
            f"{name}\nCM {m['correct_match']:.4f}  FP {m['false_positive']:.4f}  "
            f"FN {m['false_negative']:.4f}  wall-cell CM {m['wall_correct_match']:.3f}",
            fontsize=9,
        )
        _square(ax)
    handles = [
        plt.Rectangle((0, 0), 1, 1, color=(0.1, 0.2, 1.0), label=f"{ref} only (FN)"),
        plt.Rectangle((0, 0), 1, 1, color=(1.0, 0.1, 0.1), label="inferred only (FP)"),
        plt.Rectangle((0, 0), 1, 1, color=(0.55, 0.0, 0.65), label="both (correct match)"),
    ]
    axes[0, -1].legend(handles=handles, fontsize=7, loc="upper right")
    if factor > 1:
        title += f" (shown in blocks of {factor} x {factor} cells)"
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, out, dpi=150)


# ------------------------------------------------------------------ Figs. 5.11, 5.12


def plot_reference_map(grid, out, title: str = "", faces=None) -> None:
    """The reference map (:class:`floorscan.score.reference.OccupancyGrid`): free
    cells white, unknown grey, structure black, occupied cells hit by a single scan
    red; optionally a floor plan's faces ((F, 4) segments, metres) in blue over it."""
    rgb = np.full(grid.shape + (3,), 0.80)
    rgb[grid.free()] = 1.0
    h, w = grid.shape
    x0, y0 = grid.origin_xy
    r = grid.resolution_m
    counts = grid.counts()
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.imshow(rgb, origin="lower", extent=(x0, x0 + w * r, y0, y0 + h * r), interpolation="nearest")
    # occupied cells as markers of at least a pixel: at a building's scale a 5 cm cell
    # is a tenth of one, and the image alone would hide them
    size = max(0.3, (72.0 * 8 * r / max(w * r, h * r)) ** 2)
    for mask, colour in ((grid.structure(), "black"), (grid.single_scan(), (0.85, 0.1, 0.1))):
        xy = grid.cell_centres(mask)
        ax.scatter(xy[:, 0], xy[:, 1], s=size, c=[colour], marker="s", linewidths=0)
    if faces is not None and len(faces):
        ax.add_collection(_segments_collection(faces, colors="tab:blue", linewidths=0.8))
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    ax.set_title(
        f"{title}\n{counts['structure']} structure cells (black: occupied, >= {grid.params.min_scans} scans), "
        f"{counts['single_scan']} single-scan (red)\n{counts['free']} free (white), "
        f"{counts['unknown']} unknown (grey); {r * 100:.0f} cm cells",
        fontsize=9,
    )
    _save(fig, out)


def plot_quality_vs_k(curves: pd.DataFrame, out, tau: float = 0.05, up_to: float = 0.2, title: str = "") -> None:
    """F1 of the plan of the first k scans against the reference map, per extractor
    (:func:`floorscan.score.curves.score_curves`' table with an ``extractor`` column):
    every ordering, random's mean with a one-sd band over its seeds, the oracle dashed."""
    col = f"f1_{round(tau * 100):d}cm"
    extractors = sorted(curves["extractor"].unique())
    fig, axes = plt.subplots(1, len(extractors), figsize=(6.5 * len(extractors), 5), squeeze=False)
    for ax, extractor in zip(axes[0], extractors):
        c = curves[curves["extractor"] == extractor]
        n_kept = int(c["n_kept"].iloc[0])
        f1_all = float(c.loc[c["k"] == n_kept, col].iloc[0])
        ax.axvspan(0, up_to, color="0.92", zorder=0)
        for ordering, g in c.groupby("ordering", sort=True):
            n_seeds = g["seed"].nunique()
            stats = g.groupby("k", sort=True)[col].agg(["mean", "std", "count"])
            stats = stats[stats["count"] == n_seeds]  # the k every seed was scored at
            x = stats.index.to_numpy() / n_kept
            colour = ORDERING_COLOURS.get(ordering, "black")
            style = "--" if ordering == "oracle" else "-"
            label = f"{ordering} (mean of {g['seed'].nunique()} seeds)" if g["seed"].nunique() > 1 else ordering
            ax.plot(x, stats["mean"], style, color=colour, lw=1.4, label=label)
            if g["seed"].nunique() > 1:
                ax.fill_between(x, stats["mean"] - stats["std"], stats["mean"] + stats["std"], color=colour, alpha=0.2)
        ax.axhline(0.95 * f1_all, color="0.3", ls=":", lw=1, label="95 % of the all-scan F1")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_xlabel(f"k / kept scans ({n_kept} kept)")
        ax.set_ylabel(f"F1 against the reference map, tau {tau * 100:.0f} cm")
        ax.set_title(f"{extractor}", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(title or "Floor-plan F1 against the number of scans", fontsize=11)
    _save(fig, out)


def plot_walls_over_points(points, panels, out, title: str = "", max_points: int = 200_000) -> None:
    """Figs. 5.11 and 5.12: wall segments over the registered points, one panel each.

    The points are drawn first, grey and half transparent, so that the walls lie on
    them and the points show around and between the walls: returns that no wall
    explains are seen.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Registered points (map frame, metres), usually already subsampled
        (:func:`subsample_points`).
    panels : list of (str, (M, 4) segments)
        Panel title and wall segments, metres.
    max_points : int
        At most this many points are drawn: beyond, every n-th (deterministic).
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) > max_points:
        pts = pts[np.linspace(0, len(pts) - 1, max_points).astype(np.int64)]
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(6 * n, 5), squeeze=False)
    for ax, (name, seg) in zip(axes[0], panels):
        ax.scatter(pts[:, 0], pts[:, 1], s=1.5, c="0.45", alpha=0.5, linewidths=0, rasterized=True,
                   zorder=1, label=f"registered points ({len(pts)} drawn)")
        ax.add_collection(_segments_collection(seg, colors="tab:red", linewidths=0.8, zorder=2,
                                               label="wall segments"))
        ax.set_title(f"{name} ({len(M.as_segments(seg))} segments)", fontsize=10)
        ax.autoscale()
        _square(ax)
        ax.legend(fontsize=7, loc="upper right", markerscale=4)
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, out)


def subsample_points(
    points, max_points: int, seed: int, z_band=None, batch_rows: int = 1 << 20, planar_tolerance_m: float | None = None
):
    """``(N, 2)`` x, y of at most ``max_points`` points (seeded), optionally only those
    with z inside ``z_band`` when the points are 3D.

    2D against 3D as the walls stage decides it (:func:`floorscan.walls.extract.scan_points_2d`):
    points whose z spans at most ``planar_tolerance_m`` (default
    :attr:`floorscan.walls.extract.ScanParams.planar_tolerance_m`) came from a 2D scanner, at
    whatever height it was mounted (the simulated rovers' 0.3 m), and are all kept;
    here the span is the whole table's, not each scan's.

    ``points`` is a frame (``x, y, z``) or the path of a Parquet points table, which is
    read in batches of ``batch_rows`` (with ``z_band``, first z to count, then x, y of
    the drawn rows):
    the same points as from the whole frame, in memory one batch at a time.
    """
    if planar_tolerance_m is None:
        from floorscan.walls.extract import ScanParams

        planar_tolerance_m = ScanParams.planar_tolerance_m
    if isinstance(points, (str, Path)):
        return _subsample_file(points, max_points, seed, z_band, batch_rows, planar_tolerance_m)
    xyz = points[["x", "y", "z"]].to_numpy(dtype=np.float64)
    if z_band is not None and len(xyz) and _z_span(xyz[:, 2]) > planar_tolerance_m:
        xyz = xyz[(xyz[:, 2] >= z_band[0]) & (xyz[:, 2] <= z_band[1])]
    if len(xyz) > max_points:
        idx = np.random.default_rng(seed).choice(len(xyz), max_points, replace=False)
        xyz = xyz[np.sort(idx)]
    return xyz[:, :2].copy()


def _z_span(z: np.ndarray) -> float:
    z = z[np.isfinite(z)]
    return float(z.max() - z.min()) if len(z) else 0.0


def _subsample_file(path, max_points: int, seed: int, z_band, batch_rows: int, planar_tolerance_m: float) -> np.ndarray:
    import pyarrow.parquet as pq

    pf = pq.ParquetFile(path)
    missing = [c for c in ("x", "y", "z") if c not in pf.schema_arrow.names]
    if missing:
        raise KeyError(f"{path}: columns {missing} missing; expected x, y, z")
    total, three_d = pf.metadata.num_rows, False
    if z_band is not None:  # one pass over z: its span (is the table 3D), and how many are in the band
        n_band, z_lo, z_hi = 0, np.inf, -np.inf
        for b in pf.iter_batches(batch_size=batch_rows, columns=["z"]):
            z = b.column(0).to_numpy(zero_copy_only=False).astype(np.float64)
            finite = z[np.isfinite(z)]
            if len(finite):
                z_lo, z_hi = min(z_lo, float(finite.min())), max(z_hi, float(finite.max()))
            n_band += int(np.count_nonzero((z >= z_band[0]) & (z <= z_band[1])))
        three_d = z_hi - z_lo > planar_tolerance_m
        if three_d:
            total = n_band
    band = (lambda z: (z >= z_band[0]) & (z <= z_band[1])) if three_d else (lambda z: np.ones(len(z), bool))
    chosen = None
    if total > max_points:
        chosen = np.sort(np.random.default_rng(seed).choice(total, max_points, replace=False))
    out, seen = [], 0
    for b in pf.iter_batches(batch_size=batch_rows, columns=["x", "y", "z"]):
        x, y, z = (b.column(i).to_numpy(zero_copy_only=False).astype(np.float64) for i in range(3))
        m = band(z)
        xy = np.column_stack([x[m], y[m]])
        if chosen is not None:
            lo, hi = np.searchsorted(chosen, [seen, seen + len(xy)])
            xy = xy[chosen[lo:hi] - seen]
        seen += int(m.sum())
        out.append(xy)
    return np.concatenate(out) if out else np.zeros((0, 2))


# ------------------------------------------------------------------------ Table 5.1


def read_benchmark(path) -> pd.DataFrame:
    """A Snakemake benchmark TSV (columns ``s``, ``h:m:s``, ``max_rss``, ...; one row
    per repeat), with "NA"/"-" as missing."""
    return pd.read_csv(path, sep="\t", na_values=["NA", "-", ""])


def stage_of(name: str) -> str:
    """Stage of a benchmark file's name relative to the benchmarks folder, e.g.
    ``walls/sequential/ransac/k5`` or ``walls_sequential_ransac_k5`` -> ``walls``."""
    for st in STAGES:
        if name == st or re.match(rf"^{st}[/_.\-]", name):
            return st
    return re.split(r"[/_.\-]", name)[0]


def stage_times(bench_dir) -> pd.DataFrame:
    """Table 5.1 from the benchmark files present under ``bench_dir`` (recursive).

    Returns
    -------
    pandas.DataFrame
        A row per stage in pipeline order (unknown stages after, by name): ``stage``,
        ``n_jobs`` (benchmark files), ``s_total`` (sum over jobs of the mean over
        repeats, seconds), ``s_max`` (slowest job, seconds), ``max_rss_mb`` (largest
        resident memory of any job, MB; NaN when not measured). Empty when no file.
    """
    bench_dir = Path(bench_dir)
    rows = []
    for p in sorted(bench_dir.rglob("*.tsv")) if bench_dir.exists() else []:
        try:
            b = read_benchmark(p)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError):
            continue
        if "s" not in b.columns or b.empty:
            continue
        name = p.relative_to(bench_dir).with_suffix("").as_posix()
        rss = pd.to_numeric(b.get("max_rss"), errors="coerce") if "max_rss" in b else None
        rows.append(
            {
                "stage": stage_of(name),
                "job": name,
                "s": float(pd.to_numeric(b["s"], errors="coerce").mean()),
                "max_rss_mb": float(rss.max()) if rss is not None else np.nan,
            }
        )
    cols = ["stage", "n_jobs", "s_total", "s_max", "max_rss_mb"]
    if not rows:
        return pd.DataFrame(columns=cols)
    jobs = pd.DataFrame(rows)
    agg = jobs.groupby("stage", sort=False).agg(
        n_jobs=("job", "size"), s_total=("s", "sum"), s_max=("s", "max"),
        max_rss_mb=("max_rss_mb", "max"),
    ).reset_index()
    rank = {s: i for i, s in enumerate(STAGES)}
    agg["_o"] = [rank.get(s, len(STAGES)) for s in agg["stage"]]
    return agg.sort_values(["_o", "stage"]).drop(columns="_o").reset_index(drop=True)[cols]


def plot_stage_times(table: pd.DataFrame, out, title: str = "") -> None:
    """Bar charts of total time and peak memory per stage (Table 5.1)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    if len(table):
        y = np.arange(len(table))
        axes[0].barh(y, table["s_total"], color="tab:blue")
        axes[0].set_yticks(y, [f"{s} ({n})" for s, n in zip(table["stage"], table["n_jobs"])])
        axes[0].invert_yaxis()
        axes[1].barh(y, table["max_rss_mb"].fillna(0), color="tab:orange")
        axes[1].set_yticks(y, table["stage"])
        axes[1].invert_yaxis()
    else:
        for ax in axes:
            ax.text(0.5, 0.5, "no benchmark files", ha="center", transform=ax.transAxes)
    axes[0].set_xlabel("time, all jobs of the stage (s)")
    axes[1].set_xlabel("peak resident memory of a job (MB)")
    axes[0].set_title("time per stage (number of jobs)", fontsize=10)
    axes[1].set_title("memory per stage", fontsize=10)
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, out)


# ----------------------------------------------------------------------- Fig. 5.10


def plot_wall_extraction(status: dict, times: dict, out, title: str = "") -> None:
    """Fig. 5.10: wall extraction time per scan and cumulative walls, per extractor.

    Parameters
    ----------
    status : dict
        ``{extractor: DataFrame}`` of ``walls/{extractor}/scan_status.parquet``
        (``scan_id``, ``n_walls``, ``reason``); scans in recording order.
    times : dict
        ``{extractor: DataFrame}`` of ``benchmarks/scan_walls_{extractor}_times.parquet``
        (``scan_id``, ``time_s``, :data:`floorscan.walls.extract.SCAN_TIMES`), the seconds of
        each scan's extraction; a scan without a time is drawn without one.
    """
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for ext, df in sorted(status.items()):
        df = df.sort_values("scan_id")
        t_ext = times.get(ext, pd.DataFrame({"scan_id": [], "time_s": []}))[["scan_id", "time_s"]]
        df = df.merge(t_ext, on="scan_id", how="left")
        colour = EXTRACTOR_COLOURS.get(ext)
        t = pd.to_numeric(df["time_s"], errors="coerce").to_numpy() * 1e3
        n = pd.to_numeric(df["n_walls"], errors="coerce").fillna(0).to_numpy()
        axes[0].plot(df["scan_id"], t, ".", ms=2, color=colour,
                     label=f"{ext} (median {np.nanmedian(t) if len(t) else np.nan:.1f} ms)")
        axes[1].plot(df["scan_id"], np.cumsum(n), color=colour,
                     label=f"{ext} ({int(n.sum())} walls)")
        axes[2].plot(df["scan_id"], n, ".", ms=2, color=colour, label=ext)
    axes[0].set_ylabel("extraction time per scan (ms)")
    axes[0].set_yscale("log")
    axes[1].set_ylabel("cumulative walls extracted")
    axes[2].set_ylabel("walls per scan")
    for ax in axes:
        ax.set_xlabel("scan id (recording order)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    _save(fig, out)


# ----------------------------------------------------------------- all figures


def make_walls_figures(
    *,
    dataset: str,
    reference: dict,
    reference_kind: str,
    walls: dict,
    floorplans: dict,
    points,
    scan_status: dict,
    scan_times: dict,
    outputs: dict,
    cfg: dict,
    log=None,
) -> None:
    """Write the figures of a dataset's walls and floor plans (thesis Figs. 5.1, 5.5,
    5.10 - 5.12); they need no metrics, so they are drawn while the runs are scored.

    Parameters
    ----------
    dataset : str
        Dataset name, for titles.
    reference : dict
        ``{extractor: (M, 4) segments}`` the walls are scored against.
    reference_kind : str
        ``"ground_truth"`` or ``"reference"``.
    walls : dict
        ``{(ordering, extractor, k_label): DataFrame}`` raw wall segments for the
        figure runs (``cfg["figure_k"]`` and ``"all"``).
    floorplans : dict
        ``{(ordering, extractor): list of geometries}`` merged floor plans at
        ``cfg["figure_k"]``.
    points : pandas.DataFrame or path
        Registered points (``x, y, z``), or the path of ``registered.parquet``
        (read in batches); subsampled here (:func:`subsample_points`).
    scan_status : dict
        ``{extractor: DataFrame}`` wall extraction status per scan.
    scan_times : dict
        ``{extractor: DataFrame}`` seconds of each scan's wall extraction
        (:func:`plot_wall_extraction`).
    outputs : dict
        Paths: ``floorplan``, ``bitmap_overlay``, ``walls_over_points_k``,
        ``walls_over_points_all``, ``wall_extraction``.
    cfg : dict
        The ``score`` config section.
    """
    k = str(cfg["figure_k"])
    ext_fig = cfg["figure_extractor"]
    ordering_fig = cfg["figure_ordering"]
    ref_name = reference_name(reference_kind)
    extractors = sorted(scan_status) or sorted(reference)

    ref_fig = reference.get(ext_fig, next(iter(reference.values())))
    panels = [
        (f"{o}, {ext_fig}: first {k} scans", floorplans.get((o, ext_fig), []))
        for o in cfg["figure_orderings"]
    ]
    plot_floorplans(panels, ref_fig, reference_kind, outputs["floorplan"],
                    f"{dataset}: merged floor plans from the first {k} scans over the {ref_name}")

    all_refs = [M.as_segments(s) for s in reference.values() if len(M.as_segments(s))]
    grid = M.grid_for(np.vstack(all_refs), cfg["cell_m"], cfg["margin_m"])
    panels = [
        (f"{o}, {ext_fig}, first {k} scans", walls.get((o, ext_fig, k), np.zeros((0, 4))))
        for o in cfg["figure_orderings"]
    ]
    plot_bitmap_overlay(panels, ref_fig, reference_kind, grid, cfg["wall_width_m"],
                        outputs["bitmap_overlay"],
                        f"{dataset}: inferred walls (red) over the {ref_name} (blue)")

    xy = subsample_points(points, cfg["max_plot_points"], cfg["seed"], cfg["points_z_band_m"])
    for key, kk, label in (
        ("walls_over_points_k", k, f"the first {k} scans ({ordering_fig})"),
        ("walls_over_points_all", "all", "all kept scans"),
    ):
        panels = [
            (f"{e}, {label}", walls.get((ordering_fig, e, kk), np.zeros((0, 4))))
            for e in extractors
        ]
        plot_walls_over_points(xy, panels, outputs[key],
                               f"{dataset}: walls from {label} over the registered points")

    plot_wall_extraction(scan_status, scan_times, outputs["wall_extraction"],
                         f"{dataset}: wall extraction per scan, ransac against cluster_ransac")
    if log is not None:
        log.info("walls figures written for %s", dataset)


def make_score_figures(*, dataset: str, metrics: pd.DataFrame, bench_dir, outputs: dict, cfg: dict, log=None) -> pd.DataFrame:
    """Write the metrics figure (thesis Fig. 5.4) and the time per stage (Table 5.1)
    of a dataset; return the stage-time table.

    Parameters
    ----------
    dataset : str
        Dataset name, for titles.
    metrics : pandas.DataFrame
        ``metrics.parquet``.
    bench_dir : path
        ``results/{dataset}/benchmarks``: every job's benchmark file there is counted
        (the rule runs last, after the other figures).
    outputs : dict
        Paths: ``metrics_vs_k``, ``stage_times_png``, ``stage_times_tsv``.
    cfg : dict
        The ``score`` config section.
    """
    plot_metrics_vs_k(metrics, outputs["metrics_vs_k"], cfg["summary_tau_m"])
    table = stage_times(bench_dir)
    with atomic_path(outputs["stage_times_tsv"]) as tmp:
        table.to_csv(tmp, sep="\t", index=False, float_format="%.3f")
    plot_stage_times(table, outputs["stage_times_png"], f"{dataset}: time and memory per stage")
    if log is not None:
        log.info("score figures written for %s (%d stages timed)", dataset, len(table))
    return table
