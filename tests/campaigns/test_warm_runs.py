"""Campaign runs forked by their worker's fork server (rei.runtime.runs.fork_server) are the runs a
fresh `rei run` process makes: the same bytes, the same isolation, never stale.

Real runs of the bundled examples (pybullet, the reference navigator), real fork servers."""

from __future__ import annotations

import io
import os
import shutil
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

import rei.runtime.platform.warm as warm_package
from rei.runtime.campaigns import LocalEngine, RunResult, plan_campaign, run_campaign
from rei.runtime.campaigns.execute import execute_run, run_environment
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.platform.warm import WARM_VARIABLE
from rei.runtime.runs.fork_server import ForkServer, WarmWorkers

from .conftest import require_rei_run
from .records import EXAMPLES
from .test_process_death import SLOW_CONTROLLER, WARM_SERVER, rei_runs

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

OUTPUTS = ("trace.jsonl", "events.csv", "summary.json", "report.html", "run.log")

HANGING_CONTROLLER = """
import time

from rei.runtime.robot.navigator.reference import ReferenceNavigator


class Hanging(ReferenceNavigator):
    def step(self, observation):
        time.sleep(3600)
"""

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux only")]


@pytest.fixture
def plugins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """Controllers of the tests' own, importable by the runs (PYTHONPATH)."""
    require_rei_run()
    folder = tmp_path / "plugins"
    folder.mkdir()
    (folder / "slow_controllers.py").write_text(SLOW_CONTROLLER)
    (folder / "hanging_controllers.py").write_text(HANGING_CONTROLLER)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [str(folder), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.delenv(WARM_VARIABLE, raising=False)
    yield folder


def spec_of(mission: Path, duration: float, controller: str | None = None) -> RunSpec:
    return plan_campaign([mission], duration=duration, controller=controller).runs[0]


def wait_until(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + SAFETY_LIMIT
    while not condition():
        assert time.monotonic() < deadline, f"still waiting after {SAFETY_LIMIT:g} s: {what}"
        time.sleep(0.05)


def in_thread(work: Callable[[], list[RunResult]]) -> tuple[threading.Thread,
                                                            list[list[RunResult]]]:
    results: list[list[RunResult]] = []
    thread = threading.Thread(target=lambda: results.append(work()))
    thread.start()
    return thread, results


def servers_of(parent: int) -> set[int]:
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
                cmdline = (entry / "cmdline").read_bytes()
            except (OSError, ValueError, IndexError):
                continue
            if ppid == parent and WARM_SERVER in cmdline:
                found.add(int(entry.name))
    return found


def output_of(run: Path, name: str) -> bytes:
    return (run / name).read_bytes()


# -- the same runs ---------------------------------------------------------------------------


def test_warm_and_cold_campaigns_write_the_same_bytes(
        plugins: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    plan = plan_campaign([EXAMPLES / "simple_wall", EXAMPLES / "small_dense"], repeat=2,
                         duration=2.0)
    warm_root, cold_root = tmp_path / "warm", tmp_path / "cold"
    result = run_campaign(plan, warm_root, LocalEngine(2), {}, stream=io.StringIO())
    assert result.complete and all(r.status == "ran" for r in result.records)
    monkeypatch.setenv(WARM_VARIABLE, "off")
    result = run_campaign(plan, cold_root, LocalEngine(2), {}, stream=io.StringIO())
    assert result.complete and all(r.status == "ran" for r in result.records)
    for spec in plan.runs:
        warm_run = next((warm_root / "runs").glob(f"{spec.run_id}*"))
        cold_run = next((cold_root / "runs").glob(f"{spec.run_id}*"))
        assert b"fresh interpreter" not in output_of(warm_run, "campaign-stderr.txt")
        for name in OUTPUTS:
            assert output_of(warm_run, name) == output_of(cold_run, name), (spec.run_id, name)


def test_the_run_is_a_child_of_the_workers_fork_server(plugins: Path, tmp_path: Path) -> None:
    server = ForkServer(run_environment())
    try:
        out = tmp_path / "run"
        out.mkdir()
        with (out / "stdout").open("wb") as stdout, (out / "stderr").open("wb") as stderr:
            run = server.spawn(spec_of(EXAMPLES / "simple_wall", 1.0).run_argv(str(out)),
                               run_environment(), os.getcwd(), stdout.fileno(),
                               stderr.fileno())
        # Read before it can end: the server reaps it only after reporting its status.
        stat = Path(f"/proc/{run.pid}/stat").read_text().rsplit(")", 1)[1].split()
        assert int(stat[1]) == server.pid  # forked by the server, not started by us
        assert int(stat[2]) == run.pid  # leading its own process group
        assert run.stop() in (0, 1, -signal.SIGKILL)
    finally:
        server.close()


# -- isolation -------------------------------------------------------------------------------


def test_a_warm_run_killed_by_sigkill_is_crashed_and_its_neighbour_finishes(
        plugins: Path, tmp_path: Path) -> None:
    workers = WarmWorkers()
    victim_dir, neighbour_dir = tmp_path / "victim", tmp_path / "neighbour"
    try:
        victim_thread, victim = in_thread(lambda: [execute_run(
            spec_of(EXAMPLES / "simple_wall", 600.0, "slow_controllers:Dawdling"), victim_dir,
            warm=workers)])
        neighbour_thread, neighbour = in_thread(lambda: [execute_run(
            spec_of(EXAMPLES / "small_dense", 2.0), neighbour_dir, warm=workers)])
        target = str(victim_dir / "campaign-stdout.txt")
        pids: list[int] = []

        def victim_started() -> bool:
            for pid in rei_runs(os.getpid()):
                try:
                    if os.readlink(f"/proc/{pid}/fd/1") == target:
                        pids.append(pid)
                except OSError:
                    pass
            return bool(pids) or not victim_thread.is_alive()

        wait_until(victim_started, "the victim's warm `rei run` process")
        assert pids, victim
        os.kill(pids[0], signal.SIGKILL)  # by the test, as the out-of-memory killer would
        victim_thread.join(SAFETY_LIMIT)
        neighbour_thread.join(SAFETY_LIMIT)
    finally:
        workers.close()
    killed, finished = victim[0][0], neighbour[0][0]
    assert killed.status == "crashed"
    assert killed.message.startswith("killed by signal 9 (SIGKILL; out of memory?)")
    assert finished.status == "ran", finished.message


def test_a_hung_warm_run_is_killed_and_the_server_serves_the_next(
        plugins: Path, tmp_path: Path) -> None:
    workers = WarmWorkers()
    try:
        def work() -> list[RunResult]:
            hung = execute_run(spec_of(EXAMPLES / "simple_wall", 60.0,
                                       "hanging_controllers:Hanging"),
                               tmp_path / "hung", timeout=2.0, warm=workers)
            servers.append(servers_of(os.getpid()))
            after = execute_run(spec_of(EXAMPLES / "simple_wall", 1.0), tmp_path / "after",
                                warm=workers)
            servers.append(servers_of(os.getpid()))
            return [hung, after]

        servers: list[set[int]] = []
        thread, results = in_thread(work)
        thread.join(SAFETY_LIMIT)
    finally:
        workers.close()
    hung, after = results[0]
    assert servers[0] and servers[0] == servers[1]  # the same server forked the next run
    assert hung.status == "hung" and "watchdog" in hung.message
    assert after.status == "ran", after.message


def test_a_dead_fork_server_crashes_its_run_and_is_replaced(
        plugins: Path, tmp_path: Path) -> None:
    workers = WarmWorkers()
    killed: list[int] = []
    try:
        def work() -> list[RunResult]:
            lost = execute_run(spec_of(EXAMPLES / "simple_wall", 600.0,
                                       "slow_controllers:Dawdling"), tmp_path / "lost",
                               warm=workers)
            after = execute_run(spec_of(EXAMPLES / "simple_wall", 1.0), tmp_path / "after",
                                warm=workers)
            return [lost, after]

        thread, results = in_thread(work)

        def running() -> bool:
            return bool(rei_runs(os.getpid())) or not thread.is_alive()

        wait_until(running, "the warm run")
        for server in servers_of(os.getpid()):
            os.kill(server, signal.SIGKILL)
            killed.append(server)
        thread.join(SAFETY_LIMIT)
        assert killed and not servers_of(os.getpid()) & set(killed)
    finally:
        workers.close()
    lost, after = results[0]
    assert lost.status == "crashed"
    assert "fork server, died" in lost.message, lost.message
    assert after.status == "ran", after.message
    assert b"fresh interpreter" not in (tmp_path / "after" / "campaign-stderr.txt").read_bytes()


# -- staleness -------------------------------------------------------------------------------


def test_changed_rei_code_is_never_served_from_a_warm_server(
        plugins: Path, tmp_path: Path) -> None:
    source = Path(warm_package.__file__)
    before = source.stat()
    workers = WarmWorkers()
    try:
        def work() -> list[RunResult]:
            first = execute_run(spec_of(EXAMPLES / "simple_wall", 1.0), tmp_path / "first",
                                warm=workers)
            servers.append(servers_of(os.getpid()))
            # An edit of REI's code (its modification time is what the fingerprint sees).
            os.utime(source, ns=(before.st_atime_ns, before.st_mtime_ns + 10**9))
            second = execute_run(spec_of(EXAMPLES / "simple_wall", 1.0), tmp_path / "second",
                                 warm=workers)
            servers.append(servers_of(os.getpid()))
            return [first, second]

        servers: list[set[int]] = []
        thread, results = in_thread(work)
        thread.join(SAFETY_LIMIT)
    finally:
        os.utime(source, ns=(before.st_atime_ns, before.st_mtime_ns))
        workers.close()
    first, second = results[0]
    assert servers[0] and servers[1], servers
    assert not servers[0] & servers[1], "the stale server forked the run after the edit"
    assert first.status == second.status == "ran", second.message


def test_a_changed_input_is_read_again_by_the_next_warm_run(
        plugins: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    suite = tmp_path / "suite"
    shutil.copytree(EXAMPLES / "simple_wall", suite)
    mission = suite / "simple_wall.mission"
    workers = WarmWorkers()
    try:
        def work() -> list[RunResult]:
            before = execute_run(spec_of(mission, 1.0), tmp_path / "before", warm=workers)
            mission.write_text(mission.read_text().replace("to_the_wall", "edited_mission"))
            after = execute_run(spec_of(mission, 1.0), tmp_path / "after", warm=workers)
            return [before, after]

        thread, results = in_thread(work)
        thread.join(SAFETY_LIMIT)
    finally:
        workers.close()
    before, after = results[0]
    assert before.status == after.status == "ran"
    assert after.summary is not None and after.summary["mission"] == "edited_mission"
    monkeypatch.setenv(WARM_VARIABLE, "off")
    cold = execute_run(spec_of(mission, 1.0), tmp_path / "cold")
    assert cold.status == "ran"
    for name in OUTPUTS:
        assert output_of(tmp_path / "after", name) == output_of(tmp_path / "cold", name), name
