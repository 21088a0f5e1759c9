"""Figures and the report (stage ``figures``): the thesis's Chapter 5 figures and the
dataset's front page. It reads every stage's files (through :mod:`floorscan.core`'s
readers) and imports no other stage package (../shared/ARCHITECTURE.md); what a figure
needs computed by a stage is in that stage's files (the bitmap overlay's numbers:
``score/<extractor>.parquet``) or is handed over by the figure job's script (the
selection figures' curves, :mod:`floorscan.select.figure_data`; the plans' footprints,
:func:`floorscan.floorplan.footprints.read_plan_footprints`).

- :mod:`~floorscan.figures.registration` (the registered map),
  :mod:`~floorscan.figures.selection` (coverage against scans and clusters, Figs 5.6-5.8);
- :mod:`~floorscan.figures.scoring` (the score stage's figures, drawn by
  :mod:`~floorscan.figures.curves`, :mod:`~floorscan.figures.floorplans`,
  :mod:`~floorscan.figures.bitmaps`, :mod:`~floorscan.figures.maps`,
  :mod:`~floorscan.figures.wall_extraction`, :mod:`~floorscan.figures.stage_times`, in
  the style of :mod:`~floorscan.figures.style`);
- :mod:`~floorscan.figures.report` (the front page), :mod:`~floorscan.figures.summary_page`
  (the summary table as HTML), :mod:`~floorscan.figures.room_table` (the plan's rooms on it),
  :mod:`~floorscan.figures.plan_scores` (how good the plan is, on it),
  :mod:`~floorscan.figures.answer` (what a finished run prints, and ``summary.md``),
  :mod:`~floorscan.figures.index_page` (the index of a run of several recordings).
"""
