"""A robot under test cannot end, stall or falsify its own test (issue 13.2).

Every misbehaviour runs through the real `rei run` command in a subprocess, as a CI job runs
it: each must end with exit status 3 and a summary.json whose verdict is "error" and whose
reason names what the controller did. The controllers are in tests/robot/faulty.py; each
breaks the contract at its 20th control step (t = 1.9 s).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rei.runtime.robot.contract import (
    ContractViolation,
    GoalFeedback,
    VelocityCommand,
    checked_command,
    checked_feedback,
)
from rei.runtime.trace import read_trace, read_trace_end
from tests.conftest import EXAMPLES, REPO

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""


def rei_run(out: Path, controller: str, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o", str(out),
         "--duration", "5", "--controller", f"tests.robot.faulty:{controller}", *extra],
        cwd=REPO, capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)


def summary_of(out: Path) -> dict[str, object]:
    data: dict[str, object] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return data


MISBEHAVIOURS = [
    ("SurrogateFeedback", "feedback.message: expected a string of text, found str"),
    ("Raising", "step() raised ValueError: the planner lost its map"),
    ("SendsStr", "command.linear: expected a finite real number, found str 'abc'"),
    ("SendsNone", "command.angular: expected a finite real number, found NoneType None"),
    ("SendsComplex", "command.linear: expected a finite real number, found complex"),
    ("SendsHugeInt", "command.linear: expected a finite real number, found int of about 401 "
                     "digits (beyond float range)"),
    ("SendsArray", "command.linear: expected a finite real number, found numpy array of "
                   "shape (2,)"),
    ("SendsBool", "command.linear: expected a finite real number, found bool True"),
    ("SendsTuple", "command: expected a VelocityCommand, found tuple (0.1, 0.0)"),
    ("NonFinite", "step() sent a non-finite command: command.linear: expected a finite real "
                  "number, found nan"),
    ("BadFeedback", "feedback() sent an invalid feedback: feedback.state: expected a "
                    "NavState, found str 'active'"),
    ("NaNFeedback", "feedback.distance_remaining: expected a finite real number, found nan"),
    ("Hanging", "step() did not return within the watchdog's 0.5 s"),
    ("SpinsInPython", "step() did not return within the watchdog's 0.5 s"),
    # A hang in C holding the interpreter lock stalls only the controller's process now.
    ("HangsInC", "step() did not return within the watchdog's 0.5 s"),
    ("ExitsProcess", "the controller's process exited with status 0 during step()"),
    ("KillsProcess", "the controller's process was killed by signal 9 (SIGKILL) during step()"),
    ("CallsSysExit", "controller step() tried to end the process (SystemExit: 0)"),
    ("MutatesScan", "step() raised ValueError: assignment destination is read-only"),
    ("InterruptsItself", "controller step() raised KeyboardInterrupt"),
    ("AnswersHugeString", "controller feedback() sent an answer longer than 1048576 bytes"),
    # The feedback is computed after the step, in the controller's process; its faults are
    # still feedback()'s, reported when it is asked for (the next tick, t = 1.9 s).
    ("RaisesInFeedback", "controller feedback() raised RuntimeError: the goal's state is lost"),
    ("HangsInFeedback", "controller feedback() did not return within the watchdog's 0.5 s"),
    # Deliberate attacks on the simulation's process: the supervisor still reports them.
    ("KillsTheSimulation", "the simulation process was killed by signal 9 (SIGKILL) at "
                           "t≈1.9 s"),
    ("StopsTheSimulation", "the simulation stopped responding at t≈1.9 s: no progress for "
                           "5.5 s"),
]


@pytest.mark.parametrize(("controller", "reason"), MISBEHAVIOURS,
                         ids=[name for name, _ in MISBEHAVIOURS])
def test_a_misbehaving_controller_is_a_run_error_with_a_summary(
        controller: str, reason: str, tmp_path: Path) -> None:
    # Only the hangs need the watchdog short; the other faults get one no load can reach, so
    # a slow honest step on a loaded machine is never taken for the fault under test.
    short = "watchdog" in reason or controller == "StopsTheSimulation"
    done = rei_run(tmp_path, controller, "--watchdog", "0.5" if short else "30")
    assert done.returncode == 3, done.stderr
    summary = summary_of(tmp_path)
    assert summary["verdict"] == "error" and summary["outcome"] == "error"
    assert reason in str(summary["reason"]), summary["reason"]
    assert summary["mission"] == "to_the_elevator" and summary["room"] == "navigation"
    log = (tmp_path / "run.log").read_text(encoding="utf-8")
    assert "\nt=    1.900  error: " in log  # at the 20th control tick, whatever broke
    # the result is on stdout, and it is the same reason
    assert done.stdout.splitlines()[-1].startswith("verdict: ERROR (")
    assert reason in done.stdout
    assert "Traceback" not in done.stderr


def test_numpy_scalars_are_real_numbers_and_keep_the_contract(tmp_path: Path) -> None:
    done = rei_run(tmp_path, "SendsNumpyScalars", "--no-monitor", "--quiet")
    assert done.returncode == 0, done.stderr
    assert summary_of(tmp_path)["outcome"] == "timeout"
    rows = list(read_trace(tmp_path / "trace.jsonl")[1])
    assert rows[-1].belief.cmd == (pytest.approx(0.1), 0.0)


def test_a_controller_that_writes_into_its_scan_copy_changes_nothing_recorded(
        tmp_path: Path) -> None:
    """It works around the read-only flag; the trace still holds what the laser measured:
    byte for byte the trace of its honest twin (same commands, no writing)."""
    honest, faking = tmp_path / "honest", tmp_path / "faking"
    assert rei_run(honest, "StopsAtTwenty", "--quiet").returncode == 1
    assert rei_run(faking, "FalsifiesScanCopy", "--quiet").returncode == 1
    trace = (faking / "trace.jsonl").read_bytes()
    assert trace == (honest / "trace.jsonl").read_bytes()
    assert (faking / "events.csv").read_bytes() == (honest / "events.csv").read_bytes()
    scans = [s.belief.scan for s in read_trace(faking / "trace.jsonl")[1]]
    assert all(s is None or s.ranges.min() > 0.0 for s in scans)  # it wrote zeros


def test_a_hang_after_the_trace_began_leaves_the_partial_trace_and_a_log_line(
        tmp_path: Path) -> None:
    done = rei_run(tmp_path, "KillsTheSimulation")
    assert done.returncode == 3
    assert not (tmp_path / "trace.jsonl").exists()  # a trace that exists is complete
    assert (tmp_path / "trace.jsonl.partial").exists()
    assert read_trace_end(tmp_path / "trace.jsonl.partial") is None
    log = (tmp_path / "run.log").read_text(encoding="utf-8").splitlines()
    assert log[-1].startswith("t=    1.900  error: the simulation process was killed")


def test_a_stale_summary_of_an_earlier_run_never_survives_a_dead_run(tmp_path: Path) -> None:
    assert rei_run(tmp_path, "Idle", "--quiet").returncode == 1
    assert summary_of(tmp_path)["outcome"] == "timeout"
    assert rei_run(tmp_path, "KillsTheSimulation", "--quiet").returncode == 3
    assert summary_of(tmp_path)["outcome"] == "error"
    assert not (tmp_path / "events.csv").exists() and not (tmp_path / "report.html").exists()


@pytest.mark.parametrize(("command", "message"), [
    (VelocityCommand(0.1, 1j), "command.angular: expected a finite real number, found "  # type: ignore[arg-type]
                               "complex 1j"),
    (VelocityCommand(float("inf"), 0.0), "found inf"),
    (VelocityCommand(10**5000, 0.0), "int of about 5001 digits"),
    (None, "command: expected a VelocityCommand, found NoneType None"),
])
def test_checked_command_names_the_field(command: object, message: str) -> None:
    with pytest.raises(ContractViolation) as caught:
        checked_command(command)
    assert message in str(caught.value)


def test_checked_answers_are_plain_floats_and_states() -> None:
    import numpy as np

    from rei.runtime.messages import NavState

    cmd = checked_command(VelocityCommand(np.float32(0.25), 1))  # type: ignore[arg-type]
    assert type(cmd.linear) is float and type(cmd.angular) is float
    fb = checked_feedback(GoalFeedback(NavState.ACTIVE, "g", float("inf")))
    assert fb.distance_remaining == float("inf")
    with pytest.raises(ContractViolation, match="expected metres >= 0"):
        checked_feedback(GoalFeedback(NavState.ACTIVE, "g", -1.0))
    with pytest.raises(ContractViolation, match="feedback.message: expected a string"):
        checked_feedback(GoalFeedback(NavState.ACTIVE, "g", None, 3))  # type: ignore[arg-type]


def _start(out: Path, controller: str, temporary: Path | None = None
           ) -> subprocess.Popen[bytes]:
    """`rei run` with a slow controller, once its run is under way (a few samples traced);
    its temporary files in ``temporary`` when given."""
    env = None if temporary is None else {**os.environ, "TMPDIR": str(temporary)}
    process = subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o", str(out),
         "--controller", f"tests.robot.faulty:{controller}", "--quiet"],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    partial = out / "trace.jsonl.partial"
    started = time.monotonic()
    while process.poll() is None and (not partial.exists() or partial.stat().st_size < 20000):
        assert time.monotonic() - started < SAFETY_LIMIT
        time.sleep(0.05)
    return process


def test_sigterm_is_passed_on_and_ends_the_run_interrupted(tmp_path: Path) -> None:
    process = _start(tmp_path, "Slow")
    process.terminate()
    assert process.wait(timeout=SAFETY_LIMIT) == 130
    summary = summary_of(tmp_path)
    assert summary["outcome"] == "interrupted"
    end = read_trace_end(tmp_path / "trace.jsonl")
    assert end is not None and end[1] == "interrupted"


def test_the_simulation_dies_with_its_supervisor(tmp_path: Path) -> None:
    """kill -9 of `rei run` (a campaign's watchdog does it) leaves no simulation behind."""
    psutil = pytest.importorskip("psutil")
    # Killed with it, the supervisor cannot remove the run's temporary folder: keep it here.
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    process = _start(tmp_path / "out", "Slow", temporary)
    children = psutil.Process(process.pid).children()
    assert len(children) == 1
    process.kill()
    process.wait()
    gone, alive = psutil.wait_procs(children, timeout=SAFETY_LIMIT)
    assert not alive


def test_a_thread_left_running_does_not_cost_the_run_its_result(tmp_path: Path) -> None:
    done = rei_run(tmp_path, "LeavesAThread", "--quiet")
    assert done.returncode == 1, done.stderr  # timeout: inconclusive, as its honest twin
    assert summary_of(tmp_path)["outcome"] == "timeout"


def test_the_conformance_checker_reports_what_would_end_a_run_in_error() -> None:
    from rei.runtime.robot import check_controller
    from tests.robot import faulty

    assert "step() broke the contract: command.linear: expected a finite real number, " \
           "found str 'abc'" in check_controller(faulty.SendsStr())
    assert "feedback() broke the contract: feedback.state: expected a NavState, found str " \
           "'active'" in check_controller(faulty.BadFeedback())
    assert "raised ValueError: assignment destination is read-only" in \
           check_controller(faulty.MutatesScan())


def test_a_second_ctrl_c_stops_a_simulation_that_cannot_end_cleanly(tmp_path: Path) -> None:
    """The first Ctrl-C is passed on; a simulation stopped by its controller cannot hear it,
    so the second one kills the simulation and the run ends interrupted all the same."""
    process = subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o", str(tmp_path),
         "--controller", "tests.robot.faulty:StopsTheSimulation", "--watchdog", "60",
         "--quiet"],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    log = tmp_path / "run.log"
    started = time.monotonic()
    # the controller is stuck once the log shows the first task (t = 0) and a while has passed
    while process.poll() is None and (not log.exists() or "task_start" not in log.read_text()):
        assert time.monotonic() - started < SAFETY_LIMIT
        time.sleep(0.05)
    time.sleep(3.0)  # past its 20th step (t = 1.9 s simulated, well under a second of wall time)
    process.send_signal(signal.SIGINT)
    time.sleep(1.0)
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=SAFETY_LIMIT)
    assert process.returncode == 130
    assert summary_of(tmp_path)["outcome"] == "interrupted"
    assert out.splitlines()[-1].startswith("verdict: INTERRUPTED (interrupted by the user")


WALL = EXAMPLES / "simple_wall" / "simple_wall.mission"


def rei_run_wall(out: Path, controller: str) -> subprocess.CompletedProcess[str]:
    """`rei run` of the wall example, with $REI_TEST_ATTACK_OUT naming the output folder."""
    return subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(WALL), "-o", str(out),
         "--duration", "20", "--controller", f"tests.robot.faulty:{controller}", "--quiet"],
        cwd=REPO, capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False,
        env={**os.environ, "REI_TEST_ATTACK_OUT": str(out)})


@pytest.fixture(scope="module")
def honest_wall_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The honest twin: drives into the wall and fails."""
    out = tmp_path_factory.mktemp("honest")
    done = rei_run_wall(out, "WallDriver")
    assert done.returncode == 1, done.stderr
    assert summary_of(out)["verdict"] == "fail"
    return out


@pytest.mark.parametrize("controller", ["PatchesTheEvaluator", "RewritesSummaryAtExit"])
def test_a_controller_cannot_falsify_its_own_verdict(controller: str, honest_wall_run: Path,
                                                     tmp_path: Path) -> None:
    """It runs in its own process: patching REI's memory or hooking its own exit changes
    nothing the simulation writes. Same commands as its honest twin: the same bytes."""
    done = rei_run_wall(tmp_path, controller)
    assert done.returncode == 1, done.stderr
    assert done.stdout.startswith("verdict: FAIL")
    summary = summary_of(tmp_path)
    honest = summary_of(honest_wall_run)
    assert summary["verdict"] == "fail"
    assert summary["verdicts"] == honest["verdicts"]
    for name in ("trace.jsonl", "events.csv"):
        assert (tmp_path / name).read_bytes() == (honest_wall_run / name).read_bytes(), name


def test_a_controller_cannot_report_an_exit_status_for_the_simulation(tmp_path: Path) -> None:
    """Its process holds no descriptor of the supervisor's pipe; what it writes into its own
    answer pipe is nonsense to the simulation: a run error, never a pass."""
    done = rei_run_wall(tmp_path, "WritesExitEverywhere")
    assert done.returncode == 3, done.stderr
    summary = summary_of(tmp_path)
    assert summary["verdict"] == "error"
    assert "reset() answered nonsense" in str(summary["reason"]), summary["reason"]


def test_the_controllers_process_is_gone_when_the_run_ends(tmp_path: Path) -> None:
    """A hosted controller's whole process group is killed and reaped by close()."""
    from rei.runtime.robot import make_controller

    controller = make_controller("tests.robot.faulty:LeavesAThread", folder=str(REPO))
    pid = controller.pid
    controller.close()
    with pytest.raises(ProcessLookupError):
        os.killpg(pid, 0)


@pytest.mark.parametrize(("line", "message"), [
    (b'{"ok": [NaN, 0.0]}', "NaN is not a number"),
    (b'{"ok": [Infinity, 0.0]}', "Infinity is not a number"),
    (b'{"ok": 1, "raised": "x"}', "expected a JSON object with one key"),
    (b"\x80\x05K\x01.", "not a JSON answer"),  # a pickle is never read
    (b"[" * 100000, "not a JSON answer"),
    (b'{"ok": ' + b"1" * 5000 + b"}", "not a JSON answer"),
])
def test_answers_from_the_host_are_plain_json(line: bytes, message: str) -> None:
    from rei.runtime.robot.host import decode_answer

    with pytest.raises(ValueError, match=message):
        decode_answer(line)


def test_answers_are_decoded_into_what_the_contract_checks() -> None:
    from rei.runtime.messages import NavState
    from rei.runtime.robot.host import command_of, feedback_of

    fb = feedback_of({"state": "active", "goal": "g", "distance": "inf", "message": ""})
    assert fb == GoalFeedback(NavState.ACTIVE, "g", float("inf"), "")
    assert checked_feedback(fb) == fb
    assert command_of([0.1, 0]) == VelocityCommand(0.1, 0)
    for bad in ([True, 0.0], ["0.1", 0.0], [0.1], {"linear": 0.1}):
        with pytest.raises(ValueError, match="expected"):
            command_of(bad)
    for answer in ({"state": "flying", "goal": None, "distance": None, "message": ""},
                   {"state": ["active"], "goal": None, "distance": None, "message": ""},
                   {"state": "active", "goal": 3, "distance": None, "message": ""},
                   {"state": "active", "goal": None, "distance": "far", "message": ""},
                   {"state": "active"}):
        with pytest.raises(ValueError):
            feedback_of(answer)


def test_the_simulation_process_is_not_dumpable() -> None:
    # Other processes of the user (the robot under test among them) cannot open its
    # descriptors through /proc/PID/fd: the supervisor's pipe stays out of reach.
    if not sys.platform.startswith("linux"):
        pytest.skip("PR_SET_DUMPABLE is Linux's")
    code = ("import ctypes; from rei.runtime.platform.processes import keep_private; "
            "keep_private(); "
            "print(ctypes.CDLL(None).prctl(3, 0, 0, 0, 0))")  # PR_GET_DUMPABLE
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=SAFETY_LIMIT, check=True)
    assert done.stdout.strip() == "0"


@pytest.mark.parametrize("warm", ["on", "off"])
def test_a_simulation_killed_with_sigkill_leaves_no_temporary_folder(warm: str,
                                                                     tmp_path: Path) -> None:
    """Issue 25: the hosted controller's folder (rei-controller-*) is made in a folder the
    supervisor owns and removes, so a simulation process killed with SIGKILL (which cleans
    up nothing) leaves nothing in $TMPDIR; forked children (REI_WARM) and fresh ones alike."""
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o", str(out),
         "--duration", "5", "--controller", "tests.robot.faulty:KillsTheSimulation",
         "--quiet"],
        cwd=REPO, capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False,
        env={**os.environ, "TMPDIR": str(temporary), "REI_WARM": warm})
    assert done.returncode == 3, done.stderr
    assert "killed by signal 9 (SIGKILL)" in str(summary_of(out)["reason"])
    assert sorted(p.name for p in temporary.iterdir()) == []
