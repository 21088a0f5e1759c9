"""The hulls and select stages: which scans cover the floor, and in what order to take
them (thesis section 3.3, Algorithms 1 and 2).

Stage ``hulls`` (``scripts/hulls_shard.py``, one job per shard of the kept scans):

- :mod:`~floorscan.select.hulls`: the coverage hulls of each scan (Algorithm 2), the
  stage's tables, and the merge of its shards;
- :mod:`~floorscan.select.clusters`: KMeans clusters of a scan and the outlier rule;
- :mod:`~floorscan.select.convex`: the convex hulls of many clusters at once (GEOS).

Stage ``select`` (``scripts/select.py``: merges the hull shards, then orders the scans;
``scripts/select_coverage.py``: the coverage orderings after the walls stage;
``scripts/selection.py``: the recommended selection):

- :mod:`~floorscan.select.registry`: every ordering by name (see below);
- :mod:`~floorscan.select.orderings`: runs the registered orderings, measures the hull
  area along each;
- :mod:`~floorscan.select.raster`: coverage polygons as raster cells;
- :mod:`~floorscan.select.greedy`: greedy maximum coverage (Algorithm 1: ``cluster_hull``,
  ``convex_hull``);
- :mod:`~floorscan.select.baselines`: ``random``, ``sequential``, ``motion_filter``;
- :mod:`~floorscan.select.coverage`: ``wall_coverage``, ``surface_coverage`` cell sets;
- :mod:`~floorscan.select.summary`: the k reaching 90/95/99 % coverage;
- :mod:`~floorscan.select.deliverables`, :mod:`~floorscan.select.recommend`: how many
  scans to keep, the scan list and their points (the recording cut to the selected
  scans is the ingest stage's writer, :mod:`floorscan.ingest.reduced`: it reads the
  recording's formats);
- :mod:`~floorscan.select.figure_data`: the data of the selection figures (Figs
  5.6-5.8, drawn by :mod:`floorscan.figures.selection`);
- :mod:`~floorscan.select.params`: ``HullParams``, ``SelectParams``, ``CoverageParams``.

Adding an ordering
------------------
1. Write the function that ranks the scans, in the module of its family (or a new
   module named by what it does).
2. Register it in :mod:`floorscan.select.registry`: an entry of ``RANKERS`` (ranked in
   the ``select`` job from the hulls and poses: ``rank(HullInputs) -> scan ids``) or
   of ``COVERAGE_SETS`` (ranked by the lazy greedy in the ``select_coverage`` job from
   the walls' per-scan segments and the points: ``cells(CoverageInputs) -> (cover,
   quality, value)``).
3. Add its name to the enums of ``select.default_ordering``
   (``workflow/schemas/select.schema.yaml``) and ``walls.orderings``
   (``workflow/schemas/walls.schema.yaml``), in the registry's order (the figures
   colour the orderings by their place in ``walls.orderings``; a test checks).

``ORDERINGS`` and ``COVERAGE_ORDERINGS`` of the registry follow, and with them the
rules' outputs, the summary table and the figures.
"""
