"""The answer's floor plan, before and after the map extractor and the structure passes
(issue 33), on datasets already run (``results/<dataset>/``: registration, selection,
per-scan walls, reference map; the synthetic ones their true walls).

For each dataset it builds, from the same selected scans:

- ``per_scan``: the per-scan extractor's segments (``floorplan`` config's old default,
  ransac) merged and paired, no structure passes (the plan of the previous tree);
- ``per_scan+structure``: the same segments through the structure passes;
- ``map+structure``: the map extractor's segments through the structure passes (the
  new default);

and scores each with :func:`floorscan.score.answer.score_answer_plan`.

``python -m benchmarks answer --datasets demo hallways intel [--scans all] [--figure grid.png]``
(``--figure``: the plans before and after, side by side, one row per dataset).
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np
import pandas as pd

COLUMNS = ["n_walls", "n_clutter", "n_junctions", "short_wall_share", "n_crossings",
           "map_completeness_5cm", "map_correctness_5cm", "map_completeness_all_5cm", "map_f1_5cm",
           "gt_precision_5cm", "gt_recall_5cm", "gt_f1_5cm", "gt_n_walls", "gt_corners_as_junctions"]


def plans_of(ds: str, scans: str = "selected"):
    from floorscan.core.io import read_table
    from floorscan.core.occupancy import read_grid
    from floorscan.floorplan.geojson import write_geojson
    from floorscan.floorplan.plan import build_floorplan
    from floorscan.walls.map_stage import map_of_scans

    root = f"results/{ds}"
    registration = read_table(f"{root}/registration.parquet")
    if scans == "selected":
        ids = pd.read_csv(f"{root}/selection/scans.csv")["scan_id"].to_numpy(np.int64)
    else:
        ids = registration.loc[registration["kept"], "scan_id"].to_numpy(np.int64)
    per_scan = read_table(f"{root}/walls/ransac/per_scan.parquet")
    per_scan = per_scan[per_scan["scan_id"].isin(ids)]
    t = time.perf_counter()
    segments, grid = map_of_scans(f"{root}/registered.parquet", registration, ids, {})
    t_map = time.perf_counter() - t
    out, times = {}, {"map_walls_s": t_map}
    tmp = tempfile.mkdtemp()
    for name, seg, g in (("per_scan", per_scan, None), ("per_scan+structure", per_scan, grid),
                         ("map+structure", segments, grid)):
        t = time.perf_counter()
        plan = build_floorplan(seg, grid=g)
        times[f"{name}_s"] = time.perf_counter() - t
        path = os.path.join(tmp, f"{name}.geojson")
        write_geojson(plan, path)
        out[name] = path
    return out, times


def main(argv=None):
    from floorscan.score.answer import read_truth, score_answer_plan
    from floorscan.score.against_reference import Structure
    from floorscan.core.occupancy import read_grid

    ap = argparse.ArgumentParser(prog="benchmarks answer")
    ap.add_argument("--datasets", nargs="+", default=["demo", "hallways", "hallways3d"])
    ap.add_argument("--scans", choices=["selected", "all"], default="selected")
    ap.add_argument("--figure", help="write the before/after grid of the plans here (PNG)")
    args = ap.parse_args(argv)
    rows, drawn = [], {}
    for ds in args.datasets:
        plans, times = plans_of(ds, args.scans)
        drawn[ds] = plans
        ref_path = f"results/{ds}/reference/occupancy.parquet"
        reference = Structure(read_grid(ref_path)) if os.path.exists(ref_path) else None
        truth_path = f"results/{ds}/sim/walls.geojson"
        truth = read_truth(truth_path) if os.path.exists(truth_path) else None
        for name, path in plans.items():
            rows.append({"dataset": ds, "plan": name, **score_answer_plan(path, reference, truth)})
        print(ds, {k: round(v, 2) for k, v in times.items()}, flush=True)
    table = pd.DataFrame(rows)
    cols = ["dataset", "plan"] + [c for c in COLUMNS if c in table.columns]
    if args.figure:
        plan_grid(drawn, args.figure)
    with pd.option_context("display.width", 250, "display.max_columns", 40, "display.float_format", "{:.3f}".format):
        print(table[cols].to_string(index=False))
    return table


def plan_grid(plans: dict, path) -> None:
    """Before (``per_scan``) and after (``map+structure``) of each dataset side by side:
    walls black, clutter orange, junctions as dots."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from floorscan.score.answer import plan_parts

    names = list(plans)
    fig, axes = plt.subplots(len(names), 2, figsize=(12, 5 * len(names)))
    axes = np.atleast_2d(axes)
    for row, ds in zip(axes, names):
        for ax, (label, key) in zip(row, (("before: per-scan walls, merged", "per_scan"),
                                         ("after: map walls, structure passes", "map+structure"))):
            parts = plan_parts(plans[ds][key])
            ax.add_collection(LineCollection(parts["clutter"].reshape(-1, 2, 2), colors="#f59e0b", linewidths=0.6))
            ax.add_collection(LineCollection(parts["axes"].reshape(-1, 2, 2), colors="k", linewidths=0.9))
            if len(parts["junctions"]):
                ax.plot(parts["junctions"][:, 0], parts["junctions"][:, 1], ".", ms=2, color="#2563eb")
            ax.autoscale()
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"{ds}: {label} ({len(parts['axes'])} walls)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    plt.close(fig)


if __name__ == "__main__":
    main()
