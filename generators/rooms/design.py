"""Which rows (one level per factor) a suite uses: the full grid, a pairwise covering array,
or seeded random picks — two strategies over one parameter space — and, for `rei search`,
the row at a point of the unit cube (``decode_point``).

Random rows are balanced (``balanced_rows``): each factor's levels come in seeded
shuffled blocks, so a suite of as many rooms as a factor has levels uses every level.

The pairwise array is built by IPOG (Lei & Tai's In-Parameter-Order): start from every pair
of the first two factors, then add one factor at a time, first choosing its level in each
existing row to cover the most new pairs (horizontal growth), then adding rows for the pairs
still missing (vertical growth). Ties are broken by level order, so the array is a pure
function of the space. This module never draws from a global random generator.
"""

from __future__ import annotations

import hashlib
import itertools
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

from rei.generators.rooms.space import Interval, ParameterSpace

Strategy = Literal["systematic", "random"]
Design = Literal["full", "pairwise", "random"]


def derived_seed(seed: int, *parts: object) -> int:
    """A 64-bit seed from (seed, parts...), independent of PYTHONHASHSEED and of platform."""
    text = ":".join(str(p) for p in (seed, *parts))
    return int.from_bytes(hashlib.sha256(text.encode("utf-8")).digest()[:8], "big")


@dataclass(frozen=True)
class SuiteDesign:
    design: Design
    rows: tuple[tuple[int, ...], ...]
    """Level indices per factor, one tuple per design row."""


def full_grid(sizes: Sequence[int]) -> list[tuple[int, ...]]:
    return list(itertools.product(*(range(n) for n in sizes)))


def pairwise(sizes: Sequence[int]) -> list[tuple[int, ...]]:
    """A covering array of strength 2: every pair of levels of every two factors appears."""
    k = len(sizes)
    if k == 0:
        return [()]
    if k == 1:
        return [(a,) for a in range(sizes[0])]
    # IPOG works best with the factors with most levels first; map back at the end.
    order = sorted(range(k), key=lambda f: (-sizes[f], f))
    s = [sizes[f] for f in order]
    rows: list[list[int | None]] = [[a, b] for a in range(s[0]) for b in range(s[1])]
    for f in range(2, k):
        uncovered: set[tuple[int, int, int]] = {(j, a, b) for j in range(f)
                                                for a in range(s[j]) for b in range(s[f])}
        # Horizontal growth.
        for row in rows:
            best, best_gain = 0, -1
            for b in range(s[f]):
                gain = sum(1 for j in range(f)
                           if row[j] is not None and (j, row[j], b) in uncovered)
                if gain > best_gain:
                    best, best_gain = b, gain
            row.append(best)
            for j in range(f):
                if row[j] is not None:
                    uncovered.discard((j, row[j], best))
        # Vertical growth, in a fixed order.
        extra: list[list[int | None]] = []
        for j, a, b in sorted(uncovered):
            for row in extra:
                if row[f] == b and row[j] is None:
                    row[j] = a
                    break
            else:
                new: list[int | None] = [None] * (f + 1)
                new[j], new[f] = a, b
                extra.append(new)
        rows.extend(extra)
    # Free slots take the level used least so far (lowest index on ties), so the levels
    # stay balanced instead of piling onto the first one.
    used = [[0] * n for n in s]
    for row in rows:
        for f, v in enumerate(row):
            if v is not None:
                used[f][v] += 1
    out: list[tuple[int, ...]] = []
    for row in rows:
        filled: list[int] = []
        for f, v in enumerate(row):
            if v is None:
                counts = used[f]
                v = min(range(s[f]), key=lambda level: (counts[level], level))
                used[f][v] += 1
            filled.append(v)
        original = [0] * k
        for pos, factor in enumerate(order):
            original[factor] = filled[pos]
        out.append(tuple(original))
    return out


def uncovered_pairs(sizes: Sequence[int], rows: Sequence[Sequence[int]]
                    ) -> list[tuple[int, int, int, int]]:
    """(factor i, level a, factor j, level b) pairs that no row holds; empty when covering."""
    seen = {(i, r[i], j, r[j]) for r in rows for i in range(len(sizes))
            for j in range(i + 1, len(sizes))}
    return [(i, a, j, b) for i in range(len(sizes)) for j in range(i + 1, len(sizes))
            for a in range(sizes[i]) for b in range(sizes[j]) if (i, a, j, b) not in seen]


def balanced_rows(space: ParameterSpace, count: int, seed: int) -> tuple[tuple[int, ...], ...]:
    """``count`` random rows in which each factor's levels are cycled in seeded blocks: rooms
    ``b*n .. b*n + n - 1`` of a factor with n levels take every level once, in an order the
    seed shuffles (per factor and block). So any suite of at least n rooms has every level of
    that factor, where independent picks can leave one out of a small suite (a small-preset
    suite of three rooms without a speed-limited mission). Row ``i`` depends only on the seed
    and ``i``: a longer suite starts with the rows of a shorter one."""
    blocks: dict[tuple[int, int], list[int]] = {}

    def level(factor: int, size: int, index: int) -> int:
        block = index // size
        key = (factor, block)
        if key not in blocks:
            order = list(range(size))
            random.Random(derived_seed(seed, "block", space.factors[factor].name,
                                       block)).shuffle(order)
            blocks[key] = order
        return blocks[key][index % size]

    sizes = [len(f.levels) for f in space.factors]
    return tuple(tuple(level(f, size, index) for f, size in enumerate(sizes))
                 for index in range(count))


def design_suite(space: ParameterSpace, strategy: Strategy, count: int | None, seed: int,
                 max_grid: int, design: str = "auto") -> tuple[SuiteDesign, int]:
    """The design rows and the number of rooms to generate (``count`` or the design's size)."""
    sizes = [len(f.levels) for f in space.factors]
    if strategy == "random":
        n = count if count is not None else 10
        return SuiteDesign("random", balanced_rows(space, n, seed)), n
    use_full = design == "full" or (design == "auto" and space.grid_size <= max_grid)
    chosen: list[tuple[int, ...]] = full_grid(sizes) if use_full else pairwise(sizes)
    return (SuiteDesign("full" if use_full else "pairwise", tuple(chosen)),
            count if count is not None else len(chosen))


# -- rows from points of the unit cube (`rei search`) ---------------------------------------

LAYOUT = "layout"
"""The search dimension that picks a room's construction stream (object placement, the
humans' paths, the goals' tiles): a seed, so nearby values give unrelated rooms."""
LAYOUT_SEEDS = 2**31


@dataclass(frozen=True)
class SearchDimension:
    """One coordinate of a search point: a factor's levels, a continuous factor's interval,
    or the layout seed."""

    name: str
    levels: tuple[str, ...] = ()
    interval: Interval | None = None

    @property
    def categorical(self) -> bool:
        return self.interval is None and self.name != LAYOUT

    def decode(self, u: float) -> str:
        """The level at coordinate ``u`` in [0, 1]: categorical levels take equal slices."""
        u = min(max(u, 0.0), 1.0)
        if self.interval is not None:
            return self.interval.level(u)
        count = len(self.levels) if self.name != LAYOUT else LAYOUT_SEEDS
        index = min(int(u * count), count - 1)
        return self.levels[index] if self.name != LAYOUT else str(index)


@dataclass(frozen=True)
class SearchRow:
    """A suite row a search picked: one level per factor (continuous ones may take any value
    of their interval) and the seed of the room's construction stream."""

    levels: tuple[tuple[str, str], ...]
    layout: int
    scenario: tuple[tuple[str, str], ...] = ()
    """Scenario parameters (generators/rooms/scenario.py) and their values, as written."""


def search_dimensions(space: ParameterSpace, intervals: Mapping[str, Interval],
                      layout: int | None, scenario: Sequence[Interval] = ()
                      ) -> tuple[SearchDimension, ...]:
    """The coordinates of a search over ``space``: every factor with more than one level or
    with an interval, in FACTOR order, then the scenario parameters' ranges as given, then
    the layout unless it is fixed."""
    dims = []
    for factor in space.factors:
        if factor.name in intervals:
            dims.append(SearchDimension(factor.name, interval=intervals[factor.name]))
        elif len(factor.levels) > 1:
            dims.append(SearchDimension(factor.name, levels=factor.levels))
    dims += [SearchDimension(r.factor, interval=r) for r in scenario]
    if layout is None:
        dims.append(SearchDimension(LAYOUT))
    return tuple(dims)


def decode_point(space: ParameterSpace, dims: Sequence[SearchDimension],
                 point: Sequence[float], layout: int | None) -> SearchRow:
    """The row at ``point`` (one coordinate in [0, 1] per dimension); factors that are not
    dimensions keep their single level."""
    if len(point) != len(dims):
        raise ValueError(f"expected a point of {len(dims)} coordinates, found {len(point)}")
    chosen = {d.name: d.decode(u) for d, u in zip(dims, point, strict=True)}
    levels = tuple((f.name, chosen.get(f.name, f.levels[0])) for f in space.factors)
    seed = int(chosen[LAYOUT]) if LAYOUT in chosen else (layout or 0)
    factors = {f.name for f in space.factors} | {LAYOUT}
    scenario = tuple((d.name, chosen[d.name]) for d in dims if d.name not in factors)
    return SearchRow(levels, seed, scenario)
