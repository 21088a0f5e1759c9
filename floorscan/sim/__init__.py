"""The synthetic buildings and their simulated recordings (stage ``simulate``).

The thesis validates its method on a simulated building whose walls are known exactly
(sections 4.1 and 5.2). Modules, in the order the stage uses them
(:func:`floorscan.sim.simulate.run_simulation`):

- :mod:`~floorscan.sim.building` (the model and its file format),
  :mod:`~floorscan.sim.building_file` (reading and checking a building file),
  :mod:`~floorscan.sim.footprint` (the walls in plan), :mod:`~floorscan.sim.obstacles`
  (where the rover cannot drive), :mod:`~floorscan.sim.mesh` (the triangle mesh, STL);
- :mod:`~floorscan.sim.scanners` (2D and 3D scanner models),
  :mod:`~floorscan.sim.raycast` (ranges cast in the mesh);
- :mod:`~floorscan.sim.params` (the stage's parameters), :mod:`~floorscan.sim.trajectory`
  (the rover's path), :mod:`~floorscan.sim.recording` (the scan, AMCL and odometry
  streams);
- :mod:`~floorscan.sim.ros1` (the bag's messages), :mod:`~floorscan.sim.writer` (the ROS1
  bag and the PCD folder), :mod:`~floorscan.sim.ground_truth` (the ground-truth walls,
  rooms, doors and the true poses);
- :mod:`~floorscan.sim.occupancy_map` (the building's plan view as a map_server map: the
  map input with its rooms and doors known).

The package imports only :mod:`floorscan.core`. To add a scanner kind, see
:mod:`floorscan.sim.scanners`; a building element, :mod:`floorscan.sim.building`.
"""
