"""How well the vehicles' paths cover the area: each path's swath (a strip one lane spacing
wide, centred on the path) rasterised on a grid of the area's cells, and the cells counted.

The grid is the area's own frame (``along`` x ``across``), cells of about :data:`CELL_M`
(finer for a lane spacing under 20 m, coarser for an area of more than :data:`MAX_CELLS`
cells), tiling the area exactly; a cell counts as covered by a vehicle when its centre is
within half a lane spacing of that vehicle's path. Overlap: cells covered by more than one
vehicle (a vehicle crossing its own swath is not an overlap); gap: cells covered by none.
Only the area is counted: a swath beyond its edges covers nothing of it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt

from backend.authoring.survey.area import AreaFrame, SurveyArea

#: Target cell size (m), and at most this fraction of a lane spacing.
CELL_M: Final = 1.0
CELLS_PER_SPACING: Final = 20
#: Most cells of a grid (cells are made coarser beyond: ~32 MB of counts at most).
MAX_CELLS: Final = 4_000_000

Track = tuple[Sequence[float], Sequence[float]]


@dataclass(frozen=True, slots=True)
class Coverage:
    """The area's cells by how many vehicles' swaths cover them (areas in m^2)."""

    cell_along_m: float
    cell_across_m: float
    area_m2: float
    covered_m2: float
    overlap_m2: float
    gap_m2: float
    #: Each vehicle's swath inside the area (m^2), in the vehicles' order.
    vehicle_m2: tuple[float, ...]

    @property
    def covered_fraction(self) -> float:
        return self.covered_m2 / self.area_m2

    @property
    def overlap_fraction(self) -> float:
        return self.overlap_m2 / self.area_m2

    @property
    def gap_fraction(self) -> float:
        return self.gap_m2 / self.area_m2


def cell_size_m(area: SurveyArea) -> float:
    """The grid's target cell size (m): see the module doc."""
    fine = min(CELL_M, area.lane_spacing_m / CELLS_PER_SPACING)
    return max(fine, math.sqrt(area.length_m * area.width_m / MAX_CELLS))


def coverage(
    area: SurveyArea, frame: AreaFrame, tracks: Sequence[Track], swath_m: float
) -> Coverage:
    """The coverage of ``area`` by the ``tracks`` (NED ``(xs, ys)``, one per vehicle), each
    with a swath ``swath_m`` wide."""
    cell = cell_size_m(area)
    n_along = max(1, math.ceil(area.length_m / cell - 1e-9))
    n_across = max(1, math.ceil(area.width_m / cell - 1e-9))
    d_along, d_across = area.length_m / n_along, area.width_m / n_across
    counts = np.zeros((n_along, n_across), dtype=np.uint8)
    vehicle_cells: list[int] = []
    for xs, ys in tracks:
        mask = np.zeros_like(counts, dtype=bool)
        local = [frame.to_local(x, y) for x, y in zip(xs, ys, strict=True)]
        for (a0, c0), (a1, c1) in zip(local, local[1:] or local, strict=False):
            _paint(mask, (a0, c0), (a1, c1), swath_m / 2.0, d_along, d_across)
        counts += mask
        vehicle_cells.append(int(mask.sum()))
    cell_m2 = d_along * d_across
    return Coverage(
        d_along,
        d_across,
        area.length_m * area.width_m,
        int(np.count_nonzero(counts)) * cell_m2,
        int(np.count_nonzero(counts > 1)) * cell_m2,
        int(np.count_nonzero(counts == 0)) * cell_m2,
        tuple(n * cell_m2 for n in vehicle_cells),
    )


def _paint(
    mask: npt.NDArray[np.bool_],
    p0: tuple[float, float],
    p1: tuple[float, float],
    radius_m: float,
    d_along: float,
    d_across: float,
) -> None:
    """Mark the cells whose centre is within ``radius_m`` of the segment ``p0``-``p1``
    (``(along, across)`` m)."""
    (a0, c0), (a1, c1) = p0, p1
    i0, i1 = _span(min(a0, a1) - radius_m, max(a0, a1) + radius_m, d_along, mask.shape[0])
    j0, j1 = _span(min(c0, c1) - radius_m, max(c0, c1) + radius_m, d_across, mask.shape[1])
    if i0 >= i1 or j0 >= j1:
        return
    along = ((np.arange(i0, i1) + 0.5) * d_along)[:, None] - a0
    across = ((np.arange(j0, j1) + 0.5) * d_across)[None, :] - c0
    da, dc = a1 - a0, c1 - c0
    length2 = da * da + dc * dc
    if length2 > 0.0:
        t = np.clip((along * da + across * dc) / length2, 0.0, 1.0)
        along = along - t * da
        across = across - t * dc
    mask[i0:i1, j0:j1] |= along * along + across * across <= radius_m * radius_m


def _span(lo_m: float, hi_m: float, cell_m: float, n: int) -> tuple[int, int]:
    """The cell indices whose centres may lie in ``[lo_m, hi_m]``, within the grid."""
    return max(0, math.floor(lo_m / cell_m)), min(n, math.ceil(hi_m / cell_m) + 1)
