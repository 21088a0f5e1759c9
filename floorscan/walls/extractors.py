"""The registry of wall extractors: what each one is called, computes, reads and costs.

:data:`REGISTRY` maps an extractor's name (config ``walls.extractors``, wildcard
``{extractor}``, folder ``walls/{extractor}/``) to an :class:`Extractor`: its function,
the config sections it reads with their parameter classes, and its relative cost. The
rest follows from it: :func:`floorscan.walls.extract.extract_walls` looks the name up
(:func:`get_extractor`; an unknown name raises), and the workflow
(``workflow/rules/common.smk``) imports :data:`REGISTRY` and :data:`EXTRACT_KEYS` for
the config that decides the per-scan extraction and for the priority of its shard jobs.

How to add an extractor: see the package docstring (:mod:`floorscan.walls`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping

from floorscan.walls.cluster import cluster_ransac_rows, import_cluster_modules
from floorscan.walls.params import ClusterParams, RansacParams
from floorscan.walls.ransac import ransac_rows


@dataclass(frozen=True)
class Extractor:
    """One wall extractor of :data:`REGISTRY`.

    Attributes
    ----------
    rows : callable
        ``rows(points, *params, seed)``: the wall segments of one scan, a list of
        ``(x0, y0, x1, y1, n_inliers, rmse_m)`` tuples (metres; see
        :func:`floorscan.walls.tables.segments_frame`). ``points`` is the scan's (N, 2)
        float64 wall points in the map frame, metres (not to be modified); ``params``
        the parameter objects of ``config``, in its order; ``seed`` seeds
        ``numpy.random.default_rng`` (the same seed, the same walls). Called only for
        scans with at least ``RansacParams.min_points`` points; an empty list means
        ``no_wall_found``.
    config : mapping of str to dataclass type
        Its parameter classes by name, in the order ``rows`` takes them, built with
        their defaults (the constants of :mod:`floorscan.walls.params`; no config
        option). Every extractor takes ``ransac``
        (:class:`~floorscan.walls.params.RansacParams`, the segment rules all share).
    cost : float
        Its seconds per scan relative to ransac's; the priority of its
        ``scan_walls_shard`` jobs is derived from it (``workflow/rules/common.smk``),
        so the slower extractor's shards start first.
    prepare : callable or None
        ``prepare(*params)``, called once per job before the first scan is timed
        (imports the extractor makes on its first scan).
    """

    rows: Callable[..., list[tuple]]
    config: Mapping[str, type]
    cost: float
    prepare: Callable[..., None] | None = None


#: The wall extractors by name, in the order of the config's default.
REGISTRY: dict[str, Extractor] = {
    # iterative RANSAC, thesis section 5.3, Algorithm 4 (floorscan.walls.ransac)
    "ransac": Extractor(rows=ransac_rows, config={"ransac": RansacParams}, cost=1.0),
    # clustering RANSAC, thesis section 3.4 (floorscan.walls.cluster): about twice
    # ransac's time a scan
    "cluster_ransac": Extractor(
        rows=cluster_ransac_rows,
        config={"ransac": RansacParams, "cluster_ransac": ClusterParams},
        cost=1.8,
        prepare=import_cluster_modules,
    ),
}

#: Extractor names (config ``walls.extractors``, wildcard ``{extractor}``).
EXTRACTORS = tuple(REGISTRY)

#: The keys of the ``walls`` config section that decide the per-scan walls: the seed
#: and the scan points' height band (:class:`~floorscan.core.wall_points.ScanParams`).
#: The workflow passes only these to the per-scan extraction (``walls_extract_config``,
#: common.smk), so that a change of k or of the orderings does not rerun it.
EXTRACT_KEYS = ("seed", "height_band_m")


def get_extractor(name: str) -> Extractor:
    """The registered extractor ``name``.

    Parameters
    ----------
    name : str
        A key of :data:`REGISTRY` (config ``walls.extractors``).

    Returns
    -------
    Extractor

    Raises
    ------
    ValueError
        When ``name`` is not in :data:`REGISTRY`.
    """
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown extractor {name!r}; expected one of {EXTRACTORS}") from None
