"""The README's distributed run works as written: its three terminals' commands, on a free
port and in a temporary folder instead of 7447 and out/, give the same events in the run's
folder and the monitor's."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from rei.runtime.bus.router import free_port
from tests.bus.conftest import SAFETY, stop_all
from tests.conftest import REPO

SECTION = "## Distributed runs: `rei bus`, `rei robot`, `rei monitor`"


def _block() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    after = text.split(SECTION, 1)[1].split("\n## ", 1)[0]
    match = re.search(r"```sh\n(.*?)```", after, re.S)
    assert match is not None
    return [shlex.join(w) for line in match.group(1).splitlines()
            if (w := shlex.split(line, comments=True))]


def test_the_readme_block_runs(tmp_path: Path) -> None:
    port = str(free_port("127.0.0.1"))
    lines = [line.replace("7447", port).replace("out/", f"{tmp_path}/") for line in _block()]
    assert [shlex.split(line)[:2] for line in lines] == [
        ["rei", "bus"], ["export", f"REI_BUS_CREDENTIALS={tmp_path}/bus"],
        ["rei", "robot"], ["rei", "monitor"],
        ["export", f"REI_BUS_CREDENTIALS={tmp_path}/bus"], ["rei", "run"], ["cmp",
                                                                      f"{tmp_path}/dist/events.csv"]]
    env = {**os.environ, "REI_BUS_CREDENTIALS": f"{tmp_path}/bus"}

    def rei(line: str) -> list[str]:
        argv = shlex.split(line)
        return [sys.executable, "-m", "rei.runtime.commands", *[a for a in argv[1:] if a != "&"]]

    started: list[subprocess.Popen[str]] = []
    try:
        bus = subprocess.Popen(rei(lines[0]), cwd=REPO, stdout=subprocess.PIPE, text=True,
                               stderr=subprocess.DEVNULL)
        started.append(bus)
        assert bus.stdout is not None
        assert bus.stdout.readline().strip() == f"endpoint tcp/127.0.0.1:{port}"
        for line in lines[2:4]:
            started.append(subprocess.Popen(rei(line), cwd=REPO, env=env, text=True,
                                            stdout=subprocess.DEVNULL,
                                            stderr=subprocess.DEVNULL))
        run = subprocess.run([*rei(lines[5]), "--bus-wait", str(SAFETY)],
                             cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stderr
        assert started[2].wait(timeout=SAFETY) == 0  # the monitor judged and ended
        assert started[1].wait(timeout=SAFETY) == 0  # --once: the robot ended with the run
        assert subprocess.run(shlex.split(lines[6]), timeout=SAFETY).returncode == 0
    finally:
        stop_all(started)
