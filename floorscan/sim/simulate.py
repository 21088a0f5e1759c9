"""The simulate stage: a rover drives a synthetic building and records it.

The thesis validates its method on a simulated building whose walls are known exactly
(sections 4.1 and 5.2). :func:`run_simulation` reads the building file
(:mod:`floorscan.sim.building_file`), builds the dataset's scanner
(:mod:`floorscan.sim.scanners`), plans the recording (:mod:`floorscan.sim.recording`) and
writes, all deterministic for a seed:

- ``recording.bag`` (ROS1) and ``pcd/`` (:mod:`floorscan.sim.writer`);
- ``true_poses.parquet``: ``t_ns`` (the scan's header stamp), ``x, y, z, yaw`` float64,
  the true scanner pose of every scan;
- ``building.stl`` (:mod:`floorscan.sim.mesh`) and ``walls.geojson`` (ground truth
  sliced at ``sensor_height_m``, :mod:`floorscan.sim.ground_truth`).
"""

from __future__ import annotations

import logging
import os
from typing import Any, Mapping

from floorscan.core.config import stage_params
from floorscan.core.io import InputError, write_table
from floorscan.core.files import write_json
from floorscan.sim.building_file import load_building
from floorscan.sim.ground_truth import TRUE_POSES, ground_truth_walls, true_poses_frame
from floorscan.sim.mesh import write_stl
from floorscan.sim.params import SimParams
from floorscan.sim.recording import simulate_recording
from floorscan.sim.scanners import scanner_from_config
from floorscan.sim.writer import write_recording

log = logging.getLogger(__name__)


def run_simulation(
    building_path: str | os.PathLike,
    dataset: Mapping[str, Any],
    cfg: Mapping[str, Any],
    outputs: Mapping[str, str | os.PathLike],
) -> dict:
    """Simulate one synthetic dataset and write all its files (the ``simulate`` stage).

    Parameters
    ----------
    building_path : path
        The building YAML.
    dataset : mapping
        The dataset entry: ``scanner`` (a name under ``cfg["scanners"]``), ``seed``,
        optionally ``name``.
    cfg : mapping
        The ``simulate`` config section (``scanners`` and :class:`SimParams` keys).
    outputs : mapping
        Paths for ``bag``, ``pcd`` (folder), ``true_poses``, ``stl``, ``walls``.

    Returns
    -------
    dict
        Counts and the settings used (see :func:`write_recording`).

    Raises
    ------
    InputError
        Bad building, unknown or invalid scanner.
    floorscan.core.config.ConfigError
        Invalid parameters (:func:`floorscan.core.config.stage_params`).
    """
    name = dataset.get("name", "?")
    scanners = cfg.get("scanners") or {}
    sname = dataset.get("scanner")
    if sname not in scanners:
        raise InputError(
            f"config datasets.{name}.scanner: {sname!r} is not a scanner in "
            f"simulate.scanners {sorted(scanners)}"
        )
    scanner = scanner_from_config(sname, scanners[sname])
    params = stage_params(SimParams, cfg)
    seed = dataset.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"config datasets.{name}.seed: expected an integer >= 0, got {seed!r}")
    building = load_building(building_path)
    rec = simulate_recording(building, scanner, params, seed)
    log.info(
        "%s: building %s, scanner %s (%d rays), %d scans over %.1f s",
        name, building.name, sname, len(scanner.directions()), len(rec.scan_t_ns),
        (rec.scan_t_ns[-1] - rec.scan_t_ns[0]) / 1e9,
    )
    write_stl(rec.mesh, outputs["stl"])
    write_table(true_poses_frame(rec), outputs["true_poses"], schema=TRUE_POSES,
                metadata={"dataset": str(name), "frame": "map", "units": "m, rad, ns"})
    counts = write_recording(rec, outputs["bag"], outputs["pcd"])
    observed = counts.pop("observed_xy")
    write_json(ground_truth_walls(building, params.sensor_height_m, observed), outputs["walls"])
    log.info("%s: wrote %s", name, counts)
    return counts
