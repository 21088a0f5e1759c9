"""The memory a job will need, known before it is spent: a job whose rasters (sized by
the site's extent) and points (sized by the scans) would not fit in the memory free on
the machine stops before it allocates them, with one message that gives the estimate
and the setting to change, instead of swapping for minutes or being killed halfway.

An estimate is made where the memory is spent, from the numbers known before it is:
the cells of a grid (its extent and cell size) and the points of the scans. Each module
that allocates a raster sized by the site says what a cell costs its job
(:class:`JobMemory`: bytes a cell, the config key of the cell size), e.g. the occupancy
grid being built (:data:`floorscan.core.ray_casting.COUNTS_BYTES_PER_CELL`), and
:func:`check_memory` compares the estimate with the memory the kernel says is
available (``MemAvailable`` of ``/proc/meminfo``: free memory and the caches it can
drop). The figures behind the bytes per cell are in ``benchmarks/README.md``.

The estimate is of what the job is about to allocate: what it holds already (the
interpreter, the imports, the points it read) is no longer in the free memory.

Usage::

    job = JobMemory(bytes_per_cell=24, key="walls.map.support_cell_m")
    job.check("the occupancy grid of the 815 kept scans", (rows, columns), 0.05)  # or raises
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from floorscan.core.io import InputError


class MemoryEstimateError(InputError):
    """A job would need more memory than the machine has free (:func:`check_memory`)."""


@dataclass(frozen=True)
class JobMemory:
    """What a job's rasters cost per cell of its grid and its work per point of the scans,
    and the setting that sizes the cells.

    Attributes
    ----------
    bytes_per_cell : float
        Peak bytes of the job's rasters per cell of its grid (the arrays of the grid's
        shape the job holds at once).
    key : str
        The config key of the cell size, e.g. ``walls.map.support_cell_m``.
    bytes_per_point : float
        Peak bytes the job's work on the scans' points takes per point, beyond the
        points it holds already (e.g. the map extractor's support test and thinning).
    """

    bytes_per_cell: float
    key: str
    bytes_per_point: float = 0.0

    def check(
        self, what: str, shape: tuple[int, int], cell_m: float, more: Mapping[str, float] | None = None,
        free: int | None = None, points: int = 0,
    ) -> float:
        """:func:`check_memory` of a grid of ``shape`` cells of ``cell_m`` metres and
        ``points`` points.

        Parameters
        ----------
        what : str
            The grid and whose scans, for the message.
        shape : (int, int)
            Rows, columns.
        cell_m : float
            Cell size, metres.
        more : mapping of str to float, optional
            Other parts the job is about to allocate (the scans' points), bytes.
        free : int, optional
            As :func:`check_memory`.
        points : int
            The points the job works on.

        Returns
        -------
        float
            The estimate, bytes: ``rows * columns * bytes_per_cell``, ``points *
            bytes_per_point`` (when not 0) and ``more``.

        Raises
        ------
        MemoryEstimateError
            As :func:`check_memory`.
        """
        h, w = (int(n) for n in shape)
        grid = f"{w} x {h} cells of {cell_m:g} m x {self.bytes_per_cell:g} bytes"
        need = {grid: float(h) * w * self.bytes_per_cell}
        if self.bytes_per_point and points:
            need[f"{points / 1e6:.3g} M points x {self.bytes_per_point:g} bytes"] = float(points) * self.bytes_per_point
        need.update(more or {})
        return check_memory(what, need, f"{self.key} (now {cell_m:g} m)", free)


def free_memory_bytes() -> int | None:
    """The memory available to a new allocation: ``MemAvailable`` of ``/proc/meminfo``.

    Returns
    -------
    int or None
        Bytes; None where the kernel does not say (not Linux): no check.
    """
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_memory(what: str, need: Mapping[str, float], option: str, free: int | None = None) -> float:
    """Stop a job whose estimate exceeds the memory free on the machine, before it is spent.

    Parameters
    ----------
    what : str
        What needs the memory and whose data (``the occupancy grid of the 815 kept
        scans of dataset 'acapulco'``).
    need : mapping of str to float
        What the job is about to allocate, by part, bytes.
    option : str
        The setting that makes it smaller, with its value (``walls.map.support_cell_m
        (0.05 m)``).
    free : int, optional
        Bytes free; default :func:`free_memory_bytes` (no check when unknown).

    Returns
    -------
    float
        The estimate, bytes.

    Raises
    ------
    MemoryEstimateError
        When the estimate exceeds ``free``: one paragraph with the estimate by part,
        the memory free, and the setting to change.
    """
    total = float(sum(need.values()))
    free = free_memory_bytes() if free is None else free
    if free is None or total <= free:
        return total
    parts = ", ".join(f"{name} {b / 1e9:.2f} GB" for name, b in need.items())
    raise MemoryEstimateError(
        f"{what} would need about {total / 1e9:.2f} GB more memory ({parts}), more than the {free / 1e9:.2f} GB "
        f"free on this machine: stopped before allocating it. Make the cells coarser with {option}: twice the cell "
        "size takes a quarter of the cells; or run fewer jobs at once (--cores 1), or on a machine with more memory."
    )
