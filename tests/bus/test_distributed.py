"""Components as processes over a real router on loopback: `rei run --bus` (the simulation),
`rei robot` (the robot under test, in lock-step) and `rei monitor` (monitor + evaluator)
give, on every example, byte-identical events.csv and trace.jsonl and the same verdicts as
the run in one process; a robot gone silent ends the run as an error naming it.

The router and one `rei robot` serve every run of the module (each run a fresh controller);
each example runs once distributed and once in process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from rei.runtime.bus.router import Router, start
from rei.runtime.runs.session import run_into
from tests.bus.conftest import SAFETY
from tests.conftest import EXAMPLES, REPO

MISSIONS = sorted(EXAMPLES.rglob("*.mission"))
DURATION = "40"
"""Simulated seconds of each run (the longest examples run 400-600 s: the first 40 hold
goals, humans, contacts and faults, and a cut run is judged like any other)."""


def _rei(*args: str, env: dict[str, str]) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.fixture(scope="module")
def bus(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Router, dict[str, str]]]:
    with start(tmp_path_factory.mktemp("distributed") / "bus") as router:
        env = {**os.environ, "REI_BUS_CREDENTIALS": str(router.bus.path)}
        robot = _rei("robot", "--bus", router.bus.endpoint, "--controller", "reference",
                     env=env)
        try:
            yield router, env
        finally:
            robot.terminate()
            _, err = robot.communicate(timeout=SAFETY)
            assert robot.returncode == 0, err


def _verdicts(folder: Path) -> list[tuple[str, str]]:
    summary = json.loads((folder / "summary.json").read_text())
    return [(v["requirement"], v["status"]) for v in summary["verdicts"]]


@pytest.mark.slow
@pytest.mark.parametrize("mission", MISSIONS, ids=lambda p: p.stem)
def test_distributed_run_equals_in_process(bus: tuple[Router, dict[str, str]],
                                           mission: Path, tmp_path: Path) -> None:
    router, env = bus
    monitor = _rei("monitor", "--bus", router.bus.endpoint, "-o", str(tmp_path / "monitor"),
                   "-q", env=env)
    try:
        run = subprocess.run(
            [sys.executable, "-m", "rei.runtime.commands", "run", str(mission), "-o",
             str(tmp_path / "dist"), "--duration", DURATION, "--bus", router.bus.endpoint,
             "--wait-for-monitor", "--bus-wait", str(SAFETY), "-q"],
            cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
        watched, err = monitor.communicate(timeout=SAFETY)
    finally:
        if monitor.poll() is None:
            monitor.kill()
            monitor.communicate()
    assert run.returncode in (0, 1), run.stderr
    local, _ = run_into(mission, tmp_path / "local", duration=float(DURATION))
    for name in ("events.csv", "trace.jsonl"):
        expected = (tmp_path / "local" / name).read_bytes()
        assert (tmp_path / "dist" / name).read_bytes() == expected, name
        assert (tmp_path / "monitor" / name).read_bytes() == expected, name
    assert _verdicts(tmp_path / "dist") == _verdicts(tmp_path / "local")
    assert _verdicts(tmp_path / "monitor") == _verdicts(tmp_path / "local")
    assert monitor.returncode == run.returncode, err
    assert json.loads((tmp_path / "monitor" / "summary.json").read_text())[
        "measurements"]["bus"] == {"received": local.measurements["samples"], "missed": 0,
                                   "missed_samples": [], "duplicated": 0, "reordered": 0,
                                   "malformed": 0, "dropped": 0}
    assert (tmp_path / "monitor" / "report.html").is_file()


@pytest.mark.slow
def test_a_silent_robot_is_a_run_error_naming_it(tmp_path: Path) -> None:
    with start(tmp_path / "bus") as router:
        env = {**os.environ, "REI_BUS_CREDENTIALS": str(router.bus.path)}
        robot = _rei("robot", "--bus", router.bus.endpoint, "--controller",
                     "tests.robot.faulty:Hanging", env=env)
        try:
            run = subprocess.run(
                [sys.executable, "-m", "rei.runtime.commands", "run",
                 str(EXAMPLES / "simple_wall" / "simple_wall.mission"), "-o",
                 str(tmp_path / "out"), "--bus", router.bus.endpoint, "--watchdog", "1",
                 "--bus-wait", str(SAFETY)],
                cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
        finally:
            robot.kill()
            robot.communicate()
    assert run.returncode == 3, run.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["outcome"] == "error"
    assert summary["reason"] == ("the robot on the bus went silent: controller step() got no "
                                 "answer within the watchdog's 1 s")


def test_no_robot_on_the_bus_is_said_in_one_line(router: Router, tmp_path: Path) -> None:
    env = {**os.environ, "REI_BUS_CREDENTIALS": str(router.bus.path)}
    run = subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run",
         str(EXAMPLES / "simple_wall" / "simple_wall.mission"), "-o", str(tmp_path / "out"),
         "--bus", router.bus.endpoint, "--bus-wait", "0.5"],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 2
    assert f"--bus: no robot answered on {router.bus.endpoint} within 0.5 s" in run.stderr
    assert len([line for line in run.stderr.splitlines() if "error" in line]) == 1
