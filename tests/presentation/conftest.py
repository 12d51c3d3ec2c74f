"""Recorded runs the views are tested on (one that passes, one that drives into a wall), and
a terminal of its own (tmux) to read `rei watch`'s screen from."""

from __future__ import annotations

import shlex
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, REPO, made_once, require_tool

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck command fails instead of hanging CI (not a performance limit)."""

RUNS = {
    # the reference navigator reaches the elevator: FAR -> CLOSE -> FAR of a wall, PASS
    "pass": (EXAMPLES / "navigation" / "navigation.mission", "40", ()),
    # a controller that drives straight into the wall: FAR -> CLOSE -> COLLISION, FAIL
    "fail": (EXAMPLES / "simple_wall" / "simple_wall.mission", "15",
             ("--controller", "tests.robot.scripted:Ram")),
}


def rei(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


@pytest.fixture(scope="session")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """name -> the output folder of a recorded `rei run` (trace.jsonl, recording.mcap,
    events.csv, summary.json), recorded once for the whole session (the view tests of either
    worker read the same folders)."""

    def record(root: Path) -> None:
        for name, (mission, duration, extra) in RUNS.items():
            done = rei("run", str(mission), "-o", str(root / name), "--record", "--duration",
                       duration, *extra)
            assert done.returncode == {"pass": 0, "fail": 1}[name], done.stdout + done.stderr

    root = made_once(tmp_path_factory, "watched", record)
    return {name: root / name for name in RUNS}


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

    def wait_for(self, ready: Callable[[str], bool], stable: bool = True) -> str:
        """The screen once ``ready`` says so and (``stable``) it stopped changing: a page is
        drawn in several writes. A screen that plays on never stops changing: ask for it
        with ``stable=False``. Polled; the limit only keeps CI from hanging."""
        deadline = time.monotonic() + SAFETY_LIMIT
        previous = None
        while True:
            screen = self.screen()
            if ready(screen) and (screen == previous or not stable):
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
    return shlex.join([sys.executable, "-m", "rei.runtime.commands", "watch", *args])
