"""`heading_tolerance DEG` of a goal: parsed, checked like every number, printed back, mapped
to radians in the concrete goal, and offered nowhere a keyword would be wrong."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rei.generators.concrete.build import load_concrete_mission
from rei.lang.lsp.completion import mission_completions
from rei.lang.mission.model import DEFAULT_HEADING_TOLERANCE
from rei.lang.printer import print_mission
from rei.lang.workspace import Workspace

ROOM = """room r {
    grid g {
        "#####"
        "#...#"
        "#####"
    }
    robot bot : turtlebot3_waffle on g_1_1
}
"""


def _mission(write, goal_options: str) -> Path:  # type: ignore[no-untyped-def]
    write("r.room", ROOM)
    return write("m.mission", f'mission m in "r.room" {{\n    goal a at g_1_1\n'
                              f'    goal b at g_1_3 {goal_options}\n}}\n')


def test_the_default_is_15_degrees_and_a_given_one_reaches_the_concrete_goal(write) -> None:  # type: ignore[no-untyped-def]
    path = _mission(write, "heading 90 heading_tolerance 5.5")
    doc = Workspace().mission(path)
    assert doc.ok, doc.diagnostics
    assert doc.mission is not None
    a, b = doc.mission.goals
    assert a.heading_tolerance_deg == DEFAULT_HEADING_TOLERANCE == 15.0
    assert (b.heading_deg, b.heading_tolerance_deg) == (90.0, 5.5)
    concrete = load_concrete_mission(path)
    assert concrete.goals[0].heading_tolerance == pytest.approx(math.radians(15.0))
    assert concrete.goals[1].heading_tolerance == pytest.approx(math.radians(5.5))
    assert concrete.goals[1].yaw == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(("options", "rule"), [
    ("heading_tolerance 0", "NUM-RANGE"),
    ("heading_tolerance -3", "NUM-RANGE"),
    ("heading_tolerance 180.5", "NUM-RANGE"),
    ("heading_tolerance 1e400", "NUM-FINITE"),
    ("heading_tolerance 10 heading_tolerance 20", "OPTION-REPEAT"),
])
def test_bad_heading_tolerances_are_located_diagnostics(write, options: str, rule: str) -> None:  # type: ignore[no-untyped-def]
    path = _mission(write, options)
    [d] = [d for d in Workspace().check(path) if d.is_error]
    assert d.rule == rule and d.span.line == 3
    if rule == "NUM-RANGE":
        assert "heading_tolerance of goal 'b' (degrees): expected a number > 0 and <= 180" \
            in d.message


def test_180_degrees_is_allowed_and_the_printer_keeps_a_non_default(write, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    path = _mission(write, "heading 0 heading_tolerance 180")
    doc = Workspace().mission(path)
    assert doc.ok and doc.mission is not None
    printed = print_mission(doc.mission, "r.room")
    assert "heading 0.0 heading_tolerance 180.0" in printed
    assert "heading_tolerance" not in printed.splitlines()[1]  # the default is not printed
    again = write("again.mission", printed)
    back = Workspace().mission(again)
    assert back.mission is not None
    assert [g.heading_tolerance_deg for g in back.mission.goals] == [15.0, 180.0]


def test_completion_offers_the_keyword_and_nothing_after_it() -> None:
    text = 'mission m in "r.room" {\n    goal a at g_1_1 '
    assert "heading_tolerance" in [c.label for c in mission_completions(text, None)]
    assert mission_completions(text + "heading_tolerance ", None) == []
