"""One call to the robot under test per control tick (issue 16, part 3).

The mission asks for the controller's feedback twice a tick (the executor, then the mission
component) before the robot's step. The controller's feedback is a pure function of its state
(the ``Controller`` contract), so the run computes it once per state: right after each step and
goal, in the robot's process (or the watchdog's worker thread), and answers every
``feedback()`` until the next state-changing call from it. These tests check that it is what a
fresh call would answer, after every kind of call, that the calls are as few as promised, and
that a feedback that raises or hangs is still the fault of ``feedback()`` when it is asked for.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tests.robot.faulty as faulty
from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.messages import LaserScan
from rei.runtime.robot import GoalFeedback, NavGoal, Observation
from rei.runtime.robot.host import HostedController
from rei.runtime.robot.watchdog import ControllerFault, GuardedController
from rei.runtime.simulation.assembly import RunConfig, generate_world, run_mission
from tests.conftest import EXAMPLES, REPO

GOAL = NavGoal("g", 1.0, 0.0, None, 0.3, 10.0)
OTHER = NavGoal("h", 2.0, 0.0, None, 0.3, 10.0)


def _observation(t: float) -> Observation:
    return Observation(t, (0.0, 0.0, 0.0), (0.0, 0.0), None)


Call = Callable[[Any], Any]
"""One call of the script, on a controller; what it answered (None for the goal calls)."""

SCRIPT: list[tuple[str, Call]] = [
    ("reset", lambda c: c.reset(None)),
    ("feedback", lambda c: c.feedback()),  # nothing computed it yet: asked for
    ("send_goal", lambda c: c.send_goal(GOAL)),
    ("feedback", lambda c: c.feedback()),
    *[entry for k in range(5) for entry in (
        ("feedback", lambda c: c.feedback()),
        ("feedback", lambda c: c.feedback()),
        ("step", lambda c, k=k: c.step(_observation(0.1 * k))),
    )],
    ("send_goal", lambda c: c.send_goal(OTHER)),  # preempts; nobody asked after the step
    ("step", lambda c: c.step(_observation(0.5))),
    ("cancel_goal", lambda c: c.cancel_goal()),  # nobody asked after the step either
    ("feedback", lambda c: c.feedback()),
    ("feedback", lambda c: c.feedback()),
    ("step", lambda c: c.step(_observation(0.6))),
    ("feedback", lambda c: c.feedback()),
]


def _answers(controller: Any) -> list[Any]:
    return [call(controller) for _, call in SCRIPT]


def _fresh() -> list[Any]:
    """What the controller answers called directly, every feedback computed when asked."""
    return _answers(faulty.Progressing())


class CountingHost(HostedController):
    """Counts the requests sent to the robot's process: one per round trip."""

    requests = 0

    def _send(self, data: bytes, deadline: float | None) -> bool:
        self.requests += 1
        return super()._send(data, deadline)


@pytest.fixture
def hosted() -> Iterator[CountingHost]:
    host = CountingHost("tests.robot.faulty:Progressing", str(REPO), timeout=30.0)
    try:
        yield host
    finally:
        host.close()


def test_a_hosted_controllers_feedback_is_what_a_fresh_call_answers(
        hosted: CountingHost) -> None:
    loaded = hosted.requests
    answers = _answers(hosted)
    assert answers == _fresh()
    feedbacks = [a for a in answers if isinstance(a, GoalFeedback)]
    assert [f.message for f in feedbacks][::2] == [
        "goal 0, step 0", "goal 1, step 0", "goal 1, step 1", "goal 1, step 2",
        "goal 1, step 3", "goal 1, step 4", "goal 2, step 6", "goal 2, step 7"]
    # asked only twice (before any step or goal; after the cancel), never after a step
    # or a goal
    calls = sum(1 for what, _ in SCRIPT if what != "feedback")
    assert hosted.requests - loaded == calls + 2


def test_a_hosted_controller_is_called_once_per_control_tick(tmp_path: Path) -> None:
    mission = generate_world(EXAMPLES / "navigation" / "navigation.mission", tmp_path / "world")
    manifest = load_manifest(tmp_path / "world")
    host = CountingHost("tests.robot.faulty:Progressing", str(REPO))
    loaded = host.requests
    try:
        record = run_mission(mission, manifest, load_monitor_config(tmp_path / "world"), host,
                             [], RunConfig(duration=3.0))
    finally:
        host.close()
    assert record.outcome == "timeout"
    ticks = 31  # t = 0.0 ... 3.0 at 10 Hz
    assert host.requests - loaded == 1 + 1 + ticks  # reset, the one goal, a step per tick


class Counted(faulty.Progressing):
    """Counts its feedback calls (which change nothing the feedback depends on)."""

    def __init__(self) -> None:
        super().__init__()
        self.asked = 0

    def feedback(self) -> GoalFeedback:
        self.asked += 1
        return super().feedback()


@pytest.mark.parametrize("timeout", [5.0, None], ids=["worker thread", "main thread"])
def test_an_in_process_controllers_feedback_is_computed_once_per_state(
        timeout: float | None) -> None:
    controller = Counted()
    guard = GuardedController(controller, timeout)
    try:
        assert _answers(guard) == _fresh()
    finally:
        guard.close()
    asked = sum(1 for what, _ in SCRIPT if what == "feedback")
    if timeout is None:  # asked when needed: once per state someone asked about
        assert controller.asked == 8 < asked
    else:  # the worker also computes it after each step and goal, asked for or not
        states = sum(1 for what, _ in SCRIPT if what in ("step", "send_goal"))
        assert controller.asked == states + 2 < asked


def _hosted(name: str) -> HostedController:
    """The faulty controller ``name`` in its own process, loaded, then watched for 0.5 s."""
    controller = HostedController(f"tests.robot.faulty:{name}", str(REPO))
    controller.timeout = 0.5  # as the watchdog sets it (a busy machine may load slowly)
    return controller


@pytest.mark.parametrize(("name", "reason"), [
    ("RaisesInFeedback", "controller feedback() raised RuntimeError: the goal's state is lost"),
    ("HangsInFeedback", "controller feedback() did not return within the watchdog's 0.5 s"),
    ("BadFeedback", "controller feedback() sent an invalid feedback: feedback.state"),
])
@pytest.mark.parametrize("where", ["hosted", "worker thread"])
def test_a_feedback_fault_is_raised_when_the_feedback_is_asked_for(
        name: str, reason: str, where: str) -> None:
    """Computed after the 19th step, it is reported at the 20th tick's feedback(), as if it
    had been computed then: not by the step that came before it."""
    controller: Any
    if where == "hosted":
        controller = _hosted(name)
    else:
        controller = GuardedController(getattr(faulty, name)(), 0.5)
    try:
        controller.reset(None)
        controller.send_goal(GOAL)
        for k in range(19):
            controller.feedback()
            controller.feedback()
            controller.step(_observation(0.1 * k))
        with pytest.raises(ControllerFault, match=reason.replace("(", r"\(").replace(")", r"\)")):
            controller.feedback()
        with pytest.raises(ControllerFault):  # and it stays broken
            controller.step(_observation(1.9))
    finally:
        controller.close()


@pytest.mark.parametrize("where", ["hosted", "worker thread"])
def test_a_feedback_nobody_asked_for_is_no_fault_unless_it_hangs(where: str) -> None:
    """After a step, a new goal comes before any feedback(): what the computed feedback said
    is dropped (no feedback was asked for), but a controller stuck in it is a fault."""
    for name, fault in (("RaisesInFeedback", None),
                        ("HangsInFeedback", r"feedback\(\) did not return")):
        controller: Any
        if where == "hosted":
            controller = _hosted(name)
        else:
            controller = GuardedController(getattr(faulty, name)(), 0.5)
        try:
            controller.reset(None)
            controller.send_goal(GOAL)
            for k in range(19):
                controller.step(_observation(0.1 * k))
            if fault is None:
                controller.send_goal(OTHER)
                controller.cancel_goal()
            else:
                with pytest.raises(ControllerFault, match=fault):
                    controller.send_goal(OTHER)
        finally:
            controller.close()


def test_a_scan_goes_to_the_robots_process_once_and_it_keeps_one_copy_per_scan() -> None:
    """The laser is slower than the control loop: the steps between two scans carry the same
    scan object, which the host keeps (one read-only copy per scan, as in-process)."""
    first = LaserScan(0.0, 0.5, 0.1, 8.0, np.array([1.0, 2.0]))
    second = LaserScan(0.0, 0.5, 0.1, 8.0, np.array([3.0, 4.0]))
    twin = LaserScan(0.0, 0.5, 0.1, 8.0, np.array([3.0, 4.0]))  # equal, another object
    host = CountingHost("tests.robot.faulty:ScanWitness", str(REPO), timeout=30.0)
    sizes: list[int] = []
    original = host._send

    def send(data: bytes, deadline: float | None) -> bool:
        sizes.append(len(data))
        return original(data, deadline)

    host._send = send  # type: ignore[method-assign]
    try:
        host.reset(None)  # type: ignore[arg-type]
        host.send_goal(GOAL)
        messages = []
        for t, scan in enumerate((None, first, first, second, second, twin, first)):
            host.step(Observation(0.1 * t, (0.0, 0.0, 0.0), (0.0, 0.0), scan))
            messages.append(host.feedback().message)
    finally:
        host.close()
    assert messages == ["0 None", "1 [1.0, 2.0]", "1 [1.0, 2.0]", "2 [3.0, 4.0]",
                        "2 [3.0, 4.0]", "3 [3.0, 4.0]", "4 [1.0, 2.0]"]
    steps = sizes[2:]
    assert steps[2] < steps[1] and steps[4] < steps[3]  # the same scan: not sent again
    assert steps[5] == steps[3] and steps[6] == steps[1]  # another object: sent
