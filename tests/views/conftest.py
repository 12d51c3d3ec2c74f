"""Recorded runs the views are tested on: one that passes, one that drives into a wall."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, REPO

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck command fails instead of hanging CI (not a performance limit)."""

RUNS = {
    # the reference navigator reaches the elevator: FAR -> CLOSE -> FAR of a wall, PASS
    "pass": (EXAMPLES / "navigation" / "navigation.mission", "40", ()),
    # a controller that drives straight into the wall: FAR -> CLOSE -> COLLISION, FAIL
    "fail": (EXAMPLES / "simple_wall" / "simple_wall.mission", "15",
             ("--controller", "tests.runtime.scripted:Ram")),
}


def rei(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "rei.runtime.cli", *args], cwd=REPO,
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


@pytest.fixture(scope="session")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """name -> the output folder of a recorded `rei run` (trace.jsonl, recording.mcap,
    events.csv, summary.json)."""
    root = tmp_path_factory.mktemp("watched")
    out = {}
    for name, (mission, duration, extra) in RUNS.items():
        folder = root / name
        done = rei("run", str(mission), "-o", str(folder), "--record", "--duration", duration,
                   *extra)
        assert done.returncode == {"pass": 0, "fail": 1}[name], done.stdout + done.stderr
        out[name] = folder
    return out
