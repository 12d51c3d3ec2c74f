"""Search strategies and the rows they decode to, without simulating: every strategy conforms
to the protocol and is deterministic for a seed (the basis of resuming by replay); points
decode to rows inside the ranges given; bad ranges are refused with the option named."""

from __future__ import annotations

import math

import pytest

from rei.generators.rooms.design import LAYOUT, decode_point, search_dimensions
from rei.generators.rooms.space import ParameterError, parse_interval, preset_space
from rei.runtime.campaigns.search import (
    STRATEGIES,
    SearchError,
    Told,
    check_strategy,
    make_strategy,
)
from rei.runtime.campaigns.search.strategies import MEASURE_RANGES


def _dims() -> tuple[object, ...]:
    space = preset_space("small").replaced({"size": ("6x4", "7x5", "8x5")})
    return search_dimensions(space, {"max_speed": parse_interval("max_speed", "0.05:0.3")},
                             None)


def _history(name: str, seed: int, batches: int = 3, batch: int = 4
             ) -> list[tuple[float, ...]]:
    """The points a strategy proposes when told a fixed function of each point."""
    dims = _dims()
    strategy = make_strategy(name, dims, seed, batch)  # type: ignore[arg-type]
    asked: list[tuple[float, ...]] = []
    for _ in range(batches):
        points = strategy.ask(batch)
        asked.extend(points)
        strategy.tell(points, [Told(sum(p) - 1.0, (p[0] * 2.0, 1.0 + p[1]))
                               for p in points])
    return asked


@pytest.mark.parametrize("name", STRATEGIES)
def test_every_strategy_conforms_and_is_deterministic_for_a_seed(name: str) -> None:
    dims = _dims()
    assert check_strategy(make_strategy(name, dims, 3, 4), len(dims)) == []  # type: ignore[arg-type]
    first, again, other = _history(name, 7), _history(name, 7), _history(name, 8)
    assert first == again
    assert first != other  # the seed matters: the test above is not vacuous
    assert all(0.0 <= u <= 1.0 for p in first for u in p)


def test_the_conformance_checker_reports_a_broken_strategy() -> None:
    class OutsideTheCube:
        name = "outside"

        def ask(self, count: int) -> list[tuple[float, ...]]:
            return [(1.5, math.nan)] * count

        def tell(self, points: object, told: object) -> None:
            return None

    assert check_strategy(OutsideTheCube()) != []
    assert check_strategy(object()) == ["expected a 'name' attribute of type str",
                                        "expected a method 'ask'", "expected a method 'tell'"]


def test_the_optimisers_learn_where_the_margin_falls_and_random_does_not() -> None:
    """Told a margin that falls as max_speed rises, TPE's and CMA-ES's later batches move to
    high speeds; random's stay spread (the mechanism behind the end-to-end comparison with
    real runs in test_search_runs.py)."""
    def late_speeds(name: str) -> float:
        dims = _dims()
        strategy = make_strategy(name, dims, 1, 4)  # type: ignore[arg-type]
        late: list[float] = []
        for batch in range(5):
            points = strategy.ask(4)
            if batch >= 2:
                late.extend(p[-2] for p in points)  # max_speed: the last factor dimension
            strategy.tell(points, [Told(1.0 - p[-2], (0.0, 1.0)) for p in points])
        return sum(late) / len(late)

    baseline = late_speeds("random")
    assert late_speeds("tpe") > baseline + 0.1
    assert late_speeds("cmaes") > baseline + 0.1


def test_map_elites_keeps_the_lowest_margin_per_descriptor_cell() -> None:
    dims = _dims()
    strategy = make_strategy("map-elites", dims, 0, 4)
    points = strategy.ask(4)
    strategy.tell(points, [Told(0.5, (0.1, 1.1)), Told(-0.2, (0.1, 1.1)),
                           Told(0.3, (1.9, 2.4)), Told(0.4, (1.0, 1.5))])
    archive = strategy.archive  # type: ignore[attr-defined]
    data = archive.data()
    assert len(archive) == 3  # two of the four points share a cell: the better one stays
    assert sorted(-float(v) for v in data["objective"]) == [-0.2, 0.3, 0.4]
    assert set(MEASURE_RANGES) >= {"closest_obstacle_m", "tortuosity"}


def test_points_decode_to_rows_inside_the_ranges_and_levels() -> None:
    space = preset_space("small").replaced({"size": ("6x4", "7x5")})
    interval = parse_interval("speed", "0.5:1.4")
    dims = search_dimensions(space, {"speed": interval}, None)
    names = [d.name for d in dims]
    assert "speed" in names and "size" in names and names[-1] == LAYOUT
    low = decode_point(space, dims, [0.0] * len(dims), None)
    high = decode_point(space, dims, [1.0] * len(dims), None)
    assert dict(low.levels)["speed"] == "0.5" and dict(high.levels)["speed"] == "1.4"
    assert dict(low.levels)["size"] == "6x4" and dict(high.levels)["size"] == "7x5"
    assert low.layout == 0 and high.layout == 2**31 - 1
    fixed = search_dimensions(space, {}, 42)
    assert LAYOUT not in [d.name for d in fixed]
    assert decode_point(space, fixed, [0.5] * len(fixed), 42).layout == 42


@pytest.mark.parametrize(("name", "text", "found"), [
    ("max_speed", "nan:1", "'nan'"), ("max_speed", "0.1:inf", "'inf'"),
    ("speed", "1.2:0.6", "'1.2:0.6'"), ("speed", "0.1:1.0", "'0.1'"),
    ("size", "4:8", "'4:8'"), ("max_speed", "0.1:0.2:0.3", "'0.1:0.2:0.3'"),
    ("max_speed", "0:0.2", "'0'"),
])
def test_bad_ranges_are_refused_naming_the_option(name: str, text: str, found: str) -> None:
    with pytest.raises(ParameterError) as error:
        parse_interval(name, text)
    message = str(error.value)
    assert message.startswith(f"--{name.replace('_', '-')}: expected ") and found in message


def test_cmaes_needs_two_dimensions() -> None:
    space = preset_space("small")
    one = search_dimensions(space.replaced({n: (space.levels(n)[0],) for n in
                                            ("shape", "size", "objects", "mix", "cycles",
                                             "behaviour", "heading", "max_speed")}),
                            {}, None)
    assert len(one) == 1
    with pytest.raises(SearchError, match="at least two"):
        make_strategy("cmaes", one, 0, 4)


def test_the_objective_is_the_margin_and_never_hides_a_failure() -> None:
    from dataclasses import replace  # noqa: PLC0415

    from rei.runtime.campaigns import RunRecord, RunSpec  # noqa: PLC0415
    from rei.runtime.campaigns.search import objective  # noqa: PLC0415
    from rei.runtime.campaigns.search.driver import (  # noqa: PLC0415
        FAILED_WITHOUT_MARGIN,
        NO_EVIDENCE,
    )
    from rei.runtime.results import Verdict  # noqa: PLC0415
    from tests.campaigns.records import summary_for  # noqa: PLC0415

    spec = RunSpec("m.r00", "/m.mission", "x/m.mission", "x", 0, 1)

    def record(*verdicts: Verdict, status: str = "ran") -> RunRecord:
        summary = replace(summary_for("m", "r", 1, True, 10.0), verdicts=verdicts)
        return RunRecord(spec, status, 0, 1.0, "", summary)

    speed = Verdict("SPEED_LIMIT", "pass", None, "", margin=0.04)
    near = Verdict("NO_ROBOT_COLLISION", "pass", None, "", margin=0.01)
    broken = Verdict("GOAL_HEADING", "fail", 3.0, "off by 0.5 rad")  # failed, no margin
    assert objective(record(speed, near), None) == 0.01  # the smallest margin
    assert objective(record(speed, near), "SPEED_LIMIT") == 0.04
    assert objective(record(speed, broken), None) == FAILED_WITHOUT_MARGIN
    assert objective(record(speed, broken), "GOAL_HEADING") == FAILED_WITHOUT_MARGIN
    assert objective(record(speed), "HUMAN_SLOW_ZONE") == NO_EVIDENCE  # not in the run
    assert objective(record(speed, status="crashed"), None) == NO_EVIDENCE
    assert objective(None, None) == NO_EVIDENCE
    far = Verdict("SPEED_LIMIT", "fail", 1.0, "", margin=-1e9)
    assert objective(record(far), None) == -10.0  # bounded, still the lowest


def test_map_elites_keeps_unbuilt_candidates_out_of_the_archive() -> None:
    # An unbuilt candidate has no room, so its objective and descriptors (NO_EVIDENCE at
    # (0, 0)) describe nothing; told as an elite it would seed the emitter from an edge cell.
    from rei.runtime.campaigns.search.driver import NO_EVIDENCE  # noqa: PLC0415

    def run(seed: int) -> tuple[object, list[list[float]]]:
        strategy = make_strategy("map-elites", _dims(), seed, 4)
        points = strategy.ask(4)
        strategy.tell(points, [Told(NO_EVIDENCE, (0.0, 0.0), built=False),
                               Told(0.3, (1.9, 2.4)), Told(NO_EVIDENCE, (0.0, 0.0), built=False),
                               Told(0.4, (1.0, 1.5))])
        return strategy, [list(p) for p in strategy.ask(4)]

    strategy, asked = run(3)
    data = strategy.archive.data()  # type: ignore[attr-defined]
    assert len(strategy.archive) == 2  # type: ignore[attr-defined,arg-type]
    assert sorted(-float(v) for v in data["objective"]) == [0.3, 0.4]
    assert all(float(m[0]) > 0.0 for m in data["measures"])  # no elite at (0, 0)
    assert asked == run(3)[1]  # still deterministic for a seed


def test_a_fail_line_names_the_failed_requirements_and_labels_the_margin() -> None:
    from dataclasses import replace  # noqa: PLC0415

    from rei.runtime.campaigns import RunRecord, RunSpec  # noqa: PLC0415
    from rei.runtime.campaigns.search.driver import (  # noqa: PLC0415
        CandidateResult,
        fail_line,
        objective,
    )
    from rei.runtime.results import Verdict  # noqa: PLC0415
    from tests.campaigns.records import summary_for  # noqa: PLC0415

    spec = RunSpec("m.r00", "/m.mission", "x/m.mission", "x", 0, 1)
    speed = Verdict("SPEED_LIMIT", "pass", None, "", margin=0.04)
    hit = Verdict("NO_ROBOT_COLLISION", "fail", 2.0, "", margin=-0.1)
    summary = replace(summary_for("m", "r", 1, True, 10.0), verdicts=(speed, hit))
    record = RunRecord(spec, "ran", 0, 1.0, "", summary)
    # The run fails by NO_ROBOT_COLLISION while the chosen requirement's margin is positive.
    result = CandidateResult(None, record, objective(record, "SPEED_LIMIT"))  # type: ignore[arg-type]
    assert fail_line(result, "SPEED_LIMIT") == ("failed NO_ROBOT_COLLISION; SPEED_LIMIT "
                                                "margin 0.04")
    result = CandidateResult(None, record, objective(record, None))  # type: ignore[arg-type]
    assert fail_line(result, None) == "failed NO_ROBOT_COLLISION; smallest margin -0.1"


@pytest.mark.parametrize(("text", "low", "high"), [
    ("0.0004:0.3", 0.001, 0.3), ("0.05:0.2999", 0.05, 0.299), ("0.1:0.3", 0.1, 0.3),
])
def test_range_ends_are_rounded_inwards_to_the_level_precision(text: str, low: float,
                                                               high: float) -> None:
    interval = parse_interval("max_speed", text)
    assert (interval.low, interval.high) == (low, high)
    assert interval.level(0.0) == f"{low:g}" and interval.level(1.0) == f"{high:g}"


def test_a_range_that_rounds_to_nothing_is_refused_naming_what_was_typed() -> None:
    with pytest.raises(ParameterError, match=r"--max-speed: .*rounded inwards to 3 decimals.*"
                                             r"found '0\.0001:0\.0004'"):
        parse_interval("max_speed", "0.0001:0.0004")
    with pytest.raises(ParameterError, match="found '0.0011:0.0019'"):
        parse_interval("max_speed", "0.0011:0.0019")  # 0.002 > 0.001 after rounding
