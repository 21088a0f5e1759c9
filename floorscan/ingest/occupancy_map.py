"""An occupancy map as a recording: a ROS map_server map (``map.yaml`` and its image) or
an image on its own, read into the occupancy grid the walls and rooms read
(:class:`floorscan.core.occupancy.OccupancyGrid`).

What a map gives is the grid alone: no scans, no poses, no time. The plan is built on
it as on the grid of the selected scans (walls fitted on its occupied cells, rooms in
its free space); registration, selection, the scan list and the reduced recording do
not exist for a map.

The image is read as ROS map_server reads it (``map_server/src/image_loader.cpp``; Nav2
``nav2_map_server/src/map_io.cpp``):

- each pixel's shade is the mean of its colour channels, 0..255 (``negate: 1`` turns it
  round); its occupancy ``occ = (255 - shade) / 255``;
- ``mode: trinary`` (the default): occupied when ``occ > occupied_thresh``, free when
  ``occ < free_thresh``, unknown between; ``mode: scale``: the same classes (the cells
  in between, which map_server scales to 1..99, are neither free nor occupied for a
  floor plan, so they are unknown here too); ``mode: raw``: the shade is the occupancy
  in percent (0..100), anything above 100 (map_server's 255) unknown, and the thresholds
  classify it;
- row 0 of the image is the top of the map: the bottom-left pixel's corner is at
  ``origin`` (x, y, metres; the map frame is map_server's, so the plan lies on the map
  in RViz).

An image on its own gives no thresholds: its free threshold is found from its shades
(:func:`image_free_thresh`), so an unknown grey that is not exactly map_saver's 205 is
not read as floor.

One choice differs from map_server: map_server's trinary mode averages an image's alpha
channel in with its colours (kept there "to preserve existing behavior"), which reads an
opaque black pixel of a grey-and-alpha PNG as unknown. Here the colours alone give the
shade, and a transparent pixel (alpha 0) is unknown, as in map_server's scale mode.

The grid holds each class as scan counts
(:func:`floorscan.core.occupancy_classes.grid_of_classes`): an occupied cell as hit by
``min_scans`` scans, a free cell as crossed by the fewest scans that make it free, so
every consumer of the grid reads the map's classes unchanged.

Bad maps raise :class:`~floorscan.core.io.InputError` naming the file and what was
expected: a yaml that is not a map_server yaml, its image missing, a resolution that is
not a positive number, an unknown ``mode``, thresholds out of order, an image of one
value, an image with no free or no occupied cell, a colour photograph.

Usage::

    grid, info = read_occupancy_map("map.yaml")            # map_server yaml
    grid, info = read_occupancy_map("floor.png", 0.05)     # an image, 5 cm a pixel
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from floorscan.core.io import InputError
from floorscan.core.map_info import MapInfo
from floorscan.core.messages import quoted
from floorscan.core.occupancy import OccupancyGrid
from floorscan.core.occupancy_classes import grid_of_classes

#: File suffixes of a map_server yaml and of a map image read on its own.
MAP_YAML_SUFFIXES = (".yaml", ".yml")
MAP_IMAGE_SUFFIXES = (".pgm", ".png")
#: map_server's modes.
MAP_MODES = ("trinary", "scale", "raw")
#: map_server's defaults (its tutorials' and Nav2's): thresholds on ``occ``, not negated.
DEFAULT_OCCUPIED_THRESH = 0.65
DEFAULT_FREE_THRESH = 0.196
#: An image has an unknown grey when its most common shade between map_server's default
#: thresholds covers at least this share of its pixels: the outside of a building is a
#: region, while the greys of a black-and-white drawing's antialiased edges are a few
#: pixels each.
UNKNOWN_MIN_SHARE = 0.01
#: The cell size of an image read on its own, metres (ROS maps' usual 5 cm).
DEFAULT_RESOLUTION_M = 0.05
#: A pixel is coloured when its channels differ by more than this (of 255): more than
#: the rounding of a grey drawn in RGB ...
COLOUR_SPREAD = 16
#: ... and an image is a colour photograph, not a map, when more than this share of its
#: pixels is coloured. A map is grey (map_server averages the channels: colour carries
#: nothing); a map with coloured annotations has a few per cent of them.
COLOUR_SHARE = 0.25

EXPECTED = (
    "expected a ROS map_server yaml (image, resolution, origin, negate, occupied_thresh, free_thresh, mode) "
    "or a greyscale map image (.pgm, .png: dark occupied, white free, grey unknown)"
)


def is_map_path(path: str | Path) -> bool:
    """Whether ``path`` names a map by its suffix: a map image (:data:`MAP_IMAGE_SUFFIXES`)
    or a yaml (:data:`MAP_YAML_SUFFIXES`) with an ``image`` key.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    bool
        False for a folder, a missing file, or a yaml that is not a map_server one
        (a config file, a ROS2 bag's ``metadata.yaml``).
    """
    path = Path(path)
    if not path.is_file():
        return False
    suffix = path.suffix.lower()
    if suffix in MAP_IMAGE_SUFFIXES:
        return True
    if suffix in MAP_YAML_SUFFIXES:
        try:
            doc = _load_yaml(path)
        except InputError:
            return False
        return isinstance(doc, dict) and "image" in doc
    return False


def map_images(path: str | Path) -> list[Path]:
    """The image a map_server yaml names (resolved beside it), when it names one.

    Parameters
    ----------
    path : str or Path
        A map_server yaml.

    Returns
    -------
    list of Path
        One path, or none for a yaml that cannot be read or names no image.
    """
    path = Path(path)
    try:
        doc = _load_yaml(path)
    except InputError:
        return []
    image = doc.get("image") if isinstance(doc, dict) else None
    return [_beside(path, image)] if isinstance(image, str) and image.strip() else []


def _beside(yaml_path: Path, image: str) -> Path:
    """The image a map_server yaml names, resolved as map_server resolves it: beside the yaml."""
    return Path(image) if Path(image).is_absolute() else yaml_path.parent / image


def read_occupancy_map(path: str | Path, resolution_m: float | None = None) -> tuple[OccupancyGrid, MapInfo]:
    """Read a map_server map or a map image into an occupancy grid (see the module
    docstring).

    Parameters
    ----------
    path : str or Path
        A map_server yaml (its ``image`` resolved beside it), or a ``.pgm`` / ``.png``
        image read with ``resolution_m``, origin 0, map_server's default occupied
        threshold and a free threshold from its own shades (:func:`image_free_thresh`).
    resolution_m : float, optional
        Metres a pixel of an image on its own (default :data:`DEFAULT_RESOLUTION_M`);
        not allowed with a yaml, which has its own.

    Returns
    -------
    grid : OccupancyGrid
        Cells of the map's resolution, row 0 at the bottom of the image; classes as
        :func:`~floorscan.core.occupancy_classes.grid_of_classes`.
    info : MapInfo

    Raises
    ------
    InputError
        For a bad map (the module docstring lists them), naming the file and what was
        expected.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: map not found; {EXPECTED}")
    defaults: list[str] = []
    if path.suffix.lower() in MAP_YAML_SUFFIXES:
        if resolution_m is not None:
            raise InputError(f"{path}: resolution_m is for a map image on its own; a map_server yaml gives its own resolution")
        meta = _map_yaml(path, defaults)
    elif path.suffix.lower() in MAP_IMAGE_SUFFIXES:
        res = DEFAULT_RESOLUTION_M if resolution_m is None else resolution_m
        meta = {"image": path, "resolution": _resolution(res, f"{path}: resolution_m"), "origin": (0.0, 0.0, 0.0),
                "negate": False, "occupied_thresh": DEFAULT_OCCUPIED_THRESH, "free_thresh": DEFAULT_FREE_THRESH,
                "mode": "trinary"}  # fmt: skip
    else:
        raise InputError(f"{path}: not a map (suffix {quoted(path.suffix or 'none', 20)}); {EXPECTED}")
    occ, known = _occupancy(meta["image"], meta["negate"], meta["mode"], where=path)
    if path.suffix.lower() in MAP_IMAGE_SUFFIXES:  # an image gives no thresholds: its shades do
        meta["free_thresh"] = image_free_thresh(occ, known, meta["free_thresh"], meta["occupied_thresh"])
    occupied = known & (occ > meta["occupied_thresh"])
    free = known & (occ < meta["free_thresh"])
    _check_classes(path, meta["image"], occ, known, occupied, free)
    x0, y0, yaw = meta["origin"]
    grid = grid_of_classes(occupied[::-1], free[::-1], (x0, y0), meta["resolution"])
    h, w = occupied.shape
    info = MapInfo(
        path=str(path), image=str(meta["image"]), mode=meta["mode"], resolution_m=meta["resolution"],
        origin_x_m=x0, origin_y_m=y0, origin_yaw_rad=yaw, negate=meta["negate"],
        occupied_thresh=meta["occupied_thresh"], free_thresh=meta["free_thresh"], width=w, height=h,
        n_occupied=int(occupied.sum()), n_free=int(free.sum()), n_unknown=int(h * w - occupied.sum() - free.sum()),
        defaults=tuple(defaults),
    )  # fmt: skip
    return grid, info


def image_free_thresh(occ: np.ndarray, known: np.ndarray, free_thresh: float, occupied_thresh: float) -> float:
    """The free threshold of a map that gives none, from its own shades.

    A map image has three shades, one per class; map_saver writes 254 (free), 205
    (unknown) and 0 (occupied), and map_server's default ``free_thresh`` (0.196, a shade
    of 205.02) falls a hair above its unknown grey. An image whose unknown grey is not
    exactly 205 (a photographed, scaled or re-encoded map: its grey spreads over 200-215)
    is half read as free, and the unknown outside becomes floor. So the threshold
    between free and unknown is placed midway between the two shades' modes (the
    nearest-mode rule): the unknown grey is the most common shade in map_server's
    unknown band (between the default thresholds), the free shade the most common one
    brighter than it.

    Parameters
    ----------
    occ : (H, W) float ndarray
        Occupancy ``(255 - shade) / 255``.
    known : (H, W) bool ndarray
    free_thresh, occupied_thresh : float
        The thresholds the map would be read with (map_server's defaults).

    Returns
    -------
    float
        The free threshold on ``occ``; ``free_thresh`` when the image has no unknown
        grey (fewer than :data:`UNKNOWN_MIN_SHARE` of its pixels in the band).
    """
    shade = np.rint(255.0 * (1.0 - occ[known])).astype(np.int64).clip(0, 255)
    counts = np.bincount(shade, minlength=256)
    lo, hi = math.ceil(255.0 * (1.0 - occupied_thresh)), math.floor(255.0 * (1.0 - free_thresh))
    if hi < lo or not shade.size:
        return free_thresh
    unknown = lo + int(np.argmax(counts[lo : hi + 1]))
    if counts[unknown] < UNKNOWN_MIN_SHARE * shade.size:
        return free_thresh
    free = unknown + 1 + int(np.argmax(counts[unknown + 1 :]))
    return (255.0 - (unknown + free) / 2.0) / 255.0


def _load_yaml(path: Path):
    import yaml

    try:
        return yaml.safe_load(path.read_text(encoding="utf-8", errors="replace"))
    except (yaml.YAMLError, OSError) as e:
        raise InputError(f"{path}: not a readable yaml ({str(e).splitlines()[0]}); {EXPECTED}") from None


def _map_yaml(path: Path, defaults: list[str]) -> dict:
    """The map_server keys of ``path``, checked; missing optional ones take map_server's
    defaults (named in ``defaults``)."""
    doc = _load_yaml(path)
    if not isinstance(doc, dict) or "image" not in doc:
        raise InputError(f"{path}: a yaml without an 'image' key, so not a map_server map; {EXPECTED}")
    image = doc["image"]
    if not isinstance(image, str) or not image.strip():
        raise InputError(f"{path}: image: expected the map image's file name, got {quoted(image, 60)}")
    image_path = _beside(path, image)
    if not image_path.is_file():
        raise InputError(f"{path}: its image {quoted(image, 80)} does not exist (looked for {image_path})")
    if "resolution" not in doc:
        raise InputError(f"{path}: no 'resolution' (metres a pixel); {EXPECTED}")
    meta = {"image": image_path, "resolution": _resolution(doc["resolution"], f"{path}: resolution")}
    origin = doc.get("origin", None)
    if origin is None:
        defaults.append("origin")
        origin = [0.0, 0.0, 0.0]
    if not isinstance(origin, (list, tuple)) or len(origin) not in (2, 3) or not all(_is_number(v) for v in origin):
        raise InputError(f"{path}: origin: expected [x, y, yaw] in metres and radians, got {quoted(origin, 60)}")
    origin = [float(v) for v in origin] + [0.0] * (3 - len(origin))
    if not all(math.isfinite(v) for v in origin):
        raise InputError(f"{path}: origin: expected finite numbers, got {origin}")
    if abs(origin[2]) > 1e-9:
        raise InputError(
            f"{path}: origin yaw {origin[2]} rad: a rotated map is not supported (most of ROS ignores the yaw "
            "too); rotate the image and set the yaw to 0"
        )
    meta["origin"] = tuple(origin)
    for key, default in (("negate", 0), ("occupied_thresh", DEFAULT_OCCUPIED_THRESH), ("free_thresh", DEFAULT_FREE_THRESH)):
        if key not in doc:
            defaults.append(key)
        value = doc.get(key, default)
        if not _is_number(value):
            raise InputError(f"{path}: {key}: expected a number, got {quoted(value, 40)}")
        meta[key] = float(value)
    if meta["negate"] not in (0.0, 1.0):
        raise InputError(f"{path}: negate: expected 0 or 1, got {doc['negate']}")
    meta["negate"] = bool(meta["negate"])
    if not 0.0 <= meta["free_thresh"] < meta["occupied_thresh"] <= 1.0:
        raise InputError(
            f"{path}: expected 0 <= free_thresh < occupied_thresh <= 1, got free_thresh {meta['free_thresh']}, "
            f"occupied_thresh {meta['occupied_thresh']}"
        )
    mode = doc.get("mode", "trinary")
    if "mode" not in doc:
        defaults.append("mode")
    if not isinstance(mode, str) or mode.lower() not in MAP_MODES:
        raise InputError(f"{path}: mode {quoted(mode, 40)}: expected one of {', '.join(MAP_MODES)}")
    meta["mode"] = mode.lower()
    return meta


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _shown(value) -> str:
    """A number as written, anything else quoted (:func:`~floorscan.core.messages.quoted`)."""
    return f"{value:g}" if _is_number(value) else quoted(value, 40)


def _resolution(value, where: str) -> float:
    if not _is_number(value) or not math.isfinite(float(value)) or float(value) <= 0:
        raise InputError(f"{where}: expected a positive number of metres a pixel, got {_shown(value)}")
    return float(value)


def _occupancy(image: Path, negate: bool, mode: str, where: Path) -> tuple[np.ndarray, np.ndarray]:
    """The image's occupancy in [0, 1] (raw: percent / 100) and which pixels are known
    (not transparent; raw: at most 100), row 0 at the top."""
    from PIL import Image, UnidentifiedImageError

    named = f"{where}" if where == image else f"{where}: its image {image}"
    try:
        with Image.open(image) as im:
            im.load()
            if im.mode in ("I;16", "I;16B", "I;16L", "I", "F"):  # 16-bit or float grey: scaled to 0..255
                a = np.asarray(im, dtype=np.float64)
                a = (a * (255.0 / max(float(a.max()), 1.0)) if a.max() > 255 else a)[..., None]
                bands = ("L",)
            else:
                if im.mode not in ("1", "L", "LA", "RGB", "RGBA"):  # a palette, CMYK, ...
                    im = im.convert("RGBA")
                bands = im.getbands()
                a = np.asarray(im)  # 8 bits a channel: kept so (a 4.7 M-pixel RGBA map: 19 MB, not 150)
                a = a.astype(np.uint8) * np.uint8(255) if im.mode == "1" else a
                a = a[..., None] if a.ndim == 2 else a
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as e:
        raise InputError(f"{named}: not an image that can be read ({e}); {EXPECTED}") from None
    if a.shape[0] < 2 or a.shape[1] < 2:
        raise InputError(f"{named}: an image of {a.shape[1]} x {a.shape[0]} pixels; a map needs at least 2 x 2")
    alpha = "A" in bands
    colour = a[..., :3] if a.shape[2] >= 3 else a[..., :1]
    known = a[..., -1] > 0 if alpha else np.ones(a.shape[:2], dtype=bool)
    if colour.shape[2] == 3:
        spread = colour.max(axis=2) - colour.min(axis=2)
        share = float((spread[known] > COLOUR_SPREAD).mean()) if known.any() else 0.0
        if share > COLOUR_SHARE:
            raise InputError(
                f"{named}: {share:.0%} of its pixels are coloured, so it is a colour picture, not an occupancy "
                f"map; {EXPECTED}"
            )
    shade = colour.sum(axis=2, dtype=np.float64) / colour.shape[2]
    if negate:
        shade = 255.0 - shade
    if mode == "raw":
        known &= shade <= 100.0
        return shade / 100.0, known
    return (255.0 - shade) / 255.0, known


def _check_classes(path: Path, image: Path, occ, known, occupied, free) -> None:
    named = f"{path}" if path == image else f"{path}: its image {image}"
    values = occ[known]
    if not len(values) or values.min() == values.max():
        what = "every pixel is transparent" if not known.any() else "every pixel has one value"
        raise InputError(f"{named}: {what}, so there is no free space and no wall to make a plan of; {EXPECTED}")
    if not free.any():
        raise InputError(
            f"{named}: no free pixel (occupancy below free_thresh), so no room; {EXPECTED}; check negate and the thresholds"
        )
    if not occupied.any():
        raise InputError(
            f"{named}: no occupied pixel (occupancy above occupied_thresh), so no wall; {EXPECTED}; check negate and "
            "the thresholds"
        )


def write_map_ingest(
    path: str | Path, resolution_m: float | None, grid_path: str | Path, pgm_path: str | Path,
    yaml_path: str | Path, info_path: str | Path,
) -> MapInfo:  # fmt: skip
    """Rule ``map_ingest``: read a map (:func:`read_occupancy_map`) and write its grid,
    the map as read (a map_server map, ``mode: trinary``: the classes the plan is built
    on, at the map's origin and resolution, so the plan lies on it in RViz) and what
    was read.

    Parameters
    ----------
    path : str or Path
        The map_server yaml or the image.
    resolution_m : float or None
        Metres a pixel of an image on its own (None: :data:`DEFAULT_RESOLUTION_M`).
    grid_path : path
        Output: the grid (:func:`floorscan.core.occupancy.write_grid`, metadata
        ``source`` ``map``).
    pgm_path, yaml_path : path
        Output: ``map.pgm`` and ``map.yaml``.
    info_path : path
        Output: :meth:`MapInfo.as_dict` as JSON.

    Returns
    -------
    MapInfo

    Raises
    ------
    InputError
        For a bad map (:func:`read_occupancy_map`); nothing is written then.
    """
    import json

    from floorscan.core.files import atomic_path
    from floorscan.core.occupancy import write_grid, write_map_server

    grid, info = read_occupancy_map(path, resolution_m)
    write_grid(grid, grid_path, metadata={"source": "map"})
    write_map_server(grid, pgm_path, yaml_path, title=f"occupancy map {Path(path).name}")
    with atomic_path(info_path) as tmp:
        Path(tmp).write_text(json.dumps(info.as_dict(), indent=1) + "\n", encoding="utf-8")
    return info
