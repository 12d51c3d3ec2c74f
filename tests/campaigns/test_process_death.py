"""Runs that die are recorded once as crashed; runs die with their campaign (issue 13, point 6).

Only the campaign's own decision (its stop request: Ctrl-C or SIGTERM of the campaign) makes a
run "interrupted" and unrecorded. A run killed by anyone else — kill -9, the out-of-memory
killer, a crash — is a finished run that did not pass, so re-running the campaign does not
keep exiting 130. And kill -9 of the campaign leaves no `rei run` behind.
"""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest

from rei.lang.cli_support import EXIT_RUN_ERROR
from rei.runtime.campaigns import CampaignStore, LocalEngine, plan_campaign, run_campaign
from rei.runtime.campaigns.execute import RUN_TEMPORARY, execute_run
from rei.runtime.commands.campaign import finish
from rei.runtime.platform.processes import start_child
from rei.runtime.runs.fork_server import WarmWorkers
from tests.conftest import REPO

from .conftest import require_rei_run
from .records import EXAMPLES

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="children die with their parent through Linux prctl")


def python(code: str) -> tuple[str, ...]:
    """A runner standing in for `rei run`: the run's arguments are appended and ignored."""
    return (sys.executable, "-c", code)


KILLS_ITSELF = python("import os, signal; os.kill(os.getpid(), signal.SIGKILL)")


def alive(pid: int, cmdline: bytes) -> bool:
    """The process ``pid`` still runs the command it ran (not a zombie, not a reused pid)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        now = Path(f"/proc/{pid}/cmdline").read_bytes()
    except (OSError, IndexError):
        return False
    return state != "Z" and now == cmdline


WARM_SERVER = b"rei.runtime.runs.fork_server\0"
"""In the command line of a campaign worker's fork server (rei.runtime.runs.fork_server), which
its forked `rei run` processes keep."""


def rei_runs(parent: int) -> dict[int, bytes]:
    """The live `rei run` processes of the campaign ``parent``, with their command lines:
    its children started as `rei run`, and the children of its workers' fork servers."""
    processes: dict[int, tuple[int, bytes]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            state, ppid = (entry / "stat").read_text().rsplit(")", 1)[1].split()[:2]
            cmdline = (entry / "cmdline").read_bytes()
        except (OSError, ValueError):
            continue
        if state != "Z":
            processes[int(entry.name)] = (int(ppid), cmdline)
    servers = {pid for pid, (ppid, cmdline) in processes.items()
               if ppid == parent and WARM_SERVER in cmdline}
    return {pid: cmdline for pid, (ppid, cmdline) in processes.items()
            if (ppid == parent and b"rei.runtime.commands\0run\0" in cmdline)
            or (ppid in servers and WARM_SERVER in cmdline)}


def wait_until(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + SAFETY_LIMIT
    while not condition():
        assert time.monotonic() < deadline, f"still waiting after {SAFETY_LIMIT:g} s: {what}"
        time.sleep(0.05)


# -- one run ---------------------------------------------------------------------------


def test_a_run_killed_with_sigkill_is_crashed_with_the_reason(tmp_path: Path) -> None:
    spec = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0).runs[0]
    result = execute_run(spec, tmp_path / "attempt", runner=KILLS_ITSELF)
    assert result.status == "crashed"
    assert result.exit_code == -signal.SIGKILL
    assert result.message.startswith("killed by signal 9 (SIGKILL; out of memory?)")


@pytest.mark.parametrize(("code", "reason"), [
    ("import os, signal; os.kill(os.getpid(), signal.SIGTERM)", "killed by signal 15 (SIGTERM)"),
    ("import os, signal; os.kill(os.getpid(), signal.SIGSEGV)", "killed by signal 11 (SIGSEGV)"),
    ("raise SystemExit(130)", "exit status 130, no summary.json"),
])
def test_any_end_the_campaign_did_not_ask_for_is_a_crash(tmp_path: Path, code: str,
                                                          reason: str) -> None:
    spec = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0).runs[0]
    result = execute_run(spec, tmp_path / "attempt", runner=python(code))
    assert result.status == "crashed"
    assert result.message.startswith(reason)


def test_only_the_campaigns_stop_request_makes_a_run_interrupted(tmp_path: Path) -> None:
    spec = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0).runs[0]
    stop = threading.Event()
    stop.set()
    result = execute_run(spec, tmp_path / "attempt", runner=python("import time; "
                                                                   "time.sleep(600)"),
                         stop=stop)
    assert result.status == "interrupted"
    assert result.message == "stopped by the campaign"


# Issue 25: a run's temporary files are in its work folder (its TMPDIR), removed however
# the run ended; `rei run` killed with SIGKILL (the watchdog's way) cannot remove them itself.
def test_a_runs_temporary_folder_is_removed_however_it_ended(tmp_path: Path) -> None:
    spec = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0).runs[0]
    made = tmp_path / "made.txt"
    runner = python("import os, signal, tempfile; d = tempfile.mkdtemp(prefix='rei-x-'); "
                    f"open({str(made)!r}, 'w').write(d); os.kill(os.getpid(), signal.SIGKILL)")
    result = execute_run(spec, tmp_path / "attempt", runner=runner)
    assert result.status == "crashed"
    folder = Path(made.read_text())
    assert folder.parent == (tmp_path / "attempt" / RUN_TEMPORARY).resolve()
    assert not folder.parent.exists()

    stop = threading.Event()
    made.unlink()
    hangs = python("import tempfile, time; d = tempfile.mkdtemp(prefix='rei-x-'); "
                   f"open({str(made)!r}, 'w').write(d); time.sleep(600)")
    waiter = threading.Thread(target=lambda: wait_until(made.exists, "the folder") or
                              stop.set())
    waiter.start()
    result = execute_run(spec, tmp_path / "again", runner=hangs, stop=stop)
    waiter.join()
    assert result.status == "interrupted"
    assert not Path(made.read_text()).exists() and not (tmp_path / "again" / ".tmp").exists()


@linux_only
@pytest.mark.parametrize("warm", [True, False])
def test_rei_run_killed_with_sigkill_leaves_no_temporary_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, warm: bool) -> None:
    """A real `rei run` (forked by a fork server, or a fresh interpreter) killed with SIGKILL
    mid-run: its supervisor's folder and the controller's, in the run's TMPDIR, are gone."""
    require_rei_run()
    elsewhere = tmp_path / "tmp"  # the campaign's own TMPDIR: nothing of the run's lands here
    elsewhere.mkdir()
    monkeypatch.setenv("TMPDIR", str(elsewhere))
    monkeypatch.delenv("REI_WARM", raising=False)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(REPO),
                                                      os.environ.get("PYTHONPATH", "")]))
    spec = replace(plan_campaign([EXAMPLES / "simple_wall"], duration=5.0).runs[0],
                   controller="tests.robot.faulty:KillsRei")
    workers = WarmWorkers() if warm else None
    try:
        result = execute_run(spec, tmp_path / "attempt", warm=workers)
    finally:
        if workers is not None:
            workers.close()
    assert result.status == "crashed", result.message
    assert result.exit_code == -signal.SIGKILL
    stderr = (tmp_path / "attempt" / "campaign-stderr.txt").read_text()
    if warm:
        assert "fresh interpreter" not in stderr, stderr  # it was forked by the server
    assert sorted(p.name for p in elsewhere.iterdir()) == []
    assert not (tmp_path / "attempt" / RUN_TEMPORARY).exists()


@linux_only
def test_what_a_run_started_dies_when_the_run_ends(tmp_path: Path) -> None:
    spec = plan_campaign([EXAMPLES / "simple_wall"], duration=2.0).runs[0]
    pid_file = tmp_path / "grandchild.pid"
    runner = python("import subprocess, sys; "
                    "p = subprocess.Popen(['sleep', '600']); "
                    f"open({str(pid_file)!r}, 'w').write(str(p.pid))")
    result = execute_run(spec, tmp_path / "attempt", runner=runner)
    assert result.status == "crashed"  # it wrote no summary
    grandchild = int(pid_file.read_text())
    cmdline = b"sleep\x00600\x00"
    wait_until(lambda: not alive(grandchild, cmdline), "the run's own child to die")


@linux_only
def test_a_child_dies_with_the_thread_that_started_it() -> None:
    started: list[subprocess.Popen[bytes]] = []
    thread = threading.Thread(target=lambda: started.append(start_child(["sleep", "600"])))
    thread.start()
    thread.join()
    (child,) = started
    assert child.wait(timeout=SAFETY_LIMIT) == -signal.SIGKILL


# -- the campaign ----------------------------------------------------------------------


def test_crashed_runs_complete_the_campaign_which_exits_3_not_130(tmp_path: Path) -> None:
    plan = plan_campaign([EXAMPLES / "simple_wall", EXAMPLES / "small_dense"], duration=2.0)
    root = tmp_path / "campaign"
    engine = LocalEngine(2, runner=KILLS_ITSELF)
    for session in range(2):  # the re-run finds every run recorded and runs nothing
        result = run_campaign(plan, root, engine, {}, stream=io.StringIO())
        assert result.complete
        assert result.ran_now == (2 if session == 0 else 0)
        assert finish(root, no_report=True) == EXIT_RUN_ERROR  # crashed runs: run errors
    records = CampaignStore.read(root)[2]
    assert [r.status for r in records] == ["crashed", "crashed"]
    assert all(r.verdict == "error" for r in records)
    assert all("SIGKILL; out of memory?" in r.message for r in records)


SLOW_CONTROLLER = """
import time

from rei.runtime.robot.navigator.reference import ReferenceNavigator


class Dawdling(ReferenceNavigator):
    \"\"\"Drives as the reference does, a fifth of a second per call: a run that is still
    going when the test looks for it.\"\"\"

    def step(self, observation):
        time.sleep(0.2)
        return super().step(observation)
"""


def start_campaign(tmp_path: Path, duration: str) -> tuple[list[str], dict[str, str]]:
    """The command and environment of a real campaign of 2 runs with a slow controller."""
    plugins = tmp_path / "plugins"
    plugins.mkdir(exist_ok=True)
    (plugins / "slow_controllers.py").write_text(SLOW_CONTROLLER)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(plugins), os.environ.get("PYTHONPATH", "")])}
    argv = [sys.executable, "-m", "rei.runtime.commands", "campaign",
            str(EXAMPLES / "simple_wall"), str(EXAMPLES / "small_dense"),
            "-o", str(tmp_path / "campaign"), "--workers", "2", "--duration", duration,
            "--controller", "slow_controllers:Dawdling", "--no-report"]
    return argv, env


@linux_only
@pytest.mark.slow
def test_kill_9_of_the_campaign_leaves_no_run_behind(tmp_path: Path) -> None:
    require_rei_run()
    argv, env = start_campaign(tmp_path, "600")
    campaign = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
    runs: dict[int, bytes] = {}
    try:
        def both_started() -> bool:
            runs.update(rei_runs(campaign.pid))
            return len(runs) == 2 or campaign.poll() is not None

        wait_until(both_started, "two `rei run` processes")
        assert len(runs) == 2, f"the campaign ended early ({campaign.returncode})"
    finally:
        os.kill(campaign.pid, signal.SIGKILL)  # the campaign only, as the OOM killer would
        campaign.wait()
    try:
        wait_until(lambda: not any(alive(pid, line) for pid, line in runs.items()),
                   "the runs of a killed campaign to die")
    finally:
        for pid, line in runs.items():  # never leave them running, even when the test fails
            if alive(pid, line):
                os.kill(pid, signal.SIGKILL)


@linux_only
@pytest.mark.slow
def test_a_run_killed_by_sigkill_is_recorded_crashed_once_and_rerun_is_not_130(
        tmp_path: Path) -> None:
    require_rei_run()
    out = tmp_path / "campaign"
    argv, env = start_campaign(tmp_path, "2")
    campaign = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, start_new_session=True)
    victims: dict[int, bytes] = {}

    def started() -> bool:
        victims.update(rei_runs(campaign.pid))
        return bool(victims) or campaign.poll() is not None

    wait_until(started, "a `rei run` process")
    victim = min(victims)
    os.kill(victim, signal.SIGKILL)  # by the test, not by the campaign
    _, err = campaign.communicate(timeout=SAFETY_LIMIT)
    assert campaign.returncode == EXIT_RUN_ERROR, err  # the crashed run is a run error
    records = CampaignStore.read(out)[2]
    assert len(records) == 2
    crashed = [r for r in records if r.status == "crashed"]
    assert len(crashed) == 1, [(r.status, r.message) for r in records]
    assert crashed[0].message.startswith("killed by signal 9 (SIGKILL; out of memory?)")
    rerun = subprocess.run(argv, env=env, capture_output=True, text=True,
                           timeout=SAFETY_LIMIT)
    assert rerun.returncode == EXIT_RUN_ERROR, rerun.stderr
    assert "2 of 2 runs already recorded" in rerun.stderr
    assert len(CampaignStore.read(out)[2]) == 2


@linux_only
@pytest.mark.slow
def test_sigterm_stops_the_campaign_like_ctrl_c(tmp_path: Path) -> None:
    require_rei_run()
    argv, env = start_campaign(tmp_path, "600")
    campaign = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True, start_new_session=True)
    runs: dict[int, bytes] = {}

    def started() -> bool:
        runs.update(rei_runs(campaign.pid))
        return len(runs) == 2 or campaign.poll() is not None

    wait_until(started, "two `rei run` processes")
    campaign.terminate()  # a cancelled CI job
    _, err = campaign.communicate(timeout=SAFETY_LIMIT)
    assert campaign.returncode == 130, err
    assert "Run the same command again" in err and "Traceback" not in err
    assert not any(alive(pid, line) for pid, line in runs.items())
    assert CampaignStore.read(tmp_path / "campaign")[2] == []  # stopped runs are not recorded
