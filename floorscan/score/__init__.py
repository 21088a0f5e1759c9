"""The score stage: the reference map of a recording and the quality of floor plans
against it (the reference-and-metrics work; :mod:`floorscan.score.metrics` holds the
thesis's section 5.1 metrics and moves here with the architecture step).

Modules:

- :mod:`floorscan.score.reference`: the occupancy grid of all kept scans (mapping with
  known poses), written in ROS map_server format;
- :mod:`floorscan.score.against_reference`: completeness, correctness, F1 and median
  distance of a floor plan against that map (ISPRS indoor benchmark terms).
"""
