"""The select stage's orderings of the kept scans (thesis section 3.3). New orderings
live here (:mod:`floorscan.select.coverage`); the thesis's hull orderings and the
baselines are in :mod:`floorscan.select.orderings` until the move of issue 25."""
