"""What several stages need (../shared/ARCHITECTURE.md); it imports no stage.

- :mod:`~floorscan.core.io`: the tables the stages exchange (Parquet schemas, reading,
  writing, streaming a points table scan by scan);
- :mod:`~floorscan.core.files`: files written atomically, and the temporaries a killed
  run left;
- :mod:`~floorscan.core.config`: the config's validation against the stage schemas and
  the parameter dataclasses' defaults from them (written once, in the schemas);
- :mod:`~floorscan.core.stage`: a stage script's logging and error reporting;
- :mod:`~floorscan.core.messages`: what an error message says: the user's data quoted
  short, a system error (no space, read-only, permission) named with what to do;
- :mod:`~floorscan.core.runtime`: progress lines, worker processes
  (``concurrent.futures`` with spawn), thread limits;
- :mod:`~floorscan.core.shards`: the per-scan stages split by scan range into jobs;
- :mod:`~floorscan.core.occupancy` (the occupancy grid of scans, map_server maps),
  :mod:`~floorscan.core.occupancy_classes` (a grid of given classes: a map),
  :mod:`~floorscan.core.map_info` (what the ingest stage read of a map,
  ``map/map.json``, for the pages; the map reader is ingest's
  :mod:`floorscan.ingest.occupancy_map`);
- what a stage's files hold, as the stages after it read them:
  :mod:`~floorscan.core.plan_tables` (a floor plan's tables),
  :mod:`~floorscan.core.selection` (which scans: the first k of an ordering, the
  selected ones), :mod:`~floorscan.core.score_tables` (the score stage's tables: the
  values and names of their columns, their cells for people);
- :mod:`~floorscan.core.wall_points` (a scan's 2D wall points: the height band of 3D
  scans), :mod:`~floorscan.core.geometry` (SE(2), points along wall segments),
  :mod:`~floorscan.core.segments` (wall segments as arrays),
  :mod:`~floorscan.core.segment_raster` (wall segments on the scoring grid),
  :mod:`~floorscan.core.grid` (integer grid cells), :mod:`~floorscan.core.greedy` (lazy
  greedy maximum coverage, for the coverage orderings and the score stage's oracle).
"""
