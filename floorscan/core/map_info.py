"""What was read of an occupancy map, as the later stages and the pages read it: the
ingest stage's :func:`floorscan.ingest.occupancy_map.write_map_ingest` writes
:class:`MapInfo` to ``map/map.json``; :func:`read_map_info` reads it back and
:func:`map_line` says it in one line."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path


@dataclass(frozen=True)
class MapInfo:
    """What was read of a map (the ingest log, ``summary.md``).

    Attributes
    ----------
    path, image : str
        The file given and the image read (the same for an image on its own).
    mode : str
        ``trinary``, ``scale`` or ``raw``.
    resolution_m : float
        Metres a pixel.
    origin_x_m, origin_y_m, origin_yaw_rad : float
        The bottom-left pixel's corner in the map frame.
    negate : bool
    occupied_thresh, free_thresh : float
    width, height : int
        Pixels.
    n_occupied, n_free, n_unknown : int
        Cells of each class.
    defaults : tuple of str
        The yaml keys that were missing and took map_server's defaults.
    """

    path: str
    image: str
    mode: str
    resolution_m: float
    origin_x_m: float
    origin_y_m: float
    origin_yaw_rad: float
    negate: bool
    occupied_thresh: float
    free_thresh: float
    width: int
    height: int
    n_occupied: int
    n_free: int
    n_unknown: int
    defaults: tuple = ()

    def as_dict(self) -> dict:
        """The fields as a JSON-ready dict (``defaults`` a list)."""
        return {**asdict(self), "defaults": list(self.defaults)}


def read_map_info(path: str | Path) -> dict:
    """What :func:`write_map_ingest` wrote of a map (``map/map.json``).

    Parameters
    ----------
    path : path

    Returns
    -------
    dict
        :meth:`MapInfo.as_dict`.

    Raises
    ------
    OSError, ValueError
        When the file cannot be read as JSON.
    """
    import json

    return json.loads(Path(path).read_text(encoding="utf-8"))


def map_line(info: MapInfo | dict) -> str:
    """What was read of a map, in one line (the ingest log, the answer, ``summary.md``).

    Parameters
    ----------
    info : MapInfo or dict
        :class:`MapInfo` or its :meth:`~MapInfo.as_dict`.

    Returns
    -------
    str
        E.g. ``occupancy map map.yaml (image map.pgm, mode trinary): 1202 x 786 cells of
        0.05 m, origin (-12.2, -10.0) m; 16505 occupied, 161555 free, 766712 unknown``.
    """
    d = info.as_dict() if isinstance(info, MapInfo) else dict(info)
    image = Path(d["image"]).name
    source = Path(d["path"]).name
    where = f"{source} (image {image}, mode {d['mode']})" if image != source else f"{source} (an image on its own)"
    text = (
        f"occupancy map {where}: {d['width']} x {d['height']} cells of {d['resolution_m']:g} m, origin "
        f"({d['origin_x_m']:g}, {d['origin_y_m']:g}) m; {d['n_occupied']} occupied, {d['n_free']} free, "
        f"{d['n_unknown']} unknown"
    )
    if d.get("defaults"):
        text += f"; map_server's defaults for {', '.join(d['defaults'])}"
    return text
