"""`rei watch` on a real terminal: tmux runs it, capture-pane reads the screen a person sees,
send-keys types q. The screen shows the thesis's monitor view of a known run (Figures 30-31):
the robot's and each object's FAR / CLOSE / COLLISION state, the tasks, the latest signals,
the total utility and the verdict; the exit status is the run's verdict, 130 when quit early."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rei.runtime.evaluator.signal_log import read_csv
from tests.conftest import REPO, require_tool
from tests.views.conftest import SAFETY_LIMIT


class Terminal:
    """A tmux session of its own (a private server socket), 150 x 40 characters."""

    def __init__(self, tmux: str, command: str) -> None:
        self.tmux = tmux
        self.socket = f"rei-watch-test-{uuid.uuid4().hex[:12]}"
        # the pane stays after the command: 'cat' keeps it open until the server is killed
        # (the size is the pane's: no COLUMNS/LINES inherited from the test's environment)
        shell = (f"cd {shlex.quote(str(REPO))} && unset COLUMNS LINES && {command}; "
                 f"echo EXIT=$?; cat")
        self._run("new-session", "-d", "-s", "watch", "-x", "150", "-y", "40", shell)

    def _run(self, *args: str) -> str:
        return subprocess.run([self.tmux, "-L", self.socket, *args], capture_output=True,
                              text=True, check=True, timeout=60).stdout

    def screen(self) -> str:
        return self._run("capture-pane", "-p", "-t", "watch")

    def keys(self, *keys: str) -> None:
        self._run("send-keys", "-t", "watch", *keys)

    def wait_for(self, ready: Callable[[str], bool]) -> str:
        """The screen once ``ready`` says so and it stopped changing (a page is drawn in
        several writes). Polled; the limit only keeps CI from hanging."""
        deadline = time.monotonic() + SAFETY_LIMIT
        previous = None
        while True:
            screen = self.screen()
            if ready(screen) and screen == previous:
                return screen
            previous = screen if ready(screen) else None
            assert time.monotonic() < deadline, f"the screen never got there:\n{screen}"
            time.sleep(0.2)

    def close(self) -> None:
        subprocess.run([self.tmux, "-L", self.socket, "kill-server"], capture_output=True,
                       check=False, timeout=60)


@pytest.fixture
def terminal() -> Iterator[Callable[[str], Terminal]]:
    tmux = require_tool("tmux")
    opened: list[Terminal] = []

    def open_(command: str) -> Terminal:
        opened.append(Terminal(tmux, command))
        return opened[-1]

    yield open_
    for t in opened:
        t.close()


def rei_watch(*args: str) -> str:
    return shlex.join([sys.executable, "-m", "rei.runtime.cli", "watch", *args])


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
    screen = term.wait_for(lambda s: "(replay at 1x)" in s and "q: quit" in s)
    assert "robot FAR" in screen and "task " in screen
    term.keys("q")
    screen = term.wait_for(lambda s: "EXIT=" in s)
    assert "EXIT=130" in screen
    assert "interrupted (stopped watching)" in screen
