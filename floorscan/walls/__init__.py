"""Wall extraction (stage ``walls``): the wall segments of every scan, and of the first k
scans of each ordering (thesis sections 3.4 and 5.3, Algorithm 4).

A scan's registered points (map frame, metres, ``z`` = height above the floor) become
2D wall points, which an extractor fits with lines and cuts into wall segments; the
walls of a scan depend only on its points, the parameters and ``(seed, scan_id)``, so
every kept scan is extracted once per extractor, in shards of scans, whatever the
ordering or k.

Modules, in the order of the work:

* :mod:`~floorscan.walls.params`: the parameters (config section ``walls``);
* :mod:`floorscan.core.wall_points`: a scan's 2D wall points (2D rule, height band, grid;
  shared with the reference map and the coverage orderings);
* :mod:`~floorscan.walls.segments`: a fitted line's wall segments (gaps, coverage, ends);
* :mod:`~floorscan.walls.ransac`: iterative RANSAC (section 5.3, Algorithm 4), on many
  points by :mod:`~floorscan.walls.tiles` (the points a line passes near);
* :mod:`~floorscan.walls.normals`, :mod:`~floorscan.walls.meanshift`,
  :mod:`~floorscan.walls.cluster`: clustering RANSAC (section 3.4);
* :mod:`~floorscan.walls.extractors`: the registry of extractors by name;
* :mod:`~floorscan.walls.extract`: every scan of a dataset with one extractor (rule
  ``scan_walls_shard``);
* :mod:`~floorscan.walls.shards`: the merge of those shards (rule ``scan_walls``);
* :mod:`~floorscan.walls.first_k`: the walls of the first k scans of each ordering
  (rule ``walls``);
* :mod:`~floorscan.walls.tables`: the schemas of the stage's tables.

How to add an extractor (say ``hough``):

1. Write its function in a module of its own, ``floorscan/walls/hough.py``:
   ``_hough_rows(points, params, hough, seed) -> list[tuple]``, the wall segments of
   one scan's (N, 2) wall points as ``(x0, y0, x1, y1, n_inliers, rmse_m)`` tuples
   (see :class:`floorscan.walls.extractors.Extractor` for the contract). ``params``
   is :class:`~floorscan.walls.params.RansacParams`, the segment rules every extractor
   shares; :func:`floorscan.walls.segments.claimed_segments` turns a line into
   segments by them. Its own parameters, if any, are a frozen dataclass
   (``HoughParams``) beside the others in :mod:`floorscan.walls.params`. Add a public
   ``hough(points, params, hough, seed) -> DataFrame`` for people and tests
   (:func:`floorscan.walls.tables.segments_frame` of the rows), and tests.
2. Register it in :data:`floorscan.walls.extractors.REGISTRY`: ``"hough":
   Extractor(rows=_hough_rows, config={"ransac": RansacParams, "hough": HoughParams},
   cost=...)``, ``config`` in the order the function takes the parameters, ``cost``
   its seconds per scan relative to ransac's (it sets the priority of its shard jobs).
3. Add the name to the enum of ``walls.extractors`` in
   ``workflow/schemas/walls.schema.yaml``, and its section (``hough:`` with the
   dataclass's defaults) when it has one.

Nothing else: the workflow passes the config sections of the registry to the
extraction (``walls_extract_config``) and derives the priorities from the costs
(``workflow/rules/common.smk``); a name in ``walls.extractors`` that is not registered
stops the run when the rules are read, and :func:`floorscan.walls.extract.extract_walls`
raises for it. To offer it to later stages' choices as well, add it to their enums
(``select.coverage.wall_extractor``, ``floorplan.extractor``).
"""
