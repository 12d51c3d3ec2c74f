"""The run loop as components: the scheduler's clock and order, the message contract, and the
fault stage between the sensors and the robot (issue 16.1-2, the loop side of issue 17)."""

from __future__ import annotations

import json
import math
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.errors import RunError
from rei.runtime.messages import (
    LOOP_MESSAGES,
    BodyStates,
    BodyVelocities,
    CommandIssued,
    LaserScan,
    MessageError,
    MissionEvent,
    MissionStatus,
    NavState,
    OdometryReading,
    RobotTruth,
    RobotView,
    ScanReading,
    SignalFired,
    TrackedBodies,
    message_from_json,
    message_to_json,
)
from rei.runtime.messages.sink import SampleList
from rei.runtime.observation.monitor import MonitorSink
from rei.runtime.robot import Observation, VelocityCommand
from rei.runtime.simulation.assembly import RunConfig, generate_world, run_mission
from rei.runtime.simulation.faults.stage import NO_FAULTS, Command, Pose, Twist
from rei.runtime.simulation.loop import Clock, Scheduler, Stage, every
from rei.runtime.trace import TraceWriter
from tests.conftest import EXAMPLES
from tests.robot.faulty import _Base

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"

# ---- the scheduler ------------------------------------------------------------------------------


def _schedule(last: int, stop_at: int | None = None) -> tuple[list[str], Scheduler]:
    ran: list[str] = []

    def stage(name: str, stops: bool = False) -> Any:
        def run(clock: Clock) -> None:
            ran.append(f"{clock.k}:{name}")
            if stops and clock.k == stop_at:
                clock.stop("done")
        return run

    scheduler = Scheduler([
        Stage("world", stage("world"), 1),
        Stage("laser", stage("laser"), 4),
        Stage("mission", stage("mission", stops=True), 2),
        Stage("robot", stage("robot"), 2),
        Stage("mission", stage("deadline"), None),
        Stage("collector", stage("collector"), 2, at_end=True),
    ], Clock(100.0, last))
    scheduler.run()
    return ran, scheduler


def test_stages_run_at_their_rates_in_declared_order() -> None:
    ran, scheduler = _schedule(last=5)
    assert ran[:11] == ["0:world", "0:laser", "0:mission", "0:robot", "0:collector",
                        "1:world",
                        "2:world", "2:mission", "2:robot", "2:collector",
                        "3:world"]
    # the last tick: every stage of rate None runs too, in its place; nothing after it
    assert ran[11:] == ["4:world", "4:laser", "4:mission", "4:robot", "4:collector", "5:world",
                        "5:deadline", "5:collector"]
    assert scheduler.clock.stopped and scheduler.clock.now == 0.05


def test_a_stop_skips_the_rest_of_the_tick_but_the_end_stages() -> None:
    ran, scheduler = _schedule(last=50, stop_at=4)
    assert ran[-3:] == ["4:laser", "4:mission", "4:collector"]  # no robot, no deadline
    assert scheduler.clock.reason == "done" and scheduler.clock.k == 4
    cpu = scheduler.cpu_seconds()
    assert list(cpu) == ["world", "laser", "mission", "robot", "collector"]
    assert all(v >= 0.0 for v in cpu.values())


def test_a_stop_off_the_end_stages_rate_still_runs_them_once() -> None:
    ran: list[str] = []

    def note(name: str) -> Any:
        def run(clock: Clock) -> None:
            ran.append(f"{clock.k}:{name}")
            if name == "stopper" and clock.k == 3:
                clock.stop("finished")
        return run

    scheduler = Scheduler([Stage("a", note("observe"), None, at_end=True),
                           Stage("b", note("stopper"), 3),
                           Stage("c", note("robot"), 1),
                           Stage("d", note("collector"), 2, at_end=True)], Clock(10.0, 100))
    scheduler.run()
    # tick 3: the stopper ends it; the end stages that did not run yet run, in order
    assert ran[-3:] == ["3:stopper", "3:observe", "3:collector"]
    scheduler.end()  # from outside (a controller fault): every end stage runs once more
    assert ran[-2:] == ["3:observe", "3:collector"]


def test_rates_must_divide_the_physics_rate() -> None:
    assert every(100.0, 10.0, "the control rate") == 10
    with pytest.raises(RunError, match="the laser rate of 30 Hz expected to divide the physics "
                                       "rate of 100 Hz, found a ratio of 3.33333"):
        every(100.0, 30.0, "the laser rate")


# ---- the messages -------------------------------------------------------------------------------

SCAN = LaserScan(-math.pi, 0.5, 0.1, 3.5, np.array([1.0, 2.5, 3.5]))
EXAMPLES_OF: list[Any] = [
    RobotTruth(3, 0.03, (1.0, 2.0, 0.5), (0, 4)),
    BodyStates(1, 0.1, (0.1, 0.0, 0.2), np.arange(6.0).reshape(2, 3), np.zeros((2, 3)), (4,)),
    TrackedBodies(2, 0.2, ((1.0, 1.0, 0.0),), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    BodyVelocities(0, 0.0, (((7, 0.1, 0.2, 0.0),), ((7, 0.1, 0.25, 0.0),))),
    ScanReading(5, 1.0, SCAN),
    OdometryReading(9, 0.9, (1.0, 2.0, 3.0), (0.2, 0.0)),
    RobotView(2, 0.2, SCAN, 0.0, (1.0, 2.0, 3.0), (0.2, 0.0)),
    RobotView(0, 0.0, None, None, (0.0, 0.0, 0.0), (0.0, 0.0)),
    CommandIssued(4, 0.4, (2.0, 0.0), (0.26, 0.0)),
    MissionStatus(1, 0.1, (MissionEvent("task_fail", 0.1, "g", 0, "timeout after 1 s",
                                        "timeout"),), NavState.ACTIVE, "g"),
    SignalFired(0, 0.1, "SIG_MISSION_BEGIN"),
]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, LaserScan):
        return a == b and np.array_equal(a.ranges, b.ranges)
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


@pytest.mark.parametrize("message", EXAMPLES_OF, ids=lambda m: type(m).__name__)
def test_every_message_round_trips_through_json(message: Any) -> None:
    data = json.loads(json.dumps(message_to_json(message)))
    assert data["topic"] == message.TOPIC and data["seq"] == message.seq
    back = message_from_json(data)
    assert type(back) is type(message)
    for f in fields(message):
        assert _same(getattr(back, f.name), getattr(message, f.name)), f.name


def test_every_topic_has_a_round_trip_example() -> None:
    assert {type(m) for m in EXAMPLES_OF} == set(LOOP_MESSAGES.values())


@pytest.mark.parametrize(("data", "error"), [
    ([1, 2], "expected to be a JSON object, found list"),
    ({"topic": "nope", "seq": 0}, "topic expected to be one of"),
    ({"topic": "truth/robot", "seq": 0, "time": 0.0}, "truth/robot: field 'pose' expected"),
    ({"topic": "truth/robot", "seq": 0, "time": float("nan"), "pose": [0, 0, 0]},
     "truth/robot: field 'time': expected a finite number"),
    ({"topic": "truth/robot", "seq": True, "time": 0.0, "pose": [0, 0, 0]},
     "field 'seq': expected an integer"),
    ({"topic": "truth/robot", "seq": 0, "time": 0.0, "pose": [0, 0]},
     "field 'pose': expected 3 values, found 2"),
    ({"topic": "mission/status", "seq": 0, "time": 0.0, "events": [{"kind": "boom"}],
      "nav_state": "idle", "task": None}, "field 'events': expected a mission event kind"),
    ({"topic": "mission/status", "seq": 0, "time": 0.0, "nav_state": "idle", "task": None,
      "events": [{"kind": "begin", "time": 0.0, "index": "first"}]},
     "expected a mission event's index as an integer"),
    ({"topic": "sensor/laser", "seq": 0, "time": 0.0, "scan": {"angle_min": 0.0,
      "angle_increment": 0.1, "range_min": 0.1, "range_max": 3.5, "ranges": [1.0, None]}},
     "field 'scan'"),
])
def test_a_bad_message_is_refused_naming_topic_and_field(data: Any, error: str) -> None:
    with pytest.raises(MessageError, match=error.replace("(", r"\(")):
        message_from_json(data)


# ---- the fault stage in a run -------------------------------------------------------------------


class BlankAfterSignal:
    """Blanks the robot's scan (every beam at max range) once ``trigger`` fired; records what
    it was called with."""

    def __init__(self, trigger: str) -> None:
        self.trigger = trigger
        self.active_from: float | None = None
        self.signals: list[tuple[str, float]] = []
        self.calls: list[str] = []
        self._blanked: dict[int, LaserScan] = {}

    def scan(self, time: float, measured: LaserScan | None,
             measured_at: float | None) -> tuple[LaserScan | None, float | None]:
        self.calls.append("scan")
        if self.active_from is None or measured is None:
            return measured, measured_at
        key = id(measured)
        if key not in self._blanked:  # once per measured scan
            ranges = np.full_like(measured.ranges, measured.range_max)
            ranges.flags.writeable = False
            self._blanked = {key: LaserScan(measured.angle_min, measured.angle_increment,
                                            measured.range_min, measured.range_max, ranges)}
        return self._blanked[key], measured_at

    def odometry(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        self.calls.append("odometry")
        return pose, twist

    def command(self, time: float, command: Command) -> Command:
        self.calls.append("command")
        return command

    def signal(self, time: float, name: str) -> None:
        self.signals.append((name, time))
        if name == self.trigger and self.active_from is None:
            self.active_from = time

    def timeline(self) -> tuple[tuple[str, float, float | None], ...]:
        return () if self.active_from is None else (("blank_laser", self.active_from, None),)

    def described(self) -> tuple[tuple[str, str], ...]:
        return (("blank_laser", f"laser_dropout as blank_laser share 1 when {self.trigger}"),)


class HalfSpeed(BlankAfterSignal):
    """Halves what reaches the motors."""

    def command(self, time: float, command: Command) -> Command:
        return command[0] / 2, command[1] / 2


class Recording(_Base):
    """Drives straight at 0.1 m/s whatever it sees, keeping every observation."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[Observation] = []

    def step(self, observation: Observation) -> VelocityCommand:
        if self.tracker.state.value == "pending":
            self.tracker.accept()
        self.seen.append(observation)
        return VelocityCommand(0.1, 0.0)


def _run(tmp: Path, faults: Any, monitor: bool = True,
         rates: tuple[float, float] | None = None) -> tuple[Any, SampleList, Recording]:
    mission = generate_world(NAVIGATION, tmp / "world")
    manifest, config = load_manifest(tmp / "world"), load_monitor_config(tmp / "world")
    if rates is not None:  # (laser, sample) Hz
        manifest = replace(manifest, laser=replace(manifest.laser, rate=rates[0]))
        config = replace(config, rate=rates[1])
    samples, robot = SampleList(), Recording()
    sinks: list[Any] = [samples, TraceWriter(tmp / "trace.jsonl")]
    if monitor:
        sinks.append(MonitorSink(None, tmp / "monitor"))
    record = run_mission(mission, manifest, config, robot, sinks,
                         RunConfig(duration=3.0, watchdog=None), faults=faults)
    return record, samples, robot


@pytest.fixture(scope="module")
def unfaulted(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, SampleList, Recording]:
    return _run(tmp_path_factory.mktemp("plain"), None)


def test_the_robot_and_the_trace_get_the_faulted_scan_and_truth_stays(
        tmp_path: Path, unfaulted: tuple[Any, SampleList, Recording]) -> None:
    stage = BlankAfterSignal("SIG_MISSION_TASK_START")
    record, samples, robot = _run(tmp_path, stage)
    # the monitor's signals reach the stage, with their simulation time
    assert ("SIG_MISSION_BEGIN", 0.0) in stage.signals
    start = stage.active_from
    assert start is not None and start == 0.0
    # every control tick: scan, then odometry, then command
    assert stage.calls[:6] == ["scan", "odometry", "command"] * 2
    assert stage.calls.count("command") == len(robot.seen) == 31  # t = 0.0 ... 3.0
    # the signal fired at the t=0 sample acts from the next control tick on
    assert robot.seen[0].scan is not None and robot.seen[0].scan.ranges.min() < 3.5
    blank = [o for o in robot.seen if o.time > start]
    assert blank and all(o.scan is not None and (o.scan.ranges == 3.5).all() for o in blank)
    # the trace records what the robot got
    _, plain, _ = unfaulted
    later = [s for s in samples.samples if s.time > start]
    assert all(s.belief.laser_min == 3.5 for s in later)
    # every sample says which fault was active when it was taken
    assert all(s.faults == ("blank_laser",) for s in later)
    assert all(s.faults == () for s in samples.samples if s.time <= start)
    assert any(s.belief.laser_min < 3.5 for s in plain.samples if s.time > start)
    # the ground truth never passed through the stage: the robot ignores its scan, so the
    # world moved exactly as without the fault
    assert len(samples.samples) == len(plain.samples)
    for a, b in zip(samples.samples, plain.samples, strict=True):
        assert a.robot_pose == b.robot_pose and np.array_equal(a.poses, b.poses)
    assert record.measurements["faults"] == [{"fault": "blank_laser", "start": 0.0,
                                              "end": None}]
    assert record.measurements["faults_injected"] == [
        {"fault": "blank_laser",
         "entry": "laser_dropout as blank_laser share 1 when SIG_MISSION_TASK_START"}]
    assert "faults" not in unfaulted[0].measurements
    assert "faults_injected" not in unfaulted[0].measurements


def test_the_motors_get_the_faulted_command_and_the_belief_the_asked_one(
        tmp_path: Path, unfaulted: tuple[Any, SampleList, Recording]) -> None:
    _, samples, _ = _run(tmp_path, HalfSpeed("never"), monitor=False)
    _, plain, _ = unfaulted
    assert all(s.belief.cmd == (0.1, 0.0) for s in samples.samples[1:])
    travelled = samples.samples[-1].robot_pose[0] - samples.samples[0].robot_pose[0]
    plain_travelled = plain.samples[-1].robot_pose[0] - plain.samples[0].robot_pose[0]
    assert travelled == pytest.approx(plain_travelled / 2, rel=0.05)


def test_no_faults_gives_the_same_bytes_as_no_stage(tmp_path: Path) -> None:
    _run(tmp_path / "a", None)
    record, _, _ = _run(tmp_path / "b", NO_FAULTS)
    assert (tmp_path / "a" / "trace.jsonl").read_bytes() == \
           (tmp_path / "b" / "trace.jsonl").read_bytes()
    # the loop's processor time, per component, is on the record and nowhere in the outputs
    cpu = record.component_cpu
    assert {"world", "laser", "odometry", "faults", "mission", "robot", "collector",
            "animator"} <= set(cpu)
    assert all(v >= 0.0 for v in cpu.values()) and sum(cpu.values()) <= record.cpu_seconds
    assert b"component_cpu" not in (tmp_path / "b" / "trace.jsonl").read_bytes()


def test_a_run_with_a_fault_stage_is_deterministic(tmp_path: Path) -> None:
    for name in ("a", "b"):
        _run(tmp_path / name, BlankAfterSignal("SIG_MISSION_TASK_START"))
    assert (tmp_path / "a" / "trace.jsonl").read_bytes() == \
           (tmp_path / "b" / "trace.jsonl").read_bytes()
    assert (tmp_path / "a" / "monitor" / "events.csv").read_bytes() == \
           (tmp_path / "b" / "monitor" / "events.csv").read_bytes()


def test_a_scan_measured_between_control_ticks_reaches_the_belief_through_the_stage(
        tmp_path: Path) -> None:
    # laser and samples at 20 Hz, control at 10 Hz: every other sample falls between ticks
    _, plain, _ = _run(tmp_path / "plain", None, monitor=False, rates=(20.0, 20.0))
    assert [round(s.time, 2) for s in plain.samples[:4]] == [0.0, 0.05, 0.1, 0.15]
    assert all(s.belief.scan is not None for s in plain.samples[:-1])  # each one fresh
    stage = BlankAfterSignal("never")
    stage.active_from = 0.0
    _, blank, robot = _run(tmp_path / "blank", stage, monitor=False, rates=(20.0, 20.0))
    assert all(s.belief.scan is not None and (s.belief.scan.ranges == 3.5).all()
               for s in blank.samples[:-1])
    assert all(o.scan is not None and (o.scan.ranges == 3.5).all() for o in robot.seen)
