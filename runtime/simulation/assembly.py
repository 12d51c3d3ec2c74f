"""The run loop: pybullet, animator, sensors, robot under test, mission executor and collector.

``run_mission`` assembles the components of ``rei.runtime.simulation.loop`` (world, laser, odometry,
faults, mission, robot, collector, animator) on one scheduler (docs/run-loop.md). One fixed
physics step drives everything; the controller, the laser and the collector run every n-th
step at their own rates (each rate must divide the physics rate). All randomness
comes from ``numpy.random.Generator``s seeded from the run's seed (the main stream from
``default_rng(seed)``, each variation such as the start-pose jitter from its own
``default_rng([seed, k])``, so adding one never shifts another), iteration is in
declaration order and no wall-clock time enters the outputs, so the same inputs and seed give
the same bytes. A controller that raises, hangs past the watchdog or answers outside its
contract (a malformed command or feedback) ends the run with outcome ``error``; Ctrl-C ends it
``interrupted``; in both cases the sinks are finished, so what was written stays consistent.
The controller sees the sensors through read-only copies: the sinks record what it received
(what the sensors measured, through the fault stage when one is given), whatever the
controller does with its view; the ground truth never passes through the fault stage. A
``RunProbe`` hears the loop's progress (each control tick), so a supervising process can
tell a hung or dead run from a slow one. This module must never judge the run beyond task
outcomes (the monitor and the evaluator do that, as sinks).
"""

from __future__ import annotations

import math
import time as wallclock
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from rei.catalogue import Box, Cylinder
from rei.generators.concrete import ConcreteMission
from rei.runtime.artifacts.monitor_config import MonitorConfig
from rei.runtime.artifacts.world import WorldManifest
from rei.runtime.errors import RunError
from rei.runtime.messages import SCHEMA_VERSION, GoalFacts, MissionFacts, StreamHeader
from rei.runtime.messages.sink import SampleSink
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary
from rei.runtime.robot.contract import Controller, ControllerContext, MapObstacle
from rei.runtime.robot.watchdog import ControllerFault
from rei.runtime.simulation.faults.stage import NO_FAULTS, FaultStage, fault_measurements
from rei.runtime.simulation.loop import (
    Board,
    Clock,
    Collector,
    DeadReckoning,
    Faults,
    Humans,
    Laser,
    Mission,
    Robot,
    Scheduler,
    SignalSource,
    Stage,
    World,
    every,
)
from rei.runtime.simulation.mission import TaskResult
from rei.runtime.simulation.world.start_jitter import (
    START_JITTER,
    StartJitter,
    jitter_start,
    with_robot_pose,
)


@dataclass(frozen=True)
class RunConfig:
    seed: int = 0
    physics_rate: float = 100.0
    """Physics steps per simulated second."""
    control_rate: float = 10.0
    """Controller calls (and mission executor ticks) per simulated second."""
    duration: float | None = None
    """Stop after this many simulated seconds even if the mission's time limit is later."""
    watchdog: float | None = 5.0
    """Wall-clock seconds a controller call may take; None runs it in the main thread."""
    odom_drift: float = 0.0
    """Relative standard deviation of odometry's per-tick error (0: odometry is exact)."""
    laser_noise: float | None = None
    """Standard deviation (m) of the laser's range error; None: the catalogue's value."""
    jitter: StartJitter | None = START_JITTER
    """Seeded start-pose jitter of the robot; None starts it exactly at the declared pose."""
    vary: bool = True
    """Draw each human's start delay and speed scale from the seed (its own stream, so the
    laser noise is unchanged); False walks every trajectory exactly as written."""


@dataclass(frozen=True)
class LoopRecord:
    """What the run loop recorded of one run (its outcome, tasks, measurements and costs);
    ``summary_of`` makes the run's RunSummary of it. A campaign's record of a run is
    rei.runtime.campaigns.store.RunRecord."""

    outcome: Outcome
    reason: str
    duration: float
    """Simulated seconds."""
    tasks: tuple[TaskResult, ...]
    measurements: dict[str, Any] = field(default_factory=dict)
    wall_seconds: float = 0.0
    """Wall-clock time of the loop (never written into the outputs)."""
    cpu_seconds: float = 0.0
    """Processor time of the loop, all threads (never written into the outputs)."""
    steps: int = 0
    component_cpu: dict[str, float] = field(default_factory=dict)
    """Processor seconds per component of the loop (never written into the outputs)."""


def static_map(manifest: WorldManifest) -> tuple[MapObstacle, ...]:
    """What the robot may know beforehand: walls and static (fixed) objects."""
    obstacles = []
    for body in manifest.walls + tuple(o for o in manifest.objects if o.fixed):
        fp = body.footprint
        if isinstance(fp, Cylinder):
            obstacles.append(MapObstacle(body.name, body.role, body.x, body.y, body.yaw,
                                         "cylinder", radius=fp.radius))
        elif isinstance(fp, Box):
            obstacles.append(MapObstacle(body.name, body.role, body.x, body.y, body.yaw, "box",
                                         fp.size_x, fp.size_y))
    return tuple(obstacles)


def speed_limit(manifest: WorldManifest, mission: ConcreteMission) -> float:
    """m/s the robot can reach: the drive's limit, lowered by the mission's max_speed."""
    if mission.max_speed is None:
        return manifest.drive.max_linear
    return min(manifest.drive.max_linear, mission.max_speed)


def mission_facts(manifest: WorldManifest, mission: ConcreteMission) -> MissionFacts:
    """The goals and limits the stream header carries for requirements (one cycle)."""
    # Headings in (-pi, pi]: the .mission admits -360..360 degrees for the same directions.
    goals = tuple(GoalFacts(g.name, g.x, g.y,
                            None if g.yaw is None else math.remainder(g.yaw, math.tau),
                            g.tolerance, g.heading_tolerance, g.timeout) for g in mission.goals)
    drive = manifest.drive
    return MissionFacts(goals, mission.cycles, mission.time_limit,
                        speed_limit(manifest, mission), drive.max_angular, mission.max_speed,
                        drive.max_linear_accel, drive.max_linear_decel,
                        drive.max_angular_accel, drive.max_angular_decel)


def stream_header(manifest: WorldManifest, monitor: MonitorConfig,
                  mission: ConcreteMission | str, seed: int,
                  faults: tuple[tuple[str, str], ...] = ()) -> StreamHeader:
    """The header of a run's stream; a mission given by name only (a stream not made by a
    mission run) has no mission facts. ``faults``: (name, entry) of the injected faults."""
    names = [b.name for b in manifest.observed]
    if [o.name for o in monitor.objects] != names:
        raise RunError("the monitor configuration's objects expected to be the world's walls "
                       "and objects in order; regenerate both targets from the same input")
    facts = None if isinstance(mission, str) else mission_facts(manifest, mission)
    name = mission if isinstance(mission, str) else mission.name
    return StreamHeader(SCHEMA_VERSION, manifest.world, name, seed, monitor.rate,
                        monitor.robot, monitor.objects, manifest.tile_size, manifest.floors,
                        (manifest.laser.mount_x, manifest.laser.mount_y), facts,
                        monitor.data, faults)


class RunProbe(Protocol):
    """Hears how far a run got: the supervisor's heartbeat (``rei.runtime.runs.supervisor``)."""

    def begin(self, mission: str, room: str) -> None:
        """The mission is checked and its world generated (called by ``run_into``)."""

    def tick(self, time: float) -> None:
        """The loop reached simulated ``time`` and is about to call the controller."""

    def end(self, time: float) -> None:
        """The loop ended at simulated ``time``; the sinks are finishing."""


def run_mission(mission: ConcreteMission, manifest: WorldManifest, monitor: MonitorConfig,
                controller: Controller, sinks: Sequence[SampleSink], config: RunConfig,
                progress: Callable[[float, float], None] | None = None,
                log: Callable[[str], None] | None = None,
                probe: RunProbe | None = None, *,
                faults: FaultStage | None = None) -> LoopRecord:
    """Run the mission once; the record of how it ended (never raises for controller faults).

    The run is the components of ``rei.runtime.simulation.loop`` on one scheduler; ``faults`` is the
    fault stage between the sensors and the robot under test (None: no faults)."""
    say = log or (lambda line: None)
    stage = NO_FAULTS if faults is None else faults
    rate = config.physics_rate
    every_control = every(rate, config.control_rate, "the control rate")
    every_laser = every(rate, manifest.laser.rate, "the laser rate")
    every_sample = every(rate, monitor.rate, "the monitor's sample rate")
    header = stream_header(manifest, monitor, mission, config.seed, stage.described())
    # The jittered pose replaces the declared one in the manifest itself, so the pybullet body,
    # odometry's origin and the controller's start_pose below cannot disagree.
    started = jitter_start(manifest, config.seed, config.jitter)
    manifest = with_robot_pose(manifest, started.pose)
    rng = np.random.default_rng(config.seed)  # the laser's noise, then odometry's drift
    end_time = mission.time_limit
    end_reason = f"mission time limit of {mission.time_limit:g} s reached"
    end_cause = "abandoned"
    if config.duration is not None and config.duration < end_time:
        end_time = config.duration
        end_reason = f"duration limit of {config.duration:g} s reached"
        end_cause = "cut"  # the user stopped watching: the running task's end is unknown
    clock = Clock(rate, int(math.floor(end_time * rate + 1e-9)))

    robot_spec = manifest.robot
    start = (robot_spec.x, robot_spec.y, robot_spec.yaw)
    half = robot_spec.footprint.half_extents()
    context = ControllerContext(
        robot_size=(half[0] * 2, half[1] * 2), drive=manifest.drive, laser=manifest.laser,
        start_pose=start, obstacles=static_map(manifest), bounds=manifest.bounds,
        tile_size=manifest.tile_size, control_rate=config.control_rate, seed=config.seed,
        max_speed=mission.max_speed)
    laser = Laser(manifest, manifest.laser.noise if config.laser_noise is None
                  else config.laser_noise)
    world = World(manifest, rate, tuple(o.name for o in header.objects),
                  every_laser, bool(laser.moving_seen), every_sample, every_control)

    board = Board()
    wall_start = wallclock.perf_counter()
    cpu_start = wallclock.process_time()
    outcome: Outcome | None = None
    reason = ""
    robot = Robot(controller, context, config.watchdog, speed_limit(manifest, mission),
                  manifest.drive.max_angular, stage).start(board)
    world_run = world.start(board)
    try:
        animator = Humans(manifest, rate, every_control, config.seed, config.vary) \
            .start(board, world_run.world.object_ids)
        world_run.track(animator.bodies)
        laser_run = laser.start(board, rng)
        odometry = DeadReckoning(start, config.odom_drift, every_control / rate).start(board, rng)
        faults_run = Faults(stage).start(board)
        if stage is not NO_FAULTS:  # the empty stage ignores signals: nobody listens
            for sink in sinks:
                if isinstance(sink, SignalSource):
                    sink.listen(faults_run.heard)
        mission_run = Mission(mission, start, end_reason, end_cause).start(
            board, robot, probe, say)
        collector = Collector(header, manifest, tuple(sinks), every_sample, start).start(board)
        stages = [
            Stage("world", world_run.step, 1),
            Stage("world", world_run.observe, None, at_end=True),
            Stage("laser", laser_run.step, every_laser),
            Stage("odometry", odometry.step, every_control),
            Stage("faults", faults_run.step, every_control),
            Stage("mission", mission_run.step, every_control),
            Stage("robot", robot.step, every_control),
            Stage("mission", mission_run.deadline, None),
        ]
        if every_laser % every_control:  # a scan can come between control ticks
            stages.append(Stage("faults", faults_run.refresh, every_sample, at_end=True))
        stages.append(Stage("collector", collector.step, every_sample, at_end=True))
        if stage is not NO_FAULTS:
            stages.append(Stage("faults", faults_run.deliver, every_sample, at_end=True))
        if progress is not None:
            stages.append(Stage("progress", _Progress(progress, end_time).step,
                                max(1, round(rate)), at_end=True))
        if animator.items:
            stages.append(Stage("animator", animator.step, every_control))
        scheduler = Scheduler(stages, clock)
        collector.open()
        try:
            if probe is not None:
                probe.tick(0.0)
            robot.reset()
            scheduler.run()
        except ControllerFault as fault:
            outcome, reason = "error", str(fault)
            say(f"t={clock.now:9.3f}  error: {reason}")
            world_run.observe(clock)
            mission_run.abandon(clock.now, f"run error: {reason}")
            scheduler.end()
        except KeyboardInterrupt:
            outcome, reason = "interrupted", "interrupted by the user (output incomplete)"
            say(f"t={clock.now:9.3f}  interrupted")
            world_run.observe(clock)
            mission_run.abandon(clock.now, "interrupted")
            scheduler.end()
        executor = mission_run.executor
        if outcome is None and mission_run.timed_out:
            outcome, reason = "timeout", end_reason
        if outcome is None:
            failed = [r for r in executor.results if not r.succeeded]
            outcome = "failed" if failed else "completed"
            reason = (f"{len(failed)} of {len(executor.results)} tasks failed" if failed
                      else f"all {len(executor.results)} tasks succeeded")
        now = clock.now
        say(f"t={now:9.3f}  outcome {outcome}: {reason}")
        # The robot under test is stopped (a hosted one's processes killed and reaped) before
        # any output is finished: nothing it started can write after the outputs are.
        robot.close()
        if probe is not None:
            probe.end(now)
        collector.finish(now, outcome, reason)
    finally:
        robot.close()
        world_run.close()
    tasks = tuple(executor.results)
    measurements: dict[str, Any] = {
        "path_length": mission_run.path_length,
        "behaviours": mission_run.behaviours.to_json(),
        "tasks": [{"index": r.index, "task": r.task, "succeeded": r.succeeded, "reason": r.reason,
                   "start": r.start, "end": r.end, "time": r.end - r.start,
                   "final_distance": r.final_distance, "cause": r.cause} for r in tasks],
        "time_per_task": {f"{r.index}:{r.task}": r.end - r.start for r in tasks},
        "tasks_succeeded": sum(r.succeeded for r in tasks),
        "tasks_failed": sum(not r.succeeded for r in tasks),
        "collisions": world_run.episodes,
        "collided_with": sorted(world_run.touched_names),
        "first_collision": world_run.first_contact,
        "min_laser_range": laser_run.min_range if math.isfinite(laser_run.min_range) else None,
        "samples": collector.samples,
        "physics_steps": clock.k,
        "incomplete": outcome == "interrupted",
        "variations": animator.variations(),
    }
    # Other variations (the humans') record themselves under the same key: merge, never replace.
    variations = measurements.setdefault("variations", {})
    variations["start_jitter"] = started.to_json()
    described = stage.described()
    if described:  # a run without faults keeps the summary it always had
        measurements.update(fault_measurements(described, stage.timeline()))
        statistics = getattr(stage, "statistics", None)
        if callable(statistics):
            measurements["fault_statistics"] = {s.name: dict(s.counts) for s in statistics()}
    return LoopRecord(outcome, reason, clock.now, tasks, measurements,
                     wallclock.perf_counter() - wall_start,
                     wallclock.process_time() - cpu_start, clock.k,
                     scheduler.cpu_seconds())


class _Progress:
    """Tells the caller's progress display the simulated time, about once a second."""

    def __init__(self, show: Callable[[float, float], None], end: float) -> None:
        self.show, self.end, self.next = show, end, 0.0

    def step(self, clock: Clock) -> None:
        if clock.now >= self.next:
            self.show(clock.now, self.end)
            self.next = clock.now + 1.0


def summary_of(record: LoopRecord, mission: ConcreteMission, controller: str,
               seed: int) -> RunSummary:
    """The run summary before any monitor is attached (no signals, no verdicts yet)."""
    return RunSummary(RESULTS_VERSION, mission.name, mission.world.name, seed, controller,
                      record.outcome, record.reason, record.duration, 0.0, {}, (),
                      dict(record.measurements))


def generate_world(mission_path: Path, out_dir: Path, replace: bool = False) -> ConcreteMission:
    """Check the mission and generate the `pybullet` and `monitor` targets into ``out_dir``
    (with ``replace``, whatever else was in it goes: no stale URDF can be loaded)."""
    from rei.generators.concrete.build import load_concrete_mission  # noqa: PLC0415
    from rei.generators.output import OutputTree, write_tree  # noqa: PLC0415
    from rei.generators.targets import GenerationRequest, get_target  # noqa: PLC0415

    mission = load_concrete_mission(mission_path)
    request = GenerationRequest(mission_path, mission.world, mission)
    tree = OutputTree()
    for name in ("pybullet", "monitor"):
        tree.merge(get_target(name).generate(request))
    write_tree(tree, out_dir, replace=replace)
    return mission


