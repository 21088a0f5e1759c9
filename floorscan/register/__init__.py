"""The register stage: every kept scan of a recording in one map frame, refined by planar
ICP (thesis 3.2.2, 3.5, Algorithm 3 steps 2-6), and whether the result holds.

Modules, in the order the stage uses them:

- :mod:`~floorscan.register.params`: :class:`~floorscan.register.params.RegistrationConfig` (config
  ``register``) and :class:`~floorscan.register.params.GraphParams` (``register.graph``);
- :mod:`~floorscan.register.sampling`: which scans to register, by the rover's motion,
  with thresholds chosen from the recording;
- :mod:`~floorscan.register.screening`: the per-scan checks (missing pose, duplicate,
  too few points, pose jump) and the sampling among the scans that pass;
- :mod:`~floorscan.register.prepare`: the clouds of a scan that registration aligns;
- :mod:`~floorscan.register.icp`: planar ICP and Open3D-style fitness;
- the strategies of step 5: :mod:`~floorscan.register.posegraph` (``reference:
  graph``, the default; its :mod:`~floorscan.register.edges`,
  :mod:`~floorscan.register.edge_stream` and :mod:`~floorscan.register.solver`),
  :mod:`~floorscan.register.scan_to_map` (``map``),
  :mod:`~floorscan.register.sequential` (``previous``, the thesis's) and
  :mod:`~floorscan.register.odometry` (``mode: odometry``, no map poses);
- :mod:`~floorscan.register.losses`: the scans the recording lost before registration
  (without a pose, or at ingest), counted against all its scans;
- :mod:`~floorscan.register.consistency`: whether the registered map agrees with
  itself where the rover passed twice, and the verdict (with the losses);
- :mod:`~floorscan.register.result`: a strategy's per-scan result, the per-scan table,
  its summary, the errors;
- :mod:`~floorscan.register.pipeline`: the steps in order on a recording in memory
  (:func:`~floorscan.register.pipeline.register_scans`);
- :mod:`~floorscan.register.stream`: the stage's entry point, the same on a points file
  streamed scan by scan (:func:`~floorscan.register.stream.register_recording`).

To add a strategy: a module beside the others with a function
``(sampled, clouds, sids, t, cfg, initial) -> ScanRegistration``
(:class:`~floorscan.register.result.ScanRegistration`: a new per-scan result, nothing
filled in place), a branch in :func:`floorscan.register.pipeline.register_screened` and
a value of ``reference`` in ``workflow/schemas/register.schema.yaml``.
"""
