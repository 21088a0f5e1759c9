"""What the walls are scored against: the simulator's ground truth on synthetic
datasets, the reference on real recordings (the walls of the same extractor from all
kept scans, as the thesis does in section 5.4; never called ground truth).

:func:`load_references` gives the walls precision and the bitmap metrics are measured
against, :func:`load_recall_references` those recall is measured against (on synthetic
datasets the observed parts of the faces, thesis 5.2: walls never visible from the
LIDAR cannot be recovered). :data:`~floorscan.core.score_tables.GROUND_TRUTH` and
:data:`~floorscan.core.score_tables.REFERENCE` are the values
of the ``reference_kind`` column, :func:`reference_label` their wording in captions.
"""

from __future__ import annotations

from floorscan.core.score_tables import GROUND_TRUTH
from floorscan.score.geojson import read_wall_faces
from floorscan.core.segments import as_segments

#: Ground-truth feature kind of the observed parts of the faces (recall's reference).
OBSERVED_FACE = "observed_face"


def reference_label(kind: str) -> str:
    """What the walls are scored against, in words for captions and the summary: the
    simulator's walls for ``kind`` :data:`GROUND_TRUTH`, otherwise the reference, never
    called ground truth (a real recording's building has no architectural plan).

    Parameters
    ----------
    kind : str
        The dataset's reference kind.

    Returns
    -------
    str
    """
    if kind == GROUND_TRUTH:
        return "the simulator's ground-truth walls (faces of sim/walls.geojson)"
    return (
        "the reference, the walls extracted by the same extractor from all kept scans "
        "(a reference, not ground truth: the building has no architectural plan)"
    )


def load_recall_references(kind: str, extractors, ground_truth=None, recall_kind: str = OBSERVED_FACE):
    """What recall is measured against.

    Synthetic datasets (``kind`` ground_truth): the ``recall_kind`` features of
    ``walls.geojson`` (``observed_face``: the parts of the faces the recording saw,
    :func:`floorscan.sim.ground_truth.observed_faces`); ``face`` gives None (recall against
    all faces, like precision). Real recordings: None (the reference is already made
    of what the scans saw).

    Parameters
    ----------
    kind : str
    extractors : iterable of str
    ground_truth : path, optional
        The simulator's ``walls.geojson``.
    recall_kind : str

    Returns
    -------
    dict of str to (M, 4) float64 ndarray, or None
        The same segments (metres) for every extractor.

    Raises
    ------
    floorscan.core.io.InputError
        As :func:`~floorscan.score.geojson.read_wall_faces`.
    """
    if kind != GROUND_TRUTH or recall_kind == "face":
        return None
    seg = read_wall_faces(ground_truth, kind=recall_kind)
    return {e: seg for e in extractors}


def load_references(kind: str, extractors, ground_truth=None, reference_paths=()) -> dict:
    """The walls each extractor is scored against.

    ``kind`` ground_truth: the ``face`` features of the simulator's ``walls.geojson``
    (``ground_truth``), the same for every extractor. Otherwise the reference: the
    walls of each extractor from all kept scans (``reference_paths``, one Parquet
    table per extractor, in the order of ``extractors``).

    Parameters
    ----------
    kind : str
    extractors : iterable of str
    ground_truth : path, optional
    reference_paths : sequence of path

    Returns
    -------
    dict of str to (M, 4) float64 ndarray
        Segments, metres.
    """
    extractors = list(extractors)
    if kind == GROUND_TRUTH:
        gt = read_wall_faces(ground_truth, kind="face")
        return {e: gt for e in extractors}
    from floorscan.core.io import read_table

    return {e: as_segments(read_table(p)) for e, p in zip(extractors, reference_paths)}
