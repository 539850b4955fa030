"""The area's lanes split into blocks, one per vehicle, and which vehicle takes which block.

Blocks are contiguous groups of lanes, numbered across from the area's origin side, each an
even number of lanes where the count allows (a lawnmower flies out-and-back pairs): with an
odd number of lanes one edge block has one more, and the extra lane its lawnmower must fly
then lies outside the area (its entry is chosen so). A block is entered at one of two
corners: its first lane's start, heading along the lanes (``from_end`` false), or its last
lane's far end, heading back (``from_end`` true); either way the lawnmower's next lanes are to
starboard, inside the block.

Which vehicle takes which block, and from which corner, minimises the time to finish: the
largest of the vehicles' distances to fly (the Dubins transit from where the vehicle is, at
the survey speed's turn radius, plus its block's lanes), then their sum, exactly (a bottleneck
assignment, then a minimum-cost one among the assignments that keep that largest: up to 15
vehicles, well under a millisecond). Distances, not durations: every vehicle flies at the
survey's one speed, so they order the same way; the durations shown are the twin's
(:mod:`backend.authoring.durations`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from backend.authoring.survey.area import AreaFrame, SentArea, SurveyArea, SurveyVehicle
from planner import turn_radius_m
from planner._geometry import dubins


@dataclass(frozen=True, slots=True)
class Block:
    """Lanes ``first_lane`` to ``first_lane + lane_count - 1`` of the area (indices into
    :func:`backend.authoring.survey.area.area_lanes`), block ``index`` across."""

    index: int
    first_lane: int
    lane_count: int

    @property
    def last_lane(self) -> int:
        return self.first_lane + self.lane_count - 1

    @property
    def laps(self) -> int:
        """The lawnmower's laps: out-and-back pairs covering the block (one lane more for an
        odd block)."""
        return (self.lane_count + 1) // 2


@dataclass(frozen=True, slots=True)
class Entry:
    """Where and how a block's lawnmower must take effect (the pattern starts where the
    vehicle is, along its heading): the area frame's ``along_m``/``across_m``, and NED."""

    from_end: bool
    along_m: float
    across_m: float
    x_m: float
    y_m: float
    heading_deg: float


@dataclass(frozen=True, slots=True)
class Assignment:
    """A vehicle's block, the corner it enters it from, and its distance to fly (m)."""

    block: Block
    entry: Entry
    transit_m: float
    lanes_m: float

    @property
    def cost_m(self) -> float:
        return self.transit_m + self.lanes_m


def block_sizes(lanes: int, vehicles: int) -> tuple[int, ...]:
    """Lanes per block, across: pairs shared as evenly as they go (the first blocks take the
    spare pairs), the odd lane, if any, to the last block (one of the fewest pairs)."""
    pairs, odd = divmod(lanes, 2)
    base, spare = divmod(pairs, vehicles)
    sizes = [2 * (base + (1 if i < spare else 0)) for i in range(vehicles)]
    sizes[-1] += odd
    return tuple(sizes)


def blocks_of(sizes: Sequence[int]) -> tuple[Block, ...]:
    out: list[Block] = []
    first = 0
    for i, size in enumerate(sizes):
        out.append(Block(i, first, size))
        first += size
    return tuple(out)


def entries(
    block: Block,
    n_blocks: int,
    lanes: Sequence[float],
    area: SurveyArea,
    sent: SentArea,
    frame: AreaFrame,
) -> tuple[Entry, ...]:
    """The corners ``block`` may be entered from: both for an even block; for an odd one the
    corner whose extra lane falls outside the area (the last block from the start, the first
    from the far end). Each is moved to centre the lanes flown at the sent spacing and sweep
    length on the block's lanes and the area's length."""
    odd = block.lane_count % 2 == 1
    across_shift = (block.lane_count - 1) * (area.lane_spacing_m - sent.lane_spacing_m) / 2.0
    along_shift = (area.length_m - sent.length_m) / 2.0
    out: list[Entry] = []
    if not odd or block.index == n_blocks - 1:
        across, along = lanes[block.first_lane] + across_shift, along_shift
        x, y = frame.to_ned(along, across)
        out.append(Entry(False, along, across, x, y, frame.heading_deg))
    if not odd or block.index == 0:
        across, along = lanes[block.last_lane] - across_shift, area.length_m - along_shift
        x, y = frame.to_ned(along, across)
        out.append(Entry(True, along, across, x, y, (frame.heading_deg + 180.0) % 360.0))
    return tuple(out)


def transit_m(vehicle: SurveyVehicle, entry: Entry, speed_mps: float) -> float:
    """The planner's join from the vehicle's pose to ``entry`` (m): turn, straight, turn at
    the turn radius of ``speed_mps``."""
    start = (vehicle.x_m, vehicle.y_m, math.radians(vehicle.heading_deg))
    goal = (entry.x_m, entry.y_m, math.radians(entry.heading_deg))
    return dubins(start, goal, turn_radius_m(speed_mps))[2]


def assign(
    vehicles: Sequence[SurveyVehicle],
    lanes: Sequence[float],
    area: SurveyArea,
    sent: SentArea,
    frame: AreaFrame,
) -> tuple[Assignment, ...]:
    """Each vehicle's block and entry (in the vehicles' order): of the two layouts (the odd
    lane at either edge), the one whose best assignment has the smaller largest distance,
    then the smaller sum."""
    sizes = block_sizes(len(lanes), len(vehicles))
    best: tuple[tuple[float, float], tuple[Assignment, ...]] | None = None
    for layout in dict.fromkeys((sizes, sizes[::-1])):
        blocks = blocks_of(layout)
        options = [
            [_option(v, b, lanes, area, sent, frame, len(blocks)) for b in blocks] for v in vehicles
        ]
        costs = [[o.cost_m for o in row] for row in options]
        columns = bottleneck_assignment(costs)
        chosen = tuple(options[i][j] for i, j in enumerate(columns))
        score = (max(a.cost_m for a in chosen), sum(a.cost_m for a in chosen))
        if best is None or score < best[0]:
            best = (score, chosen)
    assert best is not None
    return best[1]


def _option(
    vehicle: SurveyVehicle,
    block: Block,
    lanes: Sequence[float],
    area: SurveyArea,
    sent: SentArea,
    frame: AreaFrame,
    n_blocks: int,
) -> Assignment:
    """The vehicle's nearer corner of ``block`` (the Dubins transit's length)."""
    flown = 2 * block.laps
    lanes_m = flown * sent.length_m + (flown - 1) * sent.lane_spacing_m
    options = [
        Assignment(block, e, transit_m(vehicle, e, sent.speed_mps), lanes_m)
        for e in entries(block, n_blocks, lanes, area, sent, frame)
    ]
    return min(options, key=lambda a: a.transit_m)


# --- the assignment -----------------------------------------------------------------------


def bottleneck_assignment(costs: Sequence[Sequence[float]]) -> list[int]:
    """The column of each row of the square matrix ``costs``: the smallest largest cost, and
    among the assignments with it the smallest sum."""
    n = len(costs)
    values = sorted({c for row in costs for c in row})
    lo, hi = 0, len(values) - 1
    while lo < hi:  # the smallest threshold that still admits a perfect matching
        mid = (lo + hi) // 2
        if _perfect_matching([[c <= values[mid] for c in row] for row in costs]):
            hi = mid
        else:
            lo = mid + 1
    limit = values[lo]
    over = 1.0 + n * max(values)  # more than any assignment within the limit costs
    return min_cost_assignment([[c if c <= limit else over for c in row] for row in costs])


def _perfect_matching(allowed: list[list[bool]]) -> bool:
    """Whether every row can have its own column among the allowed ones (augmenting paths)."""
    n = len(allowed)
    owner = [-1] * n

    def augment(row: int, seen: list[bool]) -> bool:
        for col in range(n):
            if allowed[row][col] and not seen[col]:
                seen[col] = True
                if owner[col] < 0 or augment(owner[col], seen):
                    owner[col] = row
                    return True
        return False

    return all(augment(row, [False] * n) for row in range(n))


def min_cost_assignment(costs: Sequence[Sequence[float]]) -> list[int]:
    """The column of each row of the square matrix ``costs`` with the smallest sum (the
    Hungarian method with potentials, O(n^3))."""
    n = len(costs)
    u = [0.0] * (n + 1)
    v = [0.0] * (n + 1)
    owner = [0] * (n + 1)  # owner[col]: the row (1-based) holding column col; 0: none
    way = [0] * (n + 1)
    for row in range(1, n + 1):
        owner[0] = row
        col0 = 0
        least = [math.inf] * (n + 1)
        used = [False] * (n + 1)
        while True:
            used[col0] = True
            r0, delta, col1 = owner[col0], math.inf, 0
            for col in range(1, n + 1):
                if not used[col]:
                    reduced = costs[r0 - 1][col - 1] - u[r0] - v[col]
                    if reduced < least[col]:
                        least[col], way[col] = reduced, col0
                    if least[col] < delta:
                        delta, col1 = least[col], col
            for col in range(n + 1):
                if used[col]:
                    u[owner[col]] += delta
                    v[col] -= delta
                else:
                    least[col] -= delta
            col0 = col1
            if owner[col0] == 0:
                break
        while col0:
            col1 = way[col0]
            owner[col0] = owner[col1]
            col0 = col1
    result = [0] * n
    for col in range(1, n + 1):
        result[owner[col] - 1] = col - 1
    return result
