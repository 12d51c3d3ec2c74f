"""The parameter space and the designs over it: full grid, pairwise covering array, random."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.generators.rooms import PRESETS, pairwise, preset_space, uncovered_pairs
from rei.generators.rooms.design import design_suite, full_grid
from rei.generators.rooms.space import ParameterError, parse_row, refuse_impossible

STATIC = ("box", "chair", "pillar", "shelf", "table")


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(min_value=1, max_value=5), min_size=0, max_size=8))
def test_pairwise_covers_every_pair_of_levels(sizes: list[int]) -> None:
    rows = pairwise(sizes)
    assert uncovered_pairs(sizes, rows) == []
    for row in rows:
        assert len(row) == len(sizes)
        assert all(0 <= v < n for v, n in zip(row, sizes, strict=True))
    # Never worse than the full grid, and a pure function of the sizes.
    assert len(rows) <= max(1, len(full_grid(sizes)))
    assert pairwise(sizes) == rows


def test_pairwise_is_much_smaller_than_the_grid_for_the_presets() -> None:
    for name in PRESETS:
        space = preset_space(name)
        sizes = [len(f.levels) for f in space.factors]
        rows = pairwise(sizes)
        assert uncovered_pairs(sizes, rows) == []
        largest_two = sorted(sizes)[-2:]
        assert len(rows) >= largest_two[0] * largest_two[1]
    medium = [len(f.levels) for f in preset_space("medium").factors]
    assert len(pairwise(medium)) < 30 < preset_space("medium").grid_size


def test_uncovered_pairs_finds_a_missing_pair() -> None:
    rows = [r for r in itertools.product(range(2), range(2)) if r != (1, 1)]
    assert uncovered_pairs([2, 2], rows) == [(0, 1, 1, 1)]


def test_systematic_uses_the_full_grid_when_small_and_pairwise_when_large() -> None:
    small = preset_space("small")
    design, count = design_suite(small, "systematic", None, 0, max_grid=1000)
    assert design.design == "full" and count == small.grid_size == len(design.rows)
    design, _ = design_suite(small, "systematic", None, 0, max_grid=4)
    assert design.design == "pairwise"


def test_random_design_depends_on_the_seed_only() -> None:
    space = preset_space("medium")
    a, _ = design_suite(space, "random", 20, 7, 256)
    b, _ = design_suite(space, "random", 20, 7, 256)
    c, _ = design_suite(space, "random", 20, 8, 256)
    assert a == b and a != c


@settings(max_examples=60, deadline=None)
@given(preset=st.sampled_from(sorted(PRESETS)), seed=st.integers(0, 2**40),
       count=st.integers(1, 40))
def test_random_rows_are_balanced_in_every_block(preset: str, seed: int, count: int) -> None:
    # Every factor with n levels takes each level once in rooms b*n .. b*n+n-1, so a suite of
    # n rooms has every level and the counts of a longer one differ by at most one.
    space = preset_space(preset).replaced({"objects": ("3", "5", "7", "9", "11")})
    design, n = design_suite(space, "random", count, seed, 256)
    assert n == count == len(design.rows)
    for f, factor in enumerate(space.factors):
        size = len(factor.levels)
        column = [row[f] for row in design.rows]
        for start in range(0, count - size + 1, size):
            assert sorted(column[start:start + size]) == list(range(size)), factor.name
        counts = [column.count(level) for level in range(size)]
        assert max(counts) - min(counts) <= 1, factor.name


def test_random_suite_of_as_many_rooms_as_levels_has_every_level() -> None:
    # Issue 22: the demo's 3 small rooms of seed 3 had no speed-limited mission.
    space = preset_space("small")
    for seed in range(1, 21):
        for factor_index, factor in enumerate(space.factors):
            design, _ = design_suite(space, "random", len(factor.levels), seed, 256)
            assert {row[factor_index] for row in design.rows} == set(
                range(len(factor.levels))), (seed, factor.name)
    design, _ = design_suite(space, "random", 3, 3, 256)
    max_speed = [f.name for f in space.factors].index("max_speed")
    assert {row[max_speed] for row in design.rows} == {0, 1}


def test_random_rows_are_prefix_stable_and_shuffled_by_the_seed() -> None:
    space = preset_space("medium")
    long, _ = design_suite(space, "random", 30, 5, 256)
    for count in (1, 2, 3, 7, 29):
        short, _ = design_suite(space, "random", count, 5, 256)
        assert short.rows == long.rows[:count]
    # The order within blocks is the seed's, not a fixed cycle: over seeds every level of a
    # three-level factor opens a suite.
    shape = [f.name for f in space.factors].index("shape")
    firsts = {design_suite(space, "random", 1, seed, 256)[0].rows[0][shape]
              for seed in range(30)}
    assert firsts == {0, 1, 2}


@pytest.mark.parametrize(("levels", "option"), [
    ({"size": "2x9"}, "size"),
    ({"size": "ninexnine"}, "size"),
    ({"objects": "-1"}, "objects"),
    ({"objects": "inf%"}, "objects"),
    ({"speed": "nan"}, "speed"),
    ({"speed": "0"}, "speed"),
    ({"mix": "table+sofa"}, "mix"),
    ({"shape": "circle"}, "shape"),
    ({"goals": "1"}, "goals"),
    ({"spacing": "-3"}, "spacing"),
    ({"loop": "maybe"}, "loop"),
])
def test_bad_levels_name_the_option(levels: dict[str, str], option: str) -> None:
    row = {f.name: f.levels[0] for f in preset_space("medium").factors} | levels
    with pytest.raises(ParameterError) as info:
        parse_row(row, STATIC)
    assert info.value.option == option
    assert f"--{option}: expected" in str(info.value)


@pytest.mark.parametrize(("levels", "option"), [
    ({"objects": "200"}, "objects"),
    ({"spacing": "40"}, "spacing"),
])
def test_impossible_rows_are_refused_before_any_work(levels: dict[str, str], option: str
                                                     ) -> None:
    row = {f.name: f.levels[0] for f in preset_space("medium").factors} | levels
    with pytest.raises(ParameterError) as info:
        refuse_impossible(parse_row(row, STATIC))
    assert info.value.option == option
