"""A router restarted during a run is survived: the simulation sends the unanswered call
again with a bounded back-off, the robot answers a repeated call once (by its number), the
restarted `rei bus` keeps its folder's credentials so everyone joins again, and the run is
byte for byte the run in one process."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rei.runtime.bus.router import free_port
from rei.runtime.runs.session import run_into
from tests.bus.conftest import SAFETY, stop_all
from tests.conftest import EXAMPLES, REPO

MISSION = EXAMPLES / "medium_sparse" / "medium_sparse.mission"


def _bus(port: int, folder: Path) -> subprocess.Popen[str]:
    process = subprocess.Popen([sys.executable, "-m", "rei.runtime.commands", "bus", "--port",
                                str(port), "--dir", str(folder)], cwd=REPO, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    assert process.stdout is not None
    assert process.stdout.readline().startswith("endpoint")
    return process


@pytest.mark.slow
def test_a_router_restart_is_survived(tmp_path: Path) -> None:
    port = free_port("127.0.0.1")
    folder = tmp_path / "bus"
    env = {**os.environ, "REI_BUS_CREDENTIALS": str(folder)}
    endpoint = f"tcp/127.0.0.1:{port}"
    started = [_bus(port, folder)]
    try:
        started.append(subprocess.Popen(
            [sys.executable, "-m", "rei.runtime.commands", "robot", "--bus", endpoint, "--once"],
            cwd=REPO, env=env, text=True, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))
        run = subprocess.Popen(
            [sys.executable, "-m", "rei.runtime.commands", "run", str(MISSION), "-o",
             str(tmp_path / "dist"), "--bus", endpoint, "--no-monitor", "--bus-wait",
             str(SAFETY)], cwd=REPO, env=env, text=True, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE)
        started.append(run)
        partial = tmp_path / "dist" / "trace.jsonl.partial"
        waited = time.monotonic()
        while not (partial.exists() and partial.stat().st_size > 20000):
            assert run.poll() is None and time.monotonic() - waited < SAFETY * 5
            time.sleep(0.01)
        started[0].send_signal(signal.SIGKILL)  # mid-run: the router is gone at once
        started[0].wait()
        started[0].stdout.close()  # type: ignore[union-attr]
        started[0] = _bus(port, folder)
        out, err = run.communicate(timeout=600)
        assert run.returncode == 0, err
        assert "call(s) to the robot sent again while nobody could answer" in err
        assert started[1].wait(timeout=SAFETY) == 0
    finally:
        stop_all(started)
    run_into(MISSION, tmp_path / "local", monitor=False)
    assert (tmp_path / "dist" / "trace.jsonl").read_bytes() == \
        (tmp_path / "local" / "trace.jsonl").read_bytes()
