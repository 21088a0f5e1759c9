"""floorscan: scan selection and wall extraction for indoor floor plans from LIDAR
recordings (the thesis "Pointcloud scan selection for indoor floor plan generation").

One subpackage per stage of the workflow, in pipeline order; a stage imports
:mod:`floorscan.core` and earlier stages only (``tests/test_architecture.py``):

- :mod:`floorscan.ingest` (recordings to tables, and the scan poses) and
  :mod:`floorscan.sim` (synthetic buildings and their recordings);
- :mod:`floorscan.register`: the scans in one map frame (thesis Algorithm 3);
- :mod:`floorscan.select`: hulls, orderings (Algorithms 1 and 2) and the selection;
- :mod:`floorscan.walls`: wall segments per scan (section 3.4, Algorithm 4);
- :mod:`floorscan.floorplan`: the floor plan and its exports;
- :mod:`floorscan.score`: the reference map, metrics and quality-vs-k curves (Chapter 5);
- :mod:`floorscan.figures`: the figures and the report's front page.

The workflow's thin scripts (``scripts/<rule>.py``) call one public function each.
"""
