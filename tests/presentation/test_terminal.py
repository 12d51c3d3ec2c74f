"""`rei watch` on a real terminal: tmux runs it, capture-pane reads the screen a person sees,
send-keys types q. The screen shows the thesis's monitor view of a known run (Figures 30-31):
the robot's and each object's FAR / CLOSE / COLLISION state, the tasks, the latest signals,
the total utility and the verdict; the exit status is the run's verdict, 130 when quit early."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from rei.runtime.observation.evaluator.signal_log import read_csv
from tests.presentation.conftest import Terminal, rei_watch


def _rows(screen: str, name: str) -> list[str]:
    return [line for line in screen.splitlines() if line.split("│")[0].strip() == name]


@pytest.mark.parametrize("name", ["pass", "fail"])
def test_the_screen_shows_the_monitor_of_a_known_run(
        recorded: dict[str, Path], terminal: Callable[[str], Terminal], name: str) -> None:
    run = recorded[name]
    summary = json.loads((run / "summary.json").read_text())
    events = read_csv(run / "events.csv")
    term = terminal(rei_watch("--replay", str(run / "recording.mcap"), "--speed", "0"))
    screen = term.wait_for(lambda s: "the stream ended; q: quit" in s)
    assert f"REI watch  {summary['mission']} in {summary['room']}" in screen
    verdict = summary["verdict"].upper()
    assert f"verdict {verdict}   total utility {summary['total_utility']:g}" in screen
    assert f"total utility {summary['total_utility']:g}   signals {len(events)}" in screen
    # the latest signals with their utilities and running totals, as events.csv has them
    for row in events[-5:]:
        assert any(row.signal in line and f"{row.utility:+g}" in line
                   and f"{row.total_utility:g}" in line for line in screen.splitlines()), screen
    # each task's outcome
    for goal in summary["measurements"]["time_to_goal"]:
        assert any(goal["status"] in line for line in _rows_containing(screen, goal["task"]))
    if name == "fail":
        # the robot is still pushing into wall_e at the end: Figure 31's danger zone, and worse
        assert "robot COLLISION" in screen
        (wall,) = _rows(screen, "wall_e")
        assert "COLLISION" in wall and "0.00 m" in wall
        # the map: the robot on the last floor against the east wall, the start goal behind
        assert "██G · R ██" in screen
    else:
        assert "robot FAR" in screen
        (human,) = _rows(screen, "walker")
        assert "human" in human and "FAR" in human
    term.keys("q")
    screen = term.wait_for(lambda s: "EXIT=" in s)
    expected = {"pass": 0, "fail": 1}[name]
    assert f"EXIT={expected}" in screen
    assert f"verdict: {verdict}; total utility {summary['total_utility']:g}" in screen


def _rows_containing(screen: str, text: str) -> list[str]:
    return [line for line in screen.splitlines() if text in line]


def test_quitting_while_the_run_plays_ends_it_as_interrupted(
        recorded: dict[str, Path], terminal: Callable[[str], Terminal]) -> None:
    # real time: the 37 s run is still playing when q is pressed
    term = terminal(rei_watch("--replay", str(recorded["pass"] / "trace.jsonl")))
    screen = term.wait_for(lambda s: "(replay at 1x)" in s and "q: quit" in s
                           and "robot FAR" in s and "task " in s, stable=False)
    term.keys("q")
    screen = term.wait_for(lambda s: "EXIT=" in s)
    assert "EXIT=130" in screen
    assert "interrupted (stopped watching)" in screen
