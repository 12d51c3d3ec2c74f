"""The run loop: pybullet, animator, sensors, robot under test, mission executor and collector.

One fixed physics step drives everything; the controller, the laser and the collector run
every n-th step at their own rates (each rate must divide the physics rate). All randomness
comes from ``numpy.random.Generator``s seeded from the run's seed (the main stream from
``default_rng(seed)``, each variation such as the start-pose jitter from its own
``default_rng([seed, k])``, so adding one never shifts another), iteration is in
declaration order and no wall-clock time enters the outputs, so the same inputs and seed give
the same bytes. A controller that raises, hangs past the watchdog or answers outside its
contract (a malformed command or feedback) ends the run with outcome ``error``; Ctrl-C ends it
``interrupted``; in both cases the sinks are finished, so what was written stays consistent.
The controller sees the sensors through read-only copies: the sinks record what the sensors
measured, whatever the controller does with its view. A ``RunProbe`` hears the loop's
progress (each control tick), so a supervising process can tell a hung or dead run from a
slow one. This module must never judge the run beyond task outcomes (the monitor and the
evaluator do that, as sinks).
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
from rei.runtime.animator import Animator
from rei.runtime.animator.animator import animated_bodies, variations_record
from rei.runtime.collector import DataCollector, MonitorConfig, SampleSink
from rei.runtime.errors import RunError
from rei.runtime.messages import (
    SCHEMA_VERSION,
    GoalFacts,
    LaserScan,
    MissionEvent,
    MissionFacts,
    NavState,
    StreamHeader,
)
from rei.runtime.mission import MissionExecutor, TaskResult
from rei.runtime.results import RESULTS_VERSION, Outcome, RunSummary
from rei.runtime.robot.protocol import (
    STOP,
    Controller,
    ControllerContext,
    MapObstacle,
    Observation,
    VelocityCommand,
    read_only_scan,
)
from rei.runtime.robot.watchdog import ControllerFault, GuardedController
from rei.runtime.sensors.laser import Laser2D, ShapeSet, merge_wall_tiles, shapes_of
from rei.runtime.sensors.odometry import Odometry
from rei.runtime.world.bullet import BulletWorld
from rei.runtime.world.manifest import WorldManifest
from rei.runtime.world.start_jitter import START_JITTER, StartJitter, jitter_start, with_robot_pose


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
class RunRecord:
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


def _every(physics_rate: float, rate: float, what: str) -> int:
    ratio = physics_rate / rate
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise RunError(f"{what} of {rate:g} Hz expected to divide the physics rate of "
                       f"{physics_rate:g} Hz, found a ratio of {ratio:g}")
    return n


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
    return MissionFacts(goals, mission.cycles, mission.time_limit,
                        speed_limit(manifest, mission), manifest.drive.max_angular,
                        mission.max_speed)


def stream_header(manifest: WorldManifest, monitor: MonitorConfig,
                  mission: ConcreteMission | str, seed: int) -> StreamHeader:
    """The header of a run's stream; a mission given by name only (a stream not made by a
    mission run) has no mission facts."""
    names = [b.name for b in manifest.observed]
    if [o.name for o in monitor.objects] != names:
        raise RunError("the monitor configuration's objects expected to be the world's walls "
                       "and objects in order; regenerate both targets from the same input")
    facts = None if isinstance(mission, str) else mission_facts(manifest, mission)
    name = mission if isinstance(mission, str) else mission.name
    return StreamHeader(SCHEMA_VERSION, manifest.world, name, seed, monitor.rate,
                        monitor.robot, monitor.objects, manifest.tile_size, manifest.floors,
                        (manifest.laser.mount_x, manifest.laser.mount_y), facts,
                        monitor.data)


class RunProbe(Protocol):
    """Hears how far a run got: the supervisor's heartbeat (``rei.runtime.supervisor``)."""

    def begin(self, mission: str, room: str) -> None:
        """The mission is checked and its world generated (called by ``run_into``)."""

    def tick(self, time: float) -> None:
        """The loop reached simulated ``time`` and is about to call the controller."""

    def end(self, time: float) -> None:
        """The loop ended at simulated ``time``; the sinks are finishing."""


class _Contacts:
    """Contact episodes of the robot: a new episode starts when a body starts touching it."""

    def __init__(self) -> None:
        self.touching: set[str] = set()
        self.episodes = 0
        self.bodies: set[str] = set()
        self.first: float | None = None

    def update(self, names: list[str], time: float) -> None:
        now = set(names)
        new = now - self.touching
        if new:
            self.episodes += len(new)
            self.bodies |= new
            if self.first is None:
                self.first = time
        self.touching = now


def run_mission(mission: ConcreteMission, manifest: WorldManifest, monitor: MonitorConfig,
                controller: Controller, sinks: Sequence[SampleSink], config: RunConfig,
                progress: Callable[[float, float], None] | None = None,
                log: Callable[[str], None] | None = None,
                probe: RunProbe | None = None) -> RunRecord:
    """Run the mission once; the record of how it ended (never raises for controller faults)."""
    say = log or (lambda line: None)
    every_control = _every(config.physics_rate, config.control_rate, "the control rate")
    every_laser = _every(config.physics_rate, manifest.laser.rate, "the laser rate")
    every_sample = _every(config.physics_rate, monitor.rate, "the monitor's sample rate")
    header = stream_header(manifest, monitor, mission, config.seed)
    # The jittered pose replaces the declared one in the manifest itself, so the pybullet body,
    # odometry's origin and the controller's start_pose below cannot disagree.
    started = jitter_start(manifest, config.seed, config.jitter)
    manifest = with_robot_pose(manifest, started.pose)
    rng = np.random.default_rng(config.seed)
    end_time = mission.time_limit
    end_reason = f"mission time limit of {mission.time_limit:g} s reached"
    end_cause = "abandoned"
    if config.duration is not None and config.duration < end_time:
        end_time = config.duration
        end_reason = f"duration limit of {config.duration:g} s reached"
        end_cause = "cut"  # the user stopped watching: the running task's end is unknown
    last_step = int(math.floor(end_time * config.physics_rate + 1e-9))

    laser_spec = manifest.laser
    plane = laser_spec.mount_z
    seen = [b for b in manifest.objects if b.height > plane]
    static_seen = [b for b in seen if b.fixed]
    [b for b in seen if not b.fixed]
    walls = merge_wall_tiles(tuple(w for w in manifest.walls if w.height > plane),
                             manifest.tile_size)
    statics = shapes_of(static_seen, np.array([(b.x, b.y, b.yaw) for b in static_seen]))
    laser = Laser2D(laser_spec, ShapeSet(np.concatenate((walls, statics.boxes)), statics.circles))
    laser_noise = laser_spec.noise if config.laser_noise is None else config.laser_noise

    n_walls = len(manifest.walls)
    all_poses = np.array([(b.x, b.y, b.yaw) for b in manifest.observed], dtype=float).reshape(-1, 3)
    all_twists = np.zeros_like(all_poses)
    moving_index = [i for i, b in enumerate(manifest.objects) if not b.fixed]
    moving_rows = np.array([n_walls + i for i in moving_index], dtype=int)
    seen_index = [i for i, b in enumerate(manifest.objects) if not b.fixed and b.height > plane]

    robot_spec = manifest.robot
    start = (robot_spec.x, robot_spec.y, robot_spec.yaw)
    context = ControllerContext(
        robot_size=(robot_spec.footprint.half_extents()[0] * 2,
                    robot_spec.footprint.half_extents()[1] * 2),
        drive=manifest.drive, laser=laser_spec, start_pose=start, obstacles=static_map(manifest),
        bounds=manifest.bounds, tile_size=manifest.tile_size, control_rate=config.control_rate,
        seed=config.seed, max_speed=mission.max_speed)
    vmax = speed_limit(manifest, mission)
    wmax = manifest.drive.max_angular

    executor = MissionExecutor(mission.tasks())
    collector = DataCollector(header, sinks, laser_spec.max_range)
    contacts = _Contacts()
    odom = Odometry(start, config.odom_drift, rng)
    outcome: Outcome | None = None
    reason = ""
    now = 0.0
    path_length = 0.0
    min_laser = math.inf
    steps = 0
    wall_start = wallclock.perf_counter()
    cpu_start = wallclock.process_time()
    guard = GuardedController(controller, config.watchdog)
    world = BulletWorld(manifest, config.physics_rate)
    try:
        named = animated_bodies(manifest.objects, world.object_ids, config.seed, config.vary)
        animated = [a for _, a in named]
        animator = Animator(animated, config.physics_rate,
                            robot_spec.footprint.circumradius())
        collector.start()
        scan: LaserScan | None = None
        seen_scan: LaserScan | None = None  # the controller's read-only copy, one per scan
        scan_time: float | None = None
        cmd: VelocityCommand = STOP
        raw: VelocityCommand = STOP
        last_truth = start
        next_progress = 0.0

        def emit(events: list[MissionEvent]) -> None:
            for e in events:
                task = f" {e.task} (#{e.index})" if e.task is not None else ""
                why = f": {e.reason}" if e.reason else ""
                say(f"t={e.time:9.3f}  {e.kind}{task}{why}")
            collector.event(events)

        def record_sample(t: float, truth: tuple[float, float, float]) -> None:
            poses, twists = world.object_states()
            if len(moving_rows):
                all_poses[moving_rows] = poses[moving_index]
                all_twists[moving_rows] = twists[moving_index]
            fb_state, task = nav_view
            # Each sample owns its arrays: sinks may keep samples (the monitor's windows).
            collector.sample(t, truth, world.twist(world.robot_id), all_poses.copy(),
                             all_twists.copy(),
                             odom.pose, odom.twist, scan, scan_time, fb_state, task,
                             (raw.linear, raw.angular))

        nav_view: tuple[NavState, str | None] = (NavState.IDLE, None)
        try:
            if probe is not None:
                probe.tick(0.0)
            guard.reset(context)
            for k in range(last_step + 1):
                steps = k
                now = k / config.physics_rate
                truth = world.pose(world.robot_id)
                touching = world.robot_contact_indices()
                contacts.update([header.objects[i].name for i in touching], now)
                collector.touch(touching)
                if k % every_laser == 0:
                    moving = None
                    if seen_index:
                        poses, _ = world.object_states()
                        moving = shapes_of([manifest.objects[i] for i in seen_index],
                                           poses[seen_index])
                    ranges = laser.scan(truth, moving, rng, laser_noise)
                    ranges.flags.writeable = False  # what was measured; sinks keep it
                    min_laser = min(min_laser, float(ranges.min()))
                    scan = LaserScan(laser.angle_min, laser.angle_increment, laser_spec.min_range,
                                     laser_spec.max_range, ranges)
                    seen_scan = None
                    scan_time = now
                if k % every_control == 0:
                    path_length += math.hypot(truth[0] - last_truth[0], truth[1] - last_truth[1])
                    last_truth = truth
                    odom.update(truth, every_control / config.physics_rate)
                    if probe is not None:
                        probe.tick(now)
                    emit(executor.tick(now, guard, truth))
                    fb = guard.feedback()
                    nav_view = (fb.state, executor.current_task)
                    if executor.finished:
                        record_sample(now, truth)
                        break
                    if seen_scan is None:
                        seen_scan = read_only_scan(scan)
                    obs = Observation(now, odom.pose, odom.twist, seen_scan, scan_time)
                    raw = guard.step(obs)
                    # The motor driver saturates: commands beyond the drive limits are clipped.
                    cmd = VelocityCommand(min(max(raw.linear, -vmax), vmax),
                                          min(max(raw.angular, -wmax), wmax))
                final = k == last_step
                if final:
                    emit(executor.abandon(now, end_reason, truth, end_cause))
                    outcome, reason = "timeout", end_reason
                if k % every_sample == 0 or final:
                    record_sample(now, truth)
                if progress is not None and now >= next_progress:
                    progress(now, end_time)
                    next_progress = now + 1.0
                if final:
                    break
                if k % every_control == 0 and animated:
                    animator.correct(k, [world.pose(item.body) for item in animated], truth,
                                     world.twist(world.robot_id))
                for body, vx, vy, wz in animator.commands(k):
                    world.set_planar_velocity(body, vx, vy, wz)
                world.drive_robot(cmd.linear, cmd.angular, truth[2])
                world.step()
        except ControllerFault as fault:
            outcome, reason = "error", str(fault)
            say(f"t={now:9.3f}  error: {reason}")
            truth = world.pose(world.robot_id)
            emit(executor.abandon(now, f"run error: {reason}", truth))
            record_sample(now, truth)
        except KeyboardInterrupt:
            outcome, reason = "interrupted", "interrupted by the user (output incomplete)"
            say(f"t={now:9.3f}  interrupted")
            truth = world.pose(world.robot_id)
            emit(executor.abandon(now, "interrupted", truth))
            record_sample(now, truth)
        if outcome is None:
            failed = [r for r in executor.results if not r.succeeded]
            outcome = "failed" if failed else "completed"
            reason = (f"{len(failed)} of {len(executor.results)} tasks failed" if failed
                      else f"all {len(executor.results)} tasks succeeded")
        say(f"t={now:9.3f}  outcome {outcome}: {reason}")
        # The robot under test is stopped (a hosted one's processes killed and reaped) before
        # any output is finished: nothing it started can write after the outputs are.
        guard.close()
        if probe is not None:
            probe.end(now)
        collector.finish(now, outcome, reason)
    finally:
        guard.close()
        world.close()
    tasks = tuple(executor.results)
    measurements: dict[str, Any] = {
        "path_length": path_length,
        "tasks": [{"index": r.index, "task": r.task, "succeeded": r.succeeded, "reason": r.reason,
                   "start": r.start, "end": r.end, "time": r.end - r.start,
                   "final_distance": r.final_distance, "cause": r.cause} for r in tasks],
        "time_per_task": {f"{r.index}:{r.task}": r.end - r.start for r in tasks},
        "tasks_succeeded": sum(r.succeeded for r in tasks),
        "tasks_failed": sum(not r.succeeded for r in tasks),
        "collisions": contacts.episodes,
        "collided_with": sorted(contacts.bodies),
        "first_collision": contacts.first,
        "min_laser_range": min_laser if math.isfinite(min_laser) else None,
        "samples": collector.seq,
        "physics_steps": steps,
        "incomplete": outcome == "interrupted",
        "variations": variations_record(named),
    }
    # Other variations (the humans') record themselves under the same key: merge, never replace.
    variations = measurements.setdefault("variations", {})
    variations["start_jitter"] = started.to_json()
    return RunRecord(outcome, reason, now, tasks, measurements,
                     wallclock.perf_counter() - wall_start,
                     wallclock.process_time() - cpu_start, steps)


def summary_of(record: RunRecord, mission: ConcreteMission, controller: str,
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


