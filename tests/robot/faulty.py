"""Controllers that break the contract on purpose, for the watchdog and error tests.

They are importable as `tests.robot.faulty:NAME`, the way a user names their own controller.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
from typing import Any

import numpy as np

from rei.runtime.messages import LaserScan
from rei.runtime.robot import ControllerContext, GoalFeedback, NavGoal, Observation, VelocityCommand
from rei.runtime.robot.contract import GoalTracker


class _Base:
    name = "faulty"

    def __init__(self) -> None:
        self.tracker = GoalTracker()
        self.calls = 0
        self.scan: LaserScan | None = None

    def reset(self, context: ControllerContext) -> None:
        self.tracker = GoalTracker()
        self.calls = 0

    def send_goal(self, goal: NavGoal) -> None:
        self.tracker.send(goal)

    def cancel_goal(self) -> None:
        self.tracker.cancel()

    def feedback(self) -> GoalFeedback:
        return self.tracker.feedback()

    def step(self, observation: Observation) -> VelocityCommand:
        self.calls += 1
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.calls >= 20:
            return self.fault()
        return VelocityCommand(0.1, 0.0)

    def fault(self) -> VelocityCommand:
        raise NotImplementedError


class Hanging(_Base):
    """Sleeps forever at its 20th step."""

    def fault(self) -> VelocityCommand:
        threading.Event().wait()
        return VelocityCommand(0.0, 0.0)


class Raising(_Base):
    def fault(self) -> VelocityCommand:
        raise ValueError("the planner lost its map")


class NonFinite(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(float("nan"), 0.0)


class Interrupting(_Base):
    """Stands for the user pressing Ctrl-C during the run."""

    def fault(self) -> VelocityCommand:
        raise KeyboardInterrupt


class Slow(_Base):
    """Drives slowly in wall-clock time (10 ms per step), so a test can interrupt it."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        threading.Event().wait(0.01)
        return VelocityCommand(0.05, 0.1)


class Idle(_Base):
    """Accepts goals and never moves: every task times out."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        return VelocityCommand(0.0, 0.0)


class ClaimsSuccess(_Base):
    """Claims every goal at once without moving: the executor must check the ground truth."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.tracker.state.value == "active":
            self.tracker.succeed()
        return VelocityCommand(0.0, 0.0)


class AbortsAtOnce(_Base):
    """Accepts every goal and aborts it at once, standing still: it never touches anything,
    so only a requirement on the goals can tell that it did nothing."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        if self.tracker.state.value == "active":
            self.tracker.abort("no path to the goal")
        return VelocityCommand(0.0, 0.0)


# The misbehaving robots of the conformance suite (tests/robot/test_misbehaving_controllers.py):
# each breaks the contract at its 20th step (t = 1.9 s) in one way a real navigator might.


class StopsAtTwenty(_Base):
    """Drives like the others and stops at its 20th step: the honest twin of FalsifiesScanCopy."""

    def fault(self) -> VelocityCommand:
        return VelocityCommand(0.0, 0.0)


class SendsStr(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand("abc", 0.0)  # type: ignore[arg-type]


class SendsNone(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(0.1, None)  # type: ignore[arg-type]


class SendsComplex(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(0.1 + 0.5j, 0.0)  # type: ignore[arg-type]


class SendsHugeInt(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(10**400, 0.0)


class SendsArray(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(np.array([0.1, 0.2]), 0.0)  # type: ignore[arg-type]


class SendsBool(_Base):
    def fault(self) -> VelocityCommand:
        return VelocityCommand(True, 0.0)


class SendsTuple(_Base):
    """Answers a bare tuple instead of a VelocityCommand."""

    def fault(self) -> VelocityCommand:
        return (0.1, 0.0)  # type: ignore[return-value]


class SendsNumpyScalars(StopsAtTwenty):
    """Numpy scalars are real numbers: this one keeps the contract."""

    def step(self, observation: Observation) -> VelocityCommand:
        super().step(observation)
        return VelocityCommand(np.float32(0.1), np.int64(0))  # type: ignore[arg-type]


class BadFeedback(StopsAtTwenty):
    """Reports its goal state as a plain string once it is under way."""

    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback()
        if self.calls >= 19:  # asked before its 20th step
            return GoalFeedback("active", fb.goal)  # type: ignore[arg-type]
        return fb


class SurrogateFeedback(StopsAtTwenty):
    """Reports a message no file or terminal can hold (a lone surrogate)."""

    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback()
        if self.calls >= 19:
            return GoalFeedback(fb.state, fb.goal, fb.distance_remaining, "lost \ud800 map")
        return fb


class NaNFeedback(StopsAtTwenty):
    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback()
        if self.calls >= 19:  # asked before its 20th step
            return GoalFeedback(fb.state, fb.goal, float("nan"))
        return fb


class SpinsInPython(_Base):
    """A busy loop in Python: the call's watchdog sees it."""

    def fault(self) -> VelocityCommand:
        while True:
            pass


class HangsInC(_Base):
    """A loop in C that never releases the interpreter lock: only the supervisor sees it."""

    def fault(self) -> VelocityCommand:
        return VelocityCommand(float(sum(range(10**13))), 0.0)


class ExitsProcess(_Base):
    """Ends the simulation's process as if the run were over and fine."""

    def fault(self) -> VelocityCommand:
        os._exit(0)


class KillsProcess(_Base):
    def fault(self) -> VelocityCommand:
        os.kill(os.getpid(), signal.SIGKILL)
        return VelocityCommand(0.0, 0.0)


class CallsSysExit(_Base):
    def fault(self) -> VelocityCommand:
        sys.exit(0)


class MutatesScan(_Base):
    """Writes into the scan it was handed, to hide an obstacle from the recorded trace."""

    def fault(self) -> VelocityCommand:
        scan = self.scan
        assert scan is not None
        scan.ranges[:] = 3.5
        return VelocityCommand(0.0, 0.0)

    def step(self, observation: Observation) -> VelocityCommand:
        self.scan = observation.scan
        return super().step(observation)


class FalsifiesScanCopy(StopsAtTwenty):
    """Works around the read-only flag (through the copy's owner) and writes anyway: it only
    changes its own copy, never what the sensors recorded."""

    def step(self, observation: Observation) -> VelocityCommand:
        if observation.scan is not None:
            owner = observation.scan.ranges.base
            if owner is not None:
                owner.flags.writeable = True
                owner[:] = 0.0
        return super().step(observation)


class Chatty(StopsAtTwenty):
    """Prints its debugging on stdout, as navigators do."""

    def step(self, observation: Observation) -> VelocityCommand:
        print(f"chatty: step at t={observation.time:.1f}", flush=True)
        return super().step(observation)


class LeavesAThread(StopsAtTwenty):
    """Starts a thread that never ends (not a daemon): the run's result must still count."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        threading.Thread(target=threading.Event().wait, name="forever").start()


class InterruptsItself(_Base):
    """Raises KeyboardInterrupt from its own code: a fault of the controller, not a Ctrl-C."""

    def fault(self) -> VelocityCommand:
        raise KeyboardInterrupt


class AnswersHugeString(StopsAtTwenty):
    """Puts 2 MiB of text into its feedback's message: more than one answer may hold."""

    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback()
        if self.calls >= 19:  # asked before its 20th step
            return GoalFeedback(fb.state, fb.goal, None, "x" * (2 << 20))
        return fb


class RaisesInFeedback(StopsAtTwenty):
    """Its feedback raises once it has made 19 steps (asked before its 20th step)."""

    def feedback(self) -> GoalFeedback:
        if self.calls >= 19:
            raise RuntimeError("the goal's state is lost")
        return self.tracker.feedback()


class HangsInFeedback(StopsAtTwenty):
    """Its feedback sleeps forever once it has made 19 steps (asked before its 20th step)."""

    def feedback(self) -> GoalFeedback:
        if self.calls >= 19:
            threading.Event().wait()
        return self.tracker.feedback()


class Progressing(StopsAtTwenty):
    """An honest controller whose feedback changes with every step and every goal: what it
    has done, in its distance and message (a pure function of its state, as promised)."""

    def __init__(self) -> None:
        super().__init__()
        self.goals = 0

    def send_goal(self, goal: NavGoal) -> None:
        super().send_goal(goal)
        self.goals += 1

    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback(max(0.0, 5.0 - 0.1 * self.calls))
        return GoalFeedback(fb.state, fb.goal, fb.distance_remaining,
                            f"goal {self.goals}, step {self.calls}")


class ScanWitness(StopsAtTwenty):
    """Says in its feedback how many scan objects it was handed and what the last one held."""

    def __init__(self) -> None:
        super().__init__()
        self.scans: list[LaserScan] = []

    def step(self, observation: Observation) -> VelocityCommand:
        if observation.scan is not None and all(observation.scan is not s for s in self.scans):
            self.scans.append(observation.scan)
        return super().step(observation)

    def feedback(self) -> GoalFeedback:
        fb = self.tracker.feedback()
        last = self.scans[-1].ranges.tolist() if self.scans else None
        return GoalFeedback(fb.state, fb.goal, None, f"{len(self.scans)} {last}")


class KillsTheSimulation(_Base):
    """Kills the process that runs the simulation (its host's parent): only the supervisor
    can report it. A deliberate attack, which running as the same OS user allows."""

    def fault(self) -> VelocityCommand:
        os.kill(os.getppid(), signal.SIGKILL)
        return VelocityCommand(0.0, 0.0)


class KillsRei(_Base):
    """Kills `rei run` itself, the supervisor (its host's parent's parent), with SIGKILL:
    what a campaign's watchdog does to a hung run. Nothing of REI's can clean up then."""

    def fault(self) -> VelocityCommand:
        with open(f"/proc/{os.getppid()}/stat", encoding="ascii") as stat:
            supervisor = int(stat.read().rsplit(")", 1)[1].split()[1])
        os.kill(supervisor, signal.SIGKILL)
        return VelocityCommand(0.0, 0.0)


class StopsTheSimulation(_Base):
    """Stops the process that runs the simulation (SIGSTOP to its host's parent): a run
    that makes no progress, which only the supervisor sees."""

    def fault(self) -> VelocityCommand:
        os.kill(os.getppid(), signal.SIGSTOP)
        threading.Event().wait()
        return VelocityCommand(0.0, 0.0)


# The robots that try to falsify their own verdict (issue 13): each drives into the east wall
# of examples/simple_wall as WallDriver, its honest twin, does, so each must end with the
# same verdict (FAIL), never a pass.


class WallDriver(_Base):
    """Accepts every goal and drives straight ahead at 0.2 m/s, into the wall."""

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        return VelocityCommand(0.2, 0.0)


def _passed(data: dict[str, Any]) -> dict[str, Any]:
    """A summary's JSON as if the run had gone well and every requirement had passed."""
    data.update(verdict="pass", outcome="completed", reason="all tasks succeeded")
    for verdict in data.get("verdicts", []):
        if isinstance(verdict, dict):
            verdict["status"] = "pass"
    return data


def _all_pass(path: str) -> None:
    """Rewrite a summary.json as if every requirement had passed."""
    try:
        with open(path, encoding="utf-8") as stream:
            data = json.load(stream)
    except (OSError, ValueError):
        data = {}
    with open(path, "w", encoding="utf-8") as stream:
        json.dump(_passed(data), stream)


class PatchesTheEvaluator(WallDriver):
    """In reset(), patches REI's evaluator and verdicts in memory so that every one passes."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        import rei.runtime.observation.evaluator.summary as summary  # noqa: PLC0415
        import rei.runtime.results as results  # noqa: PLC0415

        original = summary.summary_text

        def passing(value: Any) -> str:
            return json.dumps(_passed(json.loads(original(value))))

        summary.summary_text = passing
        results.judge = lambda *args, **kwargs: "pass"


class RewritesSummaryAtExit(WallDriver):
    """Registers an atexit hook, and starts a thread, that rewrite OUT/summary.json as all
    pass (OUT from $REI_TEST_ATTACK_OUT, as a real attacker would find it)."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        import atexit  # noqa: PLC0415

        target = os.path.join(os.environ.get("REI_TEST_ATTACK_OUT", "."), "summary.json")
        atexit.register(_all_pass, target)

        def watch() -> None:
            while not os.path.exists(target):
                threading.Event().wait(0.005)
            threading.Event().wait(0.05)
            _all_pass(target)

        threading.Thread(target=watch, daemon=True).start()


class WritesExitEverywhere(WallDriver):
    """Writes the supervisor's "exit 0" report into every file descriptor it can find."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        for name in os.listdir("/proc/self/fd"):
            try:
                os.write(int(name), b'{"exit": 0}\n')
            except OSError:
                pass
