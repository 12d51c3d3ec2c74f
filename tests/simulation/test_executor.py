"""The mission executor on its own: events, failure reasons and cycles (thesis 4.3.2, 6.1.4)."""

from __future__ import annotations

import math

import pytest

from rei.generators.concrete import ConcreteGoal
from rei.runtime.messages import NavState
from rei.runtime.robot import GoalFeedback, GoalTracker, NavGoal
from rei.runtime.simulation.mission import MissionExecutor


class ScriptedClient:
    """Ends each goal the way a script says: 'ok', 'abort' or 'hang' (never ends)."""

    def __init__(self, script: list[str]) -> None:
        self.script = script
        self.tracker = GoalTracker()
        self.sent: list[str] = []

    def send_goal(self, goal: NavGoal) -> None:
        self.tracker.send(goal)
        self.tracker.accept()
        self.sent.append(goal.name)
        what = self.script[len(self.sent) - 1]
        if what == "ok":
            self.tracker.succeed()
        elif what == "abort":
            self.tracker.abort("blocked")

    def cancel_goal(self) -> None:
        self.tracker.cancel()

    def feedback(self) -> GoalFeedback:
        return self.tracker.feedback()


def _goal(name: str, x: float) -> ConcreteGoal:
    return ConcreteGoal(name, name, x, 0.0, None, 0.3, 5.0)


def test_events_reasons_and_cycles() -> None:
    goals = (_goal("a", 0.0), _goal("b", 2.0))
    tasks = goals * 2  # cycles 2
    client = ScriptedClient(["ok", "abort", "hang", "ok"])
    executor = MissionExecutor(tasks)
    events = []
    time = 0.0
    while not executor.finished and time < 30:
        events += executor.tick(time, client, (0.0, 0.0, 0.0))
        time = round(time + 0.5, 1)
    kinds = [(e.kind, e.task, e.index) for e in events]
    assert kinds == [("begin", None, None),
                     ("task_start", "a", 0), ("task_success", "a", 0),
                     ("task_start", "b", 1), ("task_fail", "b", 1),
                     ("task_start", "a", 2), ("task_fail", "a", 2),
                     ("task_start", "b", 3), ("task_fail", "b", 3),
                     ("end", None, None)]
    reasons = [r.reason for r in executor.results]
    assert reasons[1] == "aborted: blocked"
    assert reasons[2] == "timeout after 5 s"
    assert client.tracker.state in (NavState.SUCCEEDED, NavState.PREEMPTED)
    # The last goal was claimed, but the robot stands 2 m away: ground truth decides.
    assert reasons[3].startswith("outside tolerance: the robot is 2.000 m")
    assert client.sent == ["a", "b", "a", "b"]
    causes = [e.cause for e in events if e.kind == "task_fail"]
    assert causes == ["aborted", "timeout", "position"]
    assert [r.cause for r in executor.results] == ["", "aborted", "timeout", "position"]
    assert all(e.cause == "" for e in events if e.kind != "task_fail")


def test_abandon_fails_the_running_task_and_ends() -> None:
    executor = MissionExecutor((_goal("a", 1.0),))
    client = ScriptedClient(["hang"])
    executor.tick(0.0, client, (0.0, 0.0, 0.0))
    events = executor.abandon(1.0, "interrupted", (0.0, 0.0, 0.0))
    assert [e.kind for e in events] == ["task_fail", "end"]
    assert (events[0].reason, events[0].cause) == ("interrupted", "abandoned")
    assert executor.finished and executor.abandon(2.0, "again", (0.0, 0.0, 0.0)) == []


@pytest.mark.parametrize(("heading_deg", "tolerance_deg", "yaw", "cause", "reason"), [
    (None, 15.0, 2.0, "", ""),  # no heading: any will do
    (90.0, 15.0, 0.0, "heading", "heading off by 90.0° (tolerance 15°)"),
    (10.0, 15.0, 0.0, "", ""),
    (15.0, 15.0, 0.0, "", ""),  # the tolerance itself still counts
    (-40.0, 45.0, 0.0, "", ""),
    (180.0, 15.0, -3.1, "", ""),  # the difference wraps round at ±180°
    (-170.0, 15.0, 2.8, "heading", "heading off by 29.6° (tolerance 15°)"),
])
def test_a_claimed_success_is_judged_by_the_heading_too(
        heading_deg: float | None, tolerance_deg: float, yaw: float, cause: str,
        reason: str) -> None:
    goal = ConcreteGoal("g", "g", 0.0, 0.0,
                        None if heading_deg is None else math.radians(heading_deg), 0.3, 5.0,
                        math.radians(tolerance_deg))
    executor = MissionExecutor((goal,))
    client = ScriptedClient(["ok"])
    executor.tick(0.0, client, (0.0, 0.0, yaw))
    events = executor.tick(0.1, client, (0.1, 0.0, yaw))
    assert executor.results[0].succeeded == (cause == "")
    assert (events[0].cause, events[0].reason) == (cause, reason)
    assert events[0].kind == ("task_success" if cause == "" else "task_fail")


def test_a_robot_in_the_wrong_place_fails_by_position_whatever_its_heading() -> None:
    goal = ConcreteGoal("g", "g", 1.0, 0.0, math.radians(90.0), 0.3, 5.0)
    executor = MissionExecutor((goal,))
    client = ScriptedClient(["ok"])
    executor.tick(0.0, client, (0.0, 0.0, 0.0))
    [fail, _end] = executor.tick(0.1, client, (0.0, 0.0, 0.0))
    assert fail.cause == "position" and fail.reason.startswith("outside tolerance")


def test_the_mission_ends_a_settle_period_after_its_last_task() -> None:
    client = ScriptedClient(["ok"])
    executor = MissionExecutor((_goal("a", 0.0),), settle=3.0)
    ends = {}
    time = 0.0
    while not executor.finished and time < 30:
        for e in executor.tick(time, client, (0.0, 0.0, 0.0)):
            ends[e.kind] = e.time
        assert executor.settling == (not executor.finished and "task_success" in ends)
        time = round(time + 0.1, 1)
    # the client succeeds at once; the executor sees it at its next tick
    assert ends["task_success"] == 0.1 and ends["end"] == pytest.approx(3.1)
    # a time limit in the settle period ends the mission as usual, failing nothing
    cut = MissionExecutor((_goal("a", 0.0),), settle=3.0)
    scripted = ScriptedClient(["ok"])
    cut.tick(0.0, scripted, (0.0, 0.0, 0.0))
    cut.tick(0.1, scripted, (0.0, 0.0, 0.0))
    assert cut.settling
    (end,) = cut.end_settled(1.0)
    assert (end.kind, end.time, end.reason) == ("end", 1.0, "") and cut.finished
    assert MissionExecutor((_goal("a", 0.0),)).end_settled(1.0) == []  # not settling: nothing
