"""The 2D wall points of a scan: the 2D/3D rule, the height band and the grid thinning.

A scan's registered points (map frame, metres, ``z`` = height above the floor) become
the 2D points the wall extractors fit lines to (:func:`scan_points_2d`, parameters
:class:`ScanParams`, config ``walls``): a 2D scan passes unchanged, a 3D scan is cut
to the height band of the walls (above furniture, below the ceiling, thesis section
5.3), projected to the floor plane and thinned to one mean point per grid cell
(:func:`floorscan.core.grid.cell_means`). The walls stage
(:mod:`floorscan.walls.extract`, :mod:`floorscan.walls.map_stage`), the reference map
and the answer's curve (:mod:`floorscan.score.reference`,
:mod:`floorscan.score.answer_curve`) and the coverage orderings use the same points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.config import ConfigError, schema_defaults
from floorscan.core.grid import cell_means


#: A scan whose z values span at most this is 2D, metres: a 2D scanner gives one height, a 3D scan spans metres.
PLANAR_TOLERANCE_M = 0.01
#: 3D scans: one mean point per cell of this side, metres: below the RANSAC inlier distance (3 cm), so no wall moves.
GRID_M = 0.02


@dataclass(frozen=True)
@schema_defaults(
    "walls",
    min_height_m=lambda d: float(d["height_band_m"][0]),
    max_height_m=lambda d: float(d["height_band_m"][1]),
)
class ScanParams:
    """How a scan becomes 2D wall points (config ``walls.height_band_m``; the 2D rule
    and the grid are the module's constants).

    Attributes
    ----------
    min_height_m, max_height_m : float
        Height band (above the floor) kept of 3D scans, metres.
    planar_tolerance_m : float
        A scan whose finite ``z`` values span at most this is 2D and passes unchanged
        (a 2D scanner has one height whatever it is); otherwise it is 3D.
    grid_m : float
        3D scans only: after the band cut and the projection to (x, y), keep one
        point (the mean) per grid cell of this size, metres; 0 keeps all points.
    """

    min_height_m: float
    max_height_m: float
    planar_tolerance_m: float = PLANAR_TOLERANCE_M
    grid_m: float = GRID_M

    def __post_init__(self):
        if not self.min_height_m < self.max_height_m:
            raise ConfigError(
                f"walls.height_band_m must be [min, max] with min < max, got {[self.min_height_m, self.max_height_m]}"
            )


def scan_points_2d(xyz: np.ndarray, params: ScanParams = ScanParams()) -> tuple[np.ndarray, str]:
    """The 2D wall points of one scan, or a reason why it has none.

    Rule for 2D against 3D: a scan whose ``z`` values span at most
    ``planar_tolerance_m`` came from a 2D scanner and passes unchanged (its single
    height may be anywhere, e.g. 0.3 m). Otherwise the scan is 3D: points with
    ``min_height_m <= z <= max_height_m`` are kept (above furniture, below the
    ceiling), projected to (x, y) and thinned to one mean point per ``grid_m`` cell.

    Parameters
    ----------
    xyz : (N, 3) float ndarray
        Scan points in the map frame, metres; ``z`` is height above the floor.
    params : ScanParams

    Returns
    -------
    points : (M, 2) float64 ndarray
        Wall points (x, y), metres; empty when ``reason`` is not "".
    reason : str
        "" or one of :data:`floorscan.walls.tables.REASONS` (``non_finite_coordinates``,
        ``no_points_in_height_band``).

    Raises
    ------
    ValueError
        When ``xyz`` is not two-dimensional with at least two columns.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] < 2:
        raise ValueError(f"scan points must be (N, 3), got shape {xyz.shape}")
    empty = np.empty((0, 2))
    if len(xyz) == 0:
        return empty, ""
    if not np.isfinite(xyz).all():
        return empty, "non_finite_coordinates"
    if xyz.shape[1] == 2:
        return xyz.copy(), ""
    z = xyz[:, 2].copy()  # contiguous: quicker min, max and band cut
    if float(z.max() - z.min()) <= params.planar_tolerance_m:
        return xyz[:, :2].copy(), ""
    band = np.flatnonzero((z >= params.min_height_m) & (z <= params.max_height_m))
    if len(band) == 0:
        return empty, "no_points_in_height_band"
    if params.grid_m > 0:
        return cell_means(xyz[band, :2], params.grid_m)[0], ""  # one mean point per occupied cell
    return xyz[band, :2], ""
