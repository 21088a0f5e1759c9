"""The register stage's parts that decide what a recording needs and whether its result
holds (``floorscan.register.registration`` holds the registration itself until the stage's
package move, see ``../shared/ARCHITECTURE.md``).

- :mod:`floorscan.register.sampling`: which scans to register, by the rover's motion
  (Algorithm 3 step 2 of the thesis, as a motion filter), with thresholds chosen from the
  recording;
- :mod:`floorscan.register.consistency`: whether the registered map agrees with itself
  where the rover passed twice, and the verdict on a registration.
"""
