"""The controller contract: every built-in controller passes the conformance checker."""

from __future__ import annotations

import pytest

from rei.runtime.errors import RunError
from rei.runtime.messages import NavState
from rei.runtime.robot import BUILT_IN, GoalTracker, NavGoal, check_controller, make_controller
from rei.runtime.robot.contract import IllegalTransition


@pytest.mark.parametrize("name", BUILT_IN)
def test_built_in_controllers_conform(name: str) -> None:
    assert check_controller(make_controller(name)) == []


@pytest.mark.parametrize("name", ["Raising", "NonFinite"])
def test_the_checker_reports_broken_controllers(name: str) -> None:
    problems = check_controller(make_controller(f"tests.robot.faulty:{name}"))
    assert problems and any(("raised" in p) or ("non-finite" in p) for p in problems)


def test_the_checker_reports_a_controller_that_never_finishes() -> None:
    problems = check_controller(make_controller("tests.robot.faulty:Idle"), steps=50)
    assert any("did not end" in p for p in problems)
    assert len(problems) == len(set(problems)), problems  # each broken promise said once


def test_unknown_names_say_what_was_expected() -> None:
    with pytest.raises(RunError, match="did you mean 'reference'"):
        make_controller("refrence")
    with pytest.raises(RunError, match="teleop script"):
        make_controller("teleop:spiral")
    with pytest.raises(RunError, match="cannot import module"):
        make_controller("no_such_module:Thing")
    with pytest.raises(RunError, match="has no 'Nothing'"):
        make_controller("tests.robot.faulty:Nothing")


def test_goal_tracker_follows_figure_22() -> None:
    tracker = GoalTracker()
    goal = NavGoal("g", 1.0, 0.0, None, 0.3, 10.0)
    assert tracker.state == NavState.IDLE
    with pytest.raises(IllegalTransition):
        tracker.accept()
    tracker.send(goal)
    assert tracker.state == NavState.PENDING
    tracker.accept()
    with pytest.raises(IllegalTransition):
        tracker.accept() if False else tracker._move(NavState.PENDING)
    tracker.cancel()
    assert tracker.state == NavState.PREEMPTED
    tracker.send(goal)
    tracker.accept()
    tracker.abort("blocked")
    assert tracker.feedback().message == "blocked"
    with pytest.raises(IllegalTransition):
        tracker.succeed()


def test_a_built_in_host_that_dies_while_starting_is_a_fault_naming_how() -> None:
    """A built-in controller's host is started without waiting for it (it loads while the
    world is built); a host that dies before it answered is the first call's fault."""
    import os
    import signal

    from rei.runtime.robot.host import HostedController
    from rei.runtime.robot.watchdog import ControllerFault

    hosted = HostedController("reference", timeout=30.0)
    try:
        os.killpg(hosted.pid, signal.SIGKILL)
        with pytest.raises(ControllerFault, match=r"killed by signal 9 \(SIGKILL\) during load"):
            hosted.feedback()
        with pytest.raises(ControllerFault):  # and it stays broken
            hosted.cancel_goal()
    finally:
        hosted.close()


def test_a_built_in_host_answers_its_name_once_loaded() -> None:
    hosted = make_controller("teleop:circle")
    try:
        assert hosted.name == "teleop:circle"
        assert hosted.feedback().state == NavState.IDLE
    finally:
        hosted.close()
