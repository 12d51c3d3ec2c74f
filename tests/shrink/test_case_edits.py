"""The text edits `rei shrink` makes, without running anything: each removal leaves a file that
checks clean (or is refused by the same checks as a hand-written file), keeps the user's
layout, and ddmin finds a 1-minimal subset (tests/shrink/test_shrink_command.py runs it)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.lang.errors import LanguageError
from rei.runtime.campaigns.shrink.case import (
    elements,
    load_case,
    number_sites,
    rounded,
    sizes,
    with_numbers,
    without,
)
from rei.runtime.campaigns.shrink.ddmin import ddmin
from rei.runtime.campaigns.shrink.oracle import (
    FailureOracle,
    RunSettings,
    SeedOutcome,
    _outcome,
    fails_everywhere,
)
from rei.runtime.campaigns.shrink.shrinker import Shrinker, choose_requirement, unknown_requirement
from tests.campaigns.records import summary_for

CASES = Path(__file__).parent / "cases"
CLUTTERED = CASES / "cluttered.mission"


def test_a_case_counts_its_elements_per_kind() -> None:
    counts = sizes(load_case(CLUTTERED))
    assert {k: counts[k] for k in ("humans", "objects", "dynamic_objects", "goals",
                                   "trajectory_vertices", "floors")} == {
        "humans": 2, "objects": 2, "dynamic_objects": 0, "goals": 3,
        "trajectory_vertices": 3, "floors": 15}
    assert counts["elements"] == 25


def test_dropping_people_objects_and_a_goal_checks_clean_and_reads_well() -> None:
    case = load_case(CLUTTERED)
    gone = [e for e in elements(case) if e.kind in ("humans", "objects")
            or e.label == "goal 3 (last)"]
    smaller = without(case, gone)
    assert smaller.problems() == []
    assert "\n    human " not in smaller.room_text and "\n    object " not in smaller.room_text
    assert "pacing" not in smaller.room_text  # the comment above the person went with it
    assert "\n\n}" not in smaller.room_text  # no blank line left where items were
    assert "goal last" not in smaller.mission_text and "goal second" in smaller.mission_text
    assert sizes(smaller)["elements"] == 25 - 2 - 2 - 3 - 1


def test_a_candidate_that_breaks_a_rule_is_refused_by_the_checks() -> None:
    case = load_case(CLUTTERED)
    goals = [e for e in elements(case) if e.kind == "goals"]
    assert without(case, goals[:1]).problems() == []
    # one goal (a mission has a start and a final place), or the robot's floor made wall:
    # the checks say no, so such a candidate never runs
    assert any("at least two goals" in d.message for d in without(case, goals[:2]).problems())
    start = next(e for e in elements(case) if e.kind == "floors" and e.label == "start")
    assert any("start" in d.message for d in without(case, [start]).problems())


def test_a_grid_floor_becomes_a_wall_cell() -> None:
    case = load_case(CLUTTERED)
    corner = next(e for e in elements(case) if e.label == "hall_2_5")
    smaller = without(case, [corner, next(e for e in elements(case) if e.label == "stander")])
    assert '"#....##"' in smaller.room_text  # the row as written, one cell now wall
    assert smaller.problems() == []
    assert sizes(smaller)["floors"] == 14


def test_vertices_are_dropped_from_a_trajectory_down_to_two() -> None:
    case = load_case(CLUTTERED)
    vertices = [e for e in elements(case) if e.kind == "trajectory_vertices"]
    assert without(case, vertices[1:2]).problems() == []
    assert without(case, vertices[:2]).problems()  # one vertex is no trajectory


def test_numbers_round_to_fewer_digits() -> None:
    assert rounded("12.75") == ["13", "12.8"]
    assert rounded("0.35") == ["0", "0.3"] or rounded("0.35") == ["0", "0.4"]
    assert rounded("40") == [] and rounded("0.3") == ["0"]
    case = load_case(CLUTTERED)
    sites = {s.text: s for s in number_sites(case)}
    assert {"12.75", "4.5", "9.25", "0.35", "40.5"} <= set(sites)
    shorter = with_numbers(case, [(sites["12.75"], "13"), (sites["40.5"], "40")])
    assert "heading 13\n" in shorter.room_text and "timeout 40\n" in shorter.mission_text
    assert shorter.problems() == []


def test_a_case_that_does_not_check_clean_is_refused(tmp_path: Path) -> None:
    (tmp_path / "bad.room").write_text("room bad { tile 1.0 }\n", encoding="utf-8")
    (tmp_path / "bad.mission").write_text('mission m in "bad.room" {\n    goal g at nowhere\n}\n',
                                          encoding="utf-8")
    with pytest.raises(LanguageError):
        load_case(tmp_path / "bad.mission")


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 24), st.sets(st.integers(0, 23), min_size=1, max_size=4))
def test_ddmin_finds_a_one_minimal_subset(n: int, needed: set[int]) -> None:
    needed = {x % n for x in needed}
    items = list(range(n))

    def fails(subset: list[int]) -> bool:
        return needed <= set(subset)

    found = ddmin(items, fails)
    assert fails(found)
    assert set(found) == needed  # for a monotone failure the 1-minimal subset is the cause
    for x in found:  # 1-minimal: no single item can go
        assert not fails([y for y in found if y != x])


def test_ddmin_takes_nothing_when_nothing_is_needed() -> None:
    calls: list[list[int]] = []
    assert ddmin([1, 2, 3], lambda s: calls.append(s) is None) == []
    assert calls == [[]]


def _seed(seed: int, *failed: str) -> SeedOutcome:
    return SeedOutcome(seed, "fail" if failed else "pass", failed)


def test_a_step_is_kept_only_when_the_requirement_fails_on_every_seed() -> None:
    assert fails_everywhere([_seed(0, "SPEED_LIMIT"), _seed(1, "SPEED_LIMIT", "X")],
                            "SPEED_LIMIT")
    assert not fails_everywhere([_seed(0, "SPEED_LIMIT"), _seed(1)], "SPEED_LIMIT")
    assert not fails_everywhere([_seed(0, "X"), _seed(1, "X")], "SPEED_LIMIT")
    assert not fails_everywhere([], "SPEED_LIMIT")


def test_a_broken_run_never_fails_the_requirement() -> None:
    # the mission was abandoned (run error) but its verdicts were still evaluated: one fails
    failing = summary_for("m", "r", 0, False, 5.0)
    assert _outcome(0, "ran", failing.to_json(), "").failed == ("all_tasks_succeed",)
    crashed = replace(failing, outcome="error", reason="controller raised")
    outcome = _outcome(0, "ran", crashed.to_json(), "")
    assert (outcome.verdict, outcome.failed, outcome.message) == (
        "error", (), "controller raised")
    assert "all_tasks_succeed" in outcome.judged
    # nor does an outcome that says otherwise (e.g. journaled by an older REI)
    for verdict in ("error", "interrupted", "invalid"):
        assert not fails_everywhere([SeedOutcome(0, verdict, ("A",))], "A")


def test_a_requirement_no_run_judged_is_refused_with_the_names_they_did() -> None:
    judged = [SeedOutcome(s, "fail", ("SPEED_LIMIT",), "", ("SPEED_LIMIT", "NO_COLLISION"))
              for s in (0, 1)]
    assert unknown_requirement(judged, "SPEED_LIMT") == (
        "--requirement: expected one of the requirements the case's runs judged "
        "(SPEED_LIMIT, NO_COLLISION), found 'SPEED_LIMT'; did you mean 'SPEED_LIMIT'?")
    assert unknown_requirement(judged, "FOO") is not None
    assert "did you mean" not in str(unknown_requirement(judged, "FOO"))
    assert unknown_requirement(judged, "NO_COLLISION") is None
    assert unknown_requirement(judged, None) is None
    assert unknown_requirement([SeedOutcome(0, "error", (), "crashed")], "FOO") is None


def test_a_candidate_judged_again_in_a_session_is_charged_once(tmp_path: Path) -> None:
    case = load_case(CLUTTERED)
    settings = RunSettings(seeds=(0, 1, 2))
    journal = tmp_path / "shrink-runs.jsonl"  # an earlier session judged the case
    journal.write_text(json.dumps({"digest": case.digest(), "settings": settings.describe(),
                                   "outcomes": [_seed(s, "A").to_json() for s in (0, 1, 2)]})
                       + "\n", encoding="utf-8")
    oracle = FailureOracle(settings, tmp_path / "work", journal)
    shrinker = Shrinker(oracle, "A", max_runs=3)  # room for the three seeds once
    assert shrinker.still_fails(case) and shrinker.still_fails(case)  # no BudgetSpent
    assert (oracle.runs, oracle.started) == (3, 0)  # remembered: counted once, nothing ran


def test_ddmin_never_tests_the_empty_subset_twice() -> None:
    tried: list[list[int]] = []

    def fails(kept: list[int]) -> bool:
        tried.append(kept)
        return 3 in kept

    assert ddmin(list(range(6)), fails) == [3]
    assert tried.count([]) == 1


def test_the_requirement_is_chosen_from_what_the_original_does() -> None:
    both = [_seed(0, "A", "B"), _seed(1, "B")]
    assert choose_requirement(both, None) == ("shrunk", "B")
    assert choose_requirement(both, "A") == ("flaky", "A")
    assert choose_requirement([_seed(0), _seed(1)], None) == ("passes", None)
    assert choose_requirement([_seed(0), _seed(1)], "A") == ("passes", "A")
    broken = [SeedOutcome(0, "error", (), "crashed"), _seed(1, "A")]
    assert choose_requirement(broken, None)[0] == "run_error"


def test_a_mission_repeated_in_cycles_can_go_through_its_goals_once() -> None:
    case = load_case(Path(__file__).resolve().parents[2] / "examples" / "small_dense"
                     / "small_dense.mission")
    (cycles,) = [e for e in elements(case) if e.kind == "cycles"]
    assert cycles.label == "cycles 2"
    once = without(case, [cycles])
    assert "cycles" not in once.mission_text and once.problems() == []
    assert once.models()[1].cycles == 1
    assert sizes(once)["elements"] == sizes(case)["elements"]  # a setting, not an element
