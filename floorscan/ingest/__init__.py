"""Ingest: read a recording into the scan and pose tables (thesis sections 3.2 and 3.5).

Three formats are read, each by its own reader:

- ``rosbag`` (:mod:`floorscan.ingest.rosbag`): ROS1 ``.bag`` files and ROS2 bag folders
  through rosbags' ``AnyReader``; scans from ``sensor_msgs/LaserScan`` or
  ``sensor_msgs/PointCloud2`` (:mod:`floorscan.ingest.ros_messages`); poses from a pose
  topic or the TF tree (its links and chains :mod:`floorscan.ingest.tf_chains`, the
  poses of a chain :mod:`floorscan.ingest.tf_poses`).
- ``carmen`` (:mod:`floorscan.ingest.carmen`): ``FLASER`` and ``ROBOTLASER1`` lines of a
  CARMEN log (plain or gzip), with the corrected pose on each line
  (:mod:`floorscan.ingest.carmen_lines`).
- ``pcd`` (:mod:`floorscan.ingest.pcd`): a folder of ``.pcd`` scans in the map frame plus
  a CSV of scan locations (the thesis's synthetic layout, section 4.1); each ``.pcd``
  file's header and points are read by :mod:`floorscan.ingest.pcd_file`.

An occupancy map given instead of a recording (``map``: a ROS map_server map or an
image) is read by :mod:`floorscan.ingest.occupancy_map` into the grid the walls and rooms
read (rule ``map_ingest``); the pages read what was read of it too, so it is in core.

A dataset may name only its ``path``: the format is then detected from it
(:func:`floorscan.ingest.detect.detect_format`), a bag's scan topic and pose source from
its topics and TF tree (:mod:`floorscan.ingest.rosbag_detect`), a CARMEN log's no-return
range and the kind of its stamps from its readings (:mod:`floorscan.ingest.carmen_ranges`,
:mod:`floorscan.ingest.carmen_stamps`). What was found travels with the data as
:attr:`Recording.detected <floorscan.ingest.recording.Recording>`, stored in the schema
metadata of ``scan_index.parquet`` and ``pose_stream.parquet``.

Every reader keeps the same returns (:mod:`floorscan.ingest.points`): finite, at or
beyond the minimum range and strictly short of the maximum range; a return at the
maximum is the scanner's "no return" and would draw an arc of fake wall. The text
formats (a CARMEN log, an ascii PCD, the locations CSV) read a number field the same way
(:mod:`floorscan.ingest.text`).

Every reader yields :class:`~floorscan.ingest.recording.Scan` records in recording order
plus a pose stream (:mod:`floorscan.ingest.recording`);
:func:`floorscan.ingest.readers.open_recording` opens the recording a dataset names, and
:func:`floorscan.ingest.writer.write_recording` streams the points to ``scans.parquet``
one batch at a time, so memory grows with the largest scan, not with the recording. The
``poses`` stage (:mod:`floorscan.ingest.poses`) interpolates a pose for each scan.

The other way round, :mod:`floorscan.ingest.reduced` writes the recording cut to a set
of scans (the select stage's answer), in its own format, finding each scan where the
reader found it (one module per format: ``reduced_bag``, ``reduced_carmen``,
``reduced_pcd``; their checks ``reduced_checks``).

To add a format: a reader module whose ``open_...`` function returns a
:class:`~floorscan.ingest.recording.Recording`, its branch in
:func:`~floorscan.ingest.readers.open_recording`, its rule in
:mod:`floorscan.ingest.detect`, its reduced-recording writer
(:data:`floorscan.ingest.reduced.REDUCERS`), and the format in the dataset ``format``
enum of ``workflow/schemas/config.schema.yaml``. The package imports only :mod:`floorscan.core`.
"""
