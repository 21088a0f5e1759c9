"""The score stage: the reference map of a recording, and the quality of the walls and
floor plans of the first k scans of every ordering against the ground truth
(synthetic datasets) or a reference (real recordings); thesis Chapter 5.

Modules, from the segments up:

- :mod:`floorscan.score.segments`: samples along wall segments (the segments as
  ``(M, 4)`` arrays: :mod:`floorscan.core.segments`);
- :mod:`floorscan.score.bitmap`: the thesis's section 5.1 bitmap metrics (correct
  match, false positive, false negative) on the scoring raster of the walls
  (:mod:`floorscan.core.segment_raster`);
- :mod:`floorscan.score.capsule`, :mod:`floorscan.score.nearest`: the exact length of
  walls within a tolerance of others, the exact distance of points to the nearest
  wall;
- :mod:`floorscan.score.tolerance`: precision (correctness), recall (completeness),
  F1 and median distance at each tolerance (ISPRS indoor benchmark terms);
- :mod:`floorscan.score.growing`: all metrics of a wall set, from scratch or for a
  set growing with k;
- :mod:`floorscan.score.geojson`, :mod:`floorscan.score.ground_truth`: what is read
  from GeoJSON (the simulator's walls, a floor plan's faces) and what the walls are
  scored against;
- :mod:`floorscan.score.runs`: the per-run scores table of a dataset (rule
  ``score_runs``); :mod:`floorscan.score.summary`: its scan-reduction summary;
- :mod:`floorscan.score.reference`: the occupancy grid of all kept scans (mapping with
  known poses), written in ROS map_server format;
- :mod:`floorscan.score.against_reference`: completeness, correctness, F1 and median
  distance of a floor plan against that map (its structure cells near points and
  segments found on the grid: :mod:`floorscan.score.structure_grid`);
- :mod:`floorscan.score.curves`: floor-plan quality against k for every ordering,
  random's seeds and the oracle; :mod:`floorscan.score.curve_summary`: their summary
  (k95, k99, area under the curve) and its tables;
- :mod:`floorscan.score.rooms`: a plan's rooms and doors against the true ones
  (one-to-one matching by IoU, Bormann et al., ICRA 2016; rule ``score_rooms``), and
  :mod:`floorscan.score.drawn_rooms` against rooms drawn by people (rule
  ``score_drawn``); both, and the room benchmark (``benchmarks/bench_rooms.py``), score
  through :mod:`floorscan.score.segmentation` (Bormann's per-room mean and pooled
  precision and recall, and the IoU-0.5 matching, from one intersection matrix);
- :mod:`floorscan.score.drawn`: a plan drawn by people, aligned to the map frame
  (its search over rotation and scale: :mod:`floorscan.score.correlative`, correlative
  matching with branch and bound) and the plans scored against it (rule
  ``score_drawn``).

A new metric of a wall set is computed in :func:`floorscan.score.growing.score_walls`
(and its incremental twin ``_GrowingWalls.score``, tested equal) and becomes a column
of the scores table; a new metric of a floor plan against the reference map goes to
:func:`floorscan.score.against_reference.plan_against_reference`.
"""
