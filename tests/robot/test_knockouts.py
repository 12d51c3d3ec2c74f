"""The knock-out families of the bug-finding benchmark (bench/knockouts): each wrapper does what
its family says, at the level of single steps around a fake navigator that records what it is
told and shown; every knock-out keeps the controller contract around the reference (the
checker) and around the fake (the boundary checks); and one `rei run` drives a knock-out in a
real run, around a base chosen by REI_KNOCKOUT_BASE.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import bench.knockouts as knockouts
from bench.knockouts import BASE_VARIABLE, FAMILIES, KNOCKOUTS, UnknownKnockout, make, parse
from bench.knockouts.recovery import AbortsRecovery
from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan, NavState
from rei.runtime.robot import check_controller, load_controller
from rei.runtime.robot.behaviours import doing_message, reported
from rei.runtime.robot.conformance import checker_context
from rei.runtime.robot.contract import (
    STOP,
    ContractViolation,
    ControllerContext,
    GoalFeedback,
    GoalTracker,
    NavGoal,
    Observation,
    VelocityCommand,
    checked_command,
    checked_feedback,
)
from rei.runtime.robot.navigator.reference import ReferenceNavigator
from rei.runtime.robot.teleop import TeleopController
from tests.conftest import EXAMPLES, REPO

BEAMS = 360
"""The fake laser: one beam a degree over the full circle from -pi, 0.12-3.5 m."""
GOAL = NavGoal("far", 3.0, 0.0, None, 0.3, 60.0)


class FakeNavigator:
    """A navigator that answers its k-th step (from 0, counted from reset) with the command
    (k/100, -k/100) while a goal runs, reports ``doing[k]`` as its behaviours at step k, and
    records every context, goal and observation it is given."""

    name = "fake"

    def __init__(self, doing: dict[int, tuple[str, ...]] | None = None) -> None:
        self.doing = doing or {}
        self.contexts: list[ControllerContext] = []
        self.goals: list[NavGoal] = []
        self.seen: list[Observation] = []
        self.cancels = 0
        self._tracker = GoalTracker()
        self._steps = 0
        self._message = ""

    def reset(self, context: ControllerContext) -> None:
        self.contexts.append(context)
        self._tracker, self._steps, self._message = GoalTracker(), 0, ""

    def send_goal(self, goal: NavGoal) -> None:
        self.goals.append(goal)
        self._tracker.send(goal)

    def cancel_goal(self) -> None:
        self.cancels += 1
        self._tracker.cancel()

    def feedback(self) -> GoalFeedback:
        found = self._tracker.feedback()
        return replace(found, message=self._message) if self._tracker.running else found

    def step(self, observation: Observation) -> VelocityCommand:
        self.seen.append(observation)
        k, self._steps = self._steps, self._steps + 1
        if self._tracker.state == NavState.PENDING:
            self._tracker.accept()
        self._message = doing_message(self.doing.get(k, ()))
        return VelocityCommand(k / 100, -k / 100) if self._tracker.running else STOP


def laser_scan(ranges: float | np.ndarray = 1.0) -> LaserScan:
    step = 2 * math.pi / BEAMS
    return LaserScan(-math.pi, step, 0.12, 3.5,
                     np.broadcast_to(np.asarray(ranges, dtype=float), (BEAMS,)).copy())


def observation(t: float, scan: LaserScan | None = None,
                pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Observation:
    return Observation(t, pose, (0.0, 0.0), scan, None if scan is None else t)


def wrapped(name: str, seed: int = 0, goal: NavGoal = GOAL,
            doing: dict[int, tuple[str, ...]] | None = None,
            context: ControllerContext | None = None) -> tuple[knockouts.Wrapper, FakeNavigator]:
    fake = FakeNavigator(doing)
    knockout = make(name, fake)
    knockout.reset(replace(context or checker_context(), seed=seed))
    knockout.send_goal(goal)
    return knockout, fake


def drive(knockout: knockouts.Wrapper, steps: int, dt: float = 0.1,
          scans: bool = True) -> list[VelocityCommand]:
    return [knockout.step(observation(k * dt, laser_scan() if scans else None))
            for k in range(steps)]


def inner_command(k: int) -> VelocityCommand:
    return VelocityCommand(k / 100, -k / 100)


# -- the registry and the names ------------------------------------------------------------

def test_every_family_has_graded_severities_and_every_name_is_unique() -> None:
    assert len(FAMILIES) >= 8
    for family in FAMILIES:
        assert len(family.severities) >= 3 and len(set(family.severities)) == len(
            family.severities), family.name
        low, high = family.limits
        assert all(low <= s <= high for s in family.severities), family.name
    assert len({k.name for k in KNOCKOUTS}) == len(KNOCKOUTS)
    assert len(KNOCKOUTS) == sum(len(f.severities) for f in FAMILIES)


@pytest.mark.parametrize("knockout", KNOCKOUTS, ids=lambda k: k.name)
def test_every_knockout_loads_as_a_controller_spec(knockout: knockouts.Knockout) -> None:
    controller = load_controller(knockout.spec)
    assert controller.name == knockout.name
    assert isinstance(controller, knockouts.Wrapper)
    doc = type(controller).__doc__ or ""
    assert doc.startswith("Defect: ") and "Imitates: " in doc and "Expected catcher: " in doc


def test_a_severity_off_the_table_loads_and_one_out_of_range_does_not() -> None:
    assert isinstance(load_controller("bench.knockouts:footprint_45"), knockouts.Wrapper)
    assert parse("delay_250")[1] == 250
    with pytest.raises(UnknownKnockout, match="1 to 100, found 0"):
        parse("footprint_0")
    with pytest.raises(UnknownKnockout, match="expected FAMILY_SEVERITY"):
        parse("footprnt_50")
    with pytest.raises(RunError, match="has no 'footprint_0'"):
        load_controller("bench.knockouts:footprint_0")
    with pytest.raises(AttributeError):
        knockouts.__wrapped__  # noqa: B018  (introspection must not make a controller)


def test_the_base_is_the_reference_unless_rei_knockout_base_names_another(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(BASE_VARIABLE, raising=False)
    assert type(make("delay_100").inner).__name__ == "ReferenceNavigator"
    monkeypatch.setenv(BASE_VARIABLE, "teleop:circle")
    knockout = make("delay_100")
    assert isinstance(knockout.inner, TeleopController)
    assert knockout.name == f"delay_100({knockout.inner.name})"
    monkeypatch.setenv(BASE_VARIABLE, "no_such_navigator")
    with pytest.raises(RunError, match="no_such_navigator"):
        make("delay_100")
    monkeypatch.setenv(BASE_VARIABLE, "bench.knockouts:held_10")
    with pytest.raises(RunError, match="found the knock-out 'bench.knockouts:held_10'"):
        make("delay_100")
    assert make("delay_100", make("held_10", FakeNavigator())).inner.name == "held_10(fake)"


# -- the contract ----------------------------------------------------------------------------

@pytest.mark.parametrize("knockout", KNOCKOUTS, ids=lambda k: k.name)
def test_every_knockout_around_the_reference_keeps_the_contract(
        knockout: knockouts.Knockout) -> None:
    assert check_controller(make(knockout.name)) == []


@pytest.mark.parametrize("knockout", KNOCKOUTS, ids=lambda k: k.name)
def test_every_knockout_answers_what_the_boundary_accepts_and_its_feedback_is_pure(
        knockout: knockouts.Knockout) -> None:
    """Around the fake (which reports recoveries at steps 5-9 and 20-24), every command and
    feedback passes the run's boundary checks, and asking for feedback three times a step
    changes neither the feedback nor the commands."""
    doing = {k: ("recovery.backup",) for k in (*range(5, 10), *range(20, 25))}
    answers = []
    for asks in (1, 3):
        controller, _ = wrapped(knockout.name, seed=7, doing=doing)
        found = []
        for k in range(40):
            command = checked_command(controller.step(observation(0.1 * k, laser_scan())))
            feedback = [checked_feedback(controller.feedback()) for _ in range(asks)]
            assert all(f == feedback[0] for f in feedback)
            found.append((command, feedback[0]))
        answers.append(found)
    assert answers[0] == answers[1]


def test_the_boundary_checks_can_fail() -> None:
    with pytest.raises(ContractViolation):
        checked_command(VelocityCommand(math.nan, 0.0))


# -- what each family does ---------------------------------------------------------------------

@pytest.mark.parametrize("percent", [30, 50, 70, 90])
def test_footprint_tells_the_navigator_a_scaled_robot(percent: int) -> None:
    _, fake = wrapped(f"footprint_{percent}")
    real = checker_context().robot_size
    told = fake.contexts[-1].robot_size
    assert told == pytest.approx((real[0] * percent / 100, real[1] * percent / 100))
    assert fake.contexts[-1].drive == checker_context().drive


@pytest.mark.parametrize(("milliseconds", "dt", "ticks"),
                         [(100, 0.1, 1), (200, 0.1, 2), (300, 0.1, 3), (500, 0.1, 5),
                          (100, 0.05, 2), (250, 0.1, 3)])
def test_delay_releases_each_command_exactly_that_late(milliseconds: int, dt: float,
                                                        ticks: int) -> None:
    """The command of the newest tick at least the delay old: STOP until the first is."""
    knockout, _ = wrapped(f"delay_{milliseconds}")
    commands = drive(knockout, 30, dt)
    assert commands[:ticks] == [STOP] * ticks
    assert commands[ticks:] == [inner_command(k) for k in range(30 - ticks)]


@pytest.mark.parametrize("degrees", [15, 30, 60, 90])
def test_blind_sector_reads_max_range_in_a_sector_of_its_width_ahead(degrees: int) -> None:
    knockout, fake = wrapped(f"blind_{degrees}")
    raw = laser_scan(1.0)
    knockout.step(observation(0.0, raw))
    seen = fake.seen[-1].scan
    assert seen is not None and seen is not raw
    bearings = np.degrees(raw.angle_min + raw.angle_increment * np.arange(BEAMS))
    blind = seen.ranges == seen.range_max
    assert (np.abs(bearings[blind]) <= degrees / 2 + 1e-6).all()
    assert (seen.ranges[~blind] == 1.0).all()
    assert blind.sum() == 2 * (degrees // 2) + 1  # one beam a degree, both edges included
    assert (raw.ranges == 1.0).all() and not seen.ranges.flags.writeable


def test_blind_sector_hands_a_scan_seen_again_as_the_same_object() -> None:
    knockout, fake = wrapped("blind_30")
    raw = laser_scan(1.0)
    knockout.step(Observation(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), raw, 0.0))
    knockout.step(Observation(0.1, (0.0, 0.0, 0.0), (0.0, 0.0), raw, 0.0))
    assert fake.seen[0].scan is fake.seen[1].scan


def _noisy_ranges(name: str, seed: int, raw: LaserScan, scans: int = 3) -> list[np.ndarray]:
    knockout, fake = wrapped(name, seed=seed)
    for k in range(scans):
        knockout.step(observation(0.1 * k, raw))
    return [np.array(o.scan.ranges) for o in fake.seen if o.scan is not None]


@pytest.mark.parametrize("millimetres", [20, 50, 100, 200])
def test_laser_noise_has_its_sigma_on_hits_and_leaves_nothing_seen_alone(
        millimetres: int) -> None:
    ranges = np.where(np.arange(BEAMS) % 2 == 0, 2.0, 3.5)  # every other beam sees nothing
    raw = laser_scan(ranges)
    noisy = np.concatenate([r - ranges for r in _noisy_ranges(f"noise_{millimetres}", 3, raw,
                                                                scans=20)])
    hits = np.tile(ranges, 20) == 2.0
    sigma = millimetres / 1000
    assert np.std(noisy[hits]) == pytest.approx(sigma, rel=0.1)
    assert (noisy[~hits] == 0.0).all()
    assert (raw.ranges == ranges).all()


def test_laser_noise_keeps_ranges_within_the_lasers_limits() -> None:
    raw = laser_scan(np.linspace(0.12, 3.49, BEAMS))
    for ranges in _noisy_ranges("noise_200", 1, raw, scans=5):
        assert (ranges >= raw.range_min).all() and (ranges <= raw.range_max).all()


def test_laser_noise_is_seeded_by_the_run_drawn_once_per_scan_and_new_each_scan() -> None:
    raw = laser_scan(1.5)
    first, again, other = (_noisy_ranges("noise_50", s, raw) for s in (11, 11, 12))
    assert all((a == b).all() for a, b in zip(first, again, strict=True))
    assert not (first[0] == other[0]).all()
    assert not (first[0] == first[1]).all()  # each scan its own noise
    knockout, fake = wrapped("noise_50", seed=11)
    knockout.step(Observation(0.0, (0.0, 0.0, 0.0), (0.0, 0.0), raw, 0.0))
    knockout.step(Observation(0.1, (0.0, 0.0, 0.0), (0.0, 0.0), raw, 0.0))  # the same scan
    assert fake.seen[0].scan is fake.seen[1].scan


@pytest.mark.parametrize(("family", "percent"), [("held", 10), ("held", 50), ("dropped", 25),
                                                 ("dropped", 75)])
def test_held_and_dropped_miss_that_share_of_ticks_and_do_what_their_name_says(
        family: str, percent: int) -> None:
    knockout, _ = wrapped(f"{family}_{percent}", seed=5)
    commands = drive(knockout, 2000, scans=False)
    missed = [k for k, c in enumerate(commands) if c != inner_command(k)]
    assert len(missed) / len(commands) == pytest.approx(percent / 100, abs=0.03)
    for k in missed:
        expected = (commands[k - 1] if k else STOP) if family == "held" else STOP
        assert commands[k] == expected


def test_held_and_dropped_are_seeded_by_the_run() -> None:
    def commands(name: str, seed: int) -> list[VelocityCommand]:
        return drive(wrapped(name, seed=seed)[0], 200, scans=False)

    assert commands("held_25", 1) == commands("held_25", 1)
    assert commands("held_25", 1) != commands("held_25", 2)
    assert commands("dropped_25", 1) != commands("held_25", 1)


@pytest.mark.parametrize("percent", [150, 200, 300, 400])
def test_goal_tolerance_is_scaled_and_a_goal_succeeds_within_the_scaled_one(
        percent: int) -> None:
    scaled = GOAL.tolerance * percent / 100
    inside, outside = GOAL.x - scaled + 0.01, GOAL.x - scaled - 0.01
    knockout, fake = wrapped(f"tolerance_{percent}")
    assert fake.goals[-1] == replace(GOAL, tolerance=pytest.approx(scaled))
    knockout.step(observation(0.0, pose=(outside, 0.0, 0.0)))
    assert knockout.step(observation(0.1, pose=(outside, 0.0, 0.0))) != STOP
    assert knockout.feedback().state == NavState.ACTIVE
    assert knockout.step(observation(0.2, pose=(inside, 0.0, 0.0))) == STOP
    assert knockout.feedback() == GoalFeedback(NavState.SUCCEEDED, GOAL.name,
                                               pytest.approx(scaled - 0.01), "")
    assert fake.cancels == 1
    knockout.cancel_goal()  # an ended goal stays ended
    assert knockout.feedback().state == NavState.SUCCEEDED and fake.cancels == 1


def test_goal_tolerance_leaves_a_goal_with_a_heading_to_the_navigator() -> None:
    goal = replace(GOAL, yaw=0.0)
    knockout, fake = wrapped("tolerance_400", goal=goal)
    assert fake.goals[-1].tolerance == pytest.approx(4 * goal.tolerance)
    for k in range(3):
        knockout.step(observation(0.1 * k, pose=(goal.x - 0.05, 0.0, 0.0)))
    assert knockout.feedback().state == NavState.ACTIVE


@pytest.mark.parametrize("percent", [5, 10, 25, 50])
def test_overspeed_raises_the_mission_speed_limit_and_never_the_drives(percent: int) -> None:
    limited = replace(checker_context(), max_speed=0.2)
    _, fake = wrapped(f"overspeed_{percent}", context=limited)
    assert fake.contexts[-1].max_speed == pytest.approx(0.2 * (1 + percent / 100))
    assert fake.contexts[-1].drive == limited.drive
    _, free = wrapped(f"overspeed_{percent}")
    assert free.contexts[-1] == replace(checker_context(), seed=0)


RECOVERIES = {**{k: ("recovery.replan",) for k in range(5, 8)},
              **{k: ("recovery.backup", "back_up") for k in range(8, 10)},
              **{k: ("slow_for_person",) for k in range(12, 15)},
              **{k: ("recovery.spin",) for k in range(20, 23)},
              **{k: ("recovery.wait",) for k in range(30, 33)}}
"""Three recovery rounds (steps 5-9, 20-22, 30-32), and a behaviour that is no recovery."""
ROUND_STARTS = (5, 20, 30)


@pytest.mark.parametrize("at_round", [1, 2, 3])
def test_recovery_aborts_the_goal_where_that_recovery_round_would_start(at_round: int) -> None:
    knockout, fake = wrapped(f"recovery_{at_round}", doing=RECOVERIES)
    commands = drive(knockout, 40)
    start = ROUND_STARTS[at_round - 1]
    assert commands[:start] == [inner_command(k) for k in range(start)]  # earlier rounds run
    assert commands[start:] == [STOP] * (40 - start)
    feedback = knockout.feedback()
    assert feedback.state == NavState.ABORTED and feedback.goal == GOAL.name
    assert f"recovery round {at_round}" in feedback.message
    assert fake.cancels == 1


def test_recovery_lets_every_round_run_below_its_round_and_starts_counting_per_goal() -> None:
    knockout, _ = wrapped("recovery_4", doing=RECOVERIES)
    assert drive(knockout, 40) == [inner_command(k) for k in range(40)]
    assert knockout.feedback().state == NavState.ACTIVE
    aborted, fake = wrapped("recovery_1", doing=RECOVERIES)
    drive(aborted, 10)
    aborted.send_goal(replace(GOAL, name="next"))  # a new goal: the fake's steps go on (10...)
    assert aborted.feedback().state == NavState.PENDING
    assert aborted.step(observation(1.0)) == inner_command(10)
    assert aborted.feedback().state == NavState.ACTIVE


def test_recovery_on_a_navigator_that_reports_nothing_is_that_navigator() -> None:
    knockout, _ = wrapped("recovery_1")
    assert drive(knockout, 40) == [inner_command(k) for k in range(40)]
    assert isinstance(knockout, AbortsRecovery)


BOXED_IN = LaserScan(-math.pi, 2 * math.pi / 90, 0.12, 3.5, np.full(90, 0.3))
"""The checker's laser seeing points all round the robot 0.3 m from its centre: it can neither
drive on nor turn out, and the reference recovers round after round before it aborts."""


def boxed_in(controller: knockouts.Wrapper | ReferenceNavigator) -> tuple[
        list[VelocityCommand], list[tuple[str, ...]], GoalFeedback]:
    """Commands, reported behaviours and the last feedback of a goal 2.5 m east, boxed in."""
    controller.reset(checker_context())
    controller.send_goal(NavGoal("east", 3.5, 2.0, None, 0.3, 200.0))
    commands, doing = [], []
    for k in range(600):
        t = k / 10
        commands.append(controller.step(Observation(t, (1.0, 2.0, 0.0), (0.0, 0.0), BOXED_IN,
                                                    t)))
        feedback = controller.feedback()
        doing.append(reported(feedback.message))
        if feedback.state != NavState.ACTIVE:
            break
    return commands, doing, feedback


@pytest.mark.parametrize("at_round", [1, 2, 3])
def test_recovery_around_the_reference_aborts_where_that_round_of_its_own_starts(
        at_round: int) -> None:
    """The knock-out reads the reference's own reports: it ends the goal on the step the
    reference starts its at_round-th round, after the same commands until then."""
    reference, said, end = boxed_in(ReferenceNavigator())
    recovering = [any(n.startswith("recovery.") for n in d) for d in said]
    starts = [k for k, r in enumerate(recovering) if r and not (k and recovering[k - 1])]
    assert end.state == NavState.ABORTED and len(starts) > at_round
    commands, _, feedback = boxed_in(make(f"recovery_{at_round}", ReferenceNavigator()))
    start = starts[at_round - 1]
    assert feedback.state == NavState.ABORTED
    assert f"recovery round {at_round}" in feedback.message
    assert len(commands) == start + 1 < len(reference)
    assert commands[:start] == reference[:start] and commands[start] == STOP


# -- a real run -----------------------------------------------------------------------------

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck run fails the test instead of hanging it (not a speed limit)."""


def _rei_run(out: Path, controller: str, base: str | None) -> list[tuple[float, float]]:
    """The commands of a 3 s run of examples/simple_wall (seed 1), from its trace."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    env.pop(BASE_VARIABLE, None)
    if base is not None:
        env[BASE_VARIABLE] = base
    done = subprocess.run(
        [sys.executable, "-m", "rei.runtime.commands", "run",
         str(EXAMPLES / "simple_wall" / "simple_wall.mission"), "-o", str(out), "--seed", "1",
         "--duration", "3", "--controller", controller, "--page", "none", "--quiet"],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=SAFETY_LIMIT, check=False)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["controller"] == controller
    records = [json.loads(line) for line in
               (out / "trace.jsonl").read_text(encoding="utf-8").splitlines()]
    return [tuple(r["belief"]["cmd"]) for r in records if r.get("belief")]


@pytest.mark.slow
def test_rei_run_drives_a_knockout_around_the_base_rei_knockout_base_names(
        tmp_path: Path) -> None:
    """teleop's commands do not depend on what it sees, so the knock-out's are exactly its
    own half a second (5 ticks) late: the delay, the module:attr spec and the base chosen in
    the environment all reach the run's own process."""
    teleop = _rei_run(tmp_path / "teleop", "teleop", None)
    late = _rei_run(tmp_path / "late", "bench.knockouts:delay_500", "teleop")
    assert any(c != (0.0, 0.0) for c in teleop[:10])
    assert len(late) == len(teleop) > 20
    assert late[:5] == [(0.0, 0.0)] * 5 and late[5:] == teleop[:-5]
