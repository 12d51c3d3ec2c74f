"""Benchmark of `rei run`: real-time factor of full missions, where the time goes, start-up.

For each bundled example mission and a generated 200-object room (192 static objects and
8 walking humans):

* full mission, everything on, as `rei run` runs it (``run_into``): physics (100 Hz) +
  animator + laser + odometry + the reference navigator (10 Hz) in its own process +
  mission executor + data collector + trace writer + monitor (the default specification's
  automata) + evaluator, until the mission ends. Real-time factor per wall second and per
  CPU second of the loop, the CPU of the run's process and of the robot's process added
  (the robot's from its first call to its last, read from /proc; its start-up is counted
  under start-up);
* where the CPU goes: the same mission once more, profiled (cProfile) with the navigator in
  this process, each function's own time given to a component by its module's path (numpy
  and builtins to their caller): physics (pybullet, runtime/simulation/world), laser, odometry,
  navigator (rei/runtime/robot), mission, animator, collector, trace writer, monitor,
  evaluator, run loop; plus the controller IPC, the difference between the hosted and the
  in-process loop's CPU;
* baseline: bare pybullet stepping of the same generated world for the same number of
  physics steps; the table reports full / bare;
* laser: one 360-beam scan by REI's numpy ray caster vs pybullet's ``rayTestBatch``;
* IR-SIM (PyPI ``ir-sim``), the light peer a user might pick instead: the same walls,
  objects and humans as rectangles and circles, the same robot footprint, a 360-beam
  2D lidar, stepped at 10 Hz (its lidar runs every step) with its built-in ``dash``
  behaviour for the same simulated time. REI is also run with its laser at 10 Hz for
  the equal-rate comparison (the loop without the monitor, as IR-SIM has none; CPU of both
  processes);
* start-up: the fixed CPU cost of one run in a fresh process (interpreter and imports, the
  run's set-up until the loop starts, the robot's process start-up), from a run cut after
  one physics step.

Scaling (``--scaling``): CPU per simulated second, every process counted, of a cyclic
mission in halls of 200, 1,000 and 2,000 objects, and of the 200-object hall's mission cut
at 5, 20 and 60 simulated minutes (the slope between lengths must stay flat: no cost that
grows with the time already simulated), with each run's peak memory.

Usage: python bench/simulation.py [--out DIR] [--repeat N] [--skip-irsim] [--world NAME]
       python bench/simulation.py --scaling [--repeat N] [--lengths S ...]
Real-time factor = simulated seconds / wall seconds; never asserted by tests.
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import json
import os
import pstats
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import rei.runtime.robot as robot_package
from rei.runtime.artifacts.monitor_config import load_monitor_config
from rei.runtime.artifacts.world import WorldManifest, load_manifest
from rei.runtime.raycast import scene_shapes
from rei.runtime.robot.contract import Controller, ControllerContext
from rei.runtime.robot.host import HostedController
from rei.runtime.robot.loading import load_controller
from rei.runtime.runs.session import run_into
from rei.runtime.simulation.assembly import LoopRecord, RunConfig, generate_world, run_mission
from rei.runtime.simulation.sensors.laser import Laser2D
from rei.runtime.simulation.world.bullet import BulletWorld
from rei.runtime.trace import TraceWriter

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = ["navigation", "simple_wall", "small_dense", "medium_sparse"]
TYPES = ["box", "chair", "pillar", "table"]


def hall(folder: Path, name: str, cols: int, rows: int, statics: int, humans: int = 8) -> Path:
    """A ``cols`` x ``rows`` hall (1 m tiles) with ``statics`` objects on a 2 m lattice and
    ``humans`` walking lanes across it at the same speed whatever its width; the room file."""
    grid = ["#" * (cols + 2)] + ["#" + "." * cols + "#" for _ in range(rows)] + ["#" * (cols + 2)]
    lines = [f"room {name} {{", "    tile 1.0", "    grid hall {"]
    lines += [f'        "{row}"' for row in grid]
    lines += ["    }", "    robot bot : turtlebot3_waffle on hall_1_1 heading 0"]
    lattice = [(r, c) for r in range(2, rows + 1, 2) for c in range(2, cols, 2)]
    if len(lattice) < statics:
        raise ValueError(f"a {cols} x {rows} hall holds {len(lattice)} objects, not {statics}")
    for n, (r, c) in enumerate(lattice[:statics]):
        lines.append(f"    object o{n} : {TYPES[n % len(TYPES)]} on hall_{r}_{c}")
    for h in range(humans):
        r = 3 + 2 * (h * 2 % 9)
        lap = round((30 + 3 * h) * cols / 42)
        lines.append(f"    human h{h} on hall_{r}_5 trajectory loop {{ hall_{r}_5 at 0  "
                     f"hall_{r}_{cols - 4} at {lap} }}")
    lines.append("}")
    room = folder / f"{name}.room"
    room.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return room


def big_room(folder: Path) -> Path:
    """A 42 x 22 hall with 192 static objects on a 2 m lattice and 8 humans walking lanes."""
    cols, rows = 42, 22
    hall(folder, "big_hall", cols, rows, 192)
    mission = folder / "big_hall.mission"
    mission.write_text(f'mission cross_the_hall in "big_hall.room" {{\n    time_limit 400\n'
                       f"    goal start_place at hall_1_1 timeout 30\n"
                       f"    goal far_corner at hall_{rows}_{cols} tolerance 0.3 timeout 370\n}}\n",
                       encoding="utf-8")
    return mission


def cyclic_hall(folder: Path, cols: int, rows: int, statics: int) -> Path:
    """A hall of ``statics`` objects and 8 humans and a mission that crosses the same 42 x 22
    corner of it and back (odd tiles: never on the lattice), again and again, for hours: how
    a run's cost grows with the objects and with the mission's length (``--scaling``)."""
    name = f"hall_{statics + 8}"
    hall(folder, name, cols, rows, statics)
    mission = folder / f"{name}.mission"
    mission.write_text(f'mission back_and_forth in "{name}.room" {{\n    time_limit 36000\n'
                       f"    cycles 100\n"
                       f"    goal far_corner at hall_21_41 tolerance 0.3 timeout 370\n"
                       f"    goal back_home at hall_1_1 tolerance 0.3 timeout 370\n}}\n",
                       encoding="utf-8")
    return mission


def bare_rate(manifest: WorldManifest, steps: int) -> tuple[float, float]:
    """Physics steps per (wall, CPU) second of the same world, nothing else running."""
    with BulletWorld(manifest, 100.0) as world:
        wall, cpu = time.perf_counter(), time.process_time()
        for _ in range(steps):
            world.step()
        return (steps / (time.perf_counter() - wall), steps / (time.process_time() - cpu))


def laser_costs(manifest: WorldManifest, scans: int = 50) -> tuple[float, float]:
    """Milliseconds per 360-beam scan: REI's numpy caster, pybullet's rayTestBatch."""
    plane = manifest.laser.mount_z
    laser = Laser2D(manifest.laser, scene_shapes(manifest, manifest.objects))
    pose = (manifest.robot.x, manifest.robot.y, manifest.robot.yaw)
    start = time.perf_counter()
    for _ in range(scans):
        laser.scan(pose)
    ours = (time.perf_counter() - start) / scans * 1e3
    with BulletWorld(manifest, 100.0) as world:
        o = laser.origin(pose)
        angles = laser.angles + pose[2]
        start = time.perf_counter()
        for _ in range(scans):
            world.ray_scan((float(o[0]), float(o[1]), plane), angles, manifest.laser.max_range)
        theirs = (time.perf_counter() - start) / scans * 1e3
    return ours, theirs


def process_cpu(pid: int) -> float:
    """CPU seconds (user + system) a live process used so far, from /proc."""
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class MeteredHost(HostedController):
    """The robot's own process, its CPU read when its first call (reset) has returned and
    again before it is stopped: what the robot spent during the loop, start-up excluded."""

    loop_cpu: float = 0.0

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._begun = process_cpu(self.pid)

    def close(self) -> None:
        begun = getattr(self, "_begun", None)
        if begun is not None:
            with contextlib.suppress(OSError):
                self.loop_cpu = process_cpu(self.pid) - begun
            self._begun = None
        super().close()


@contextlib.contextmanager
def controllers(make: Callable[[str, str | None], Controller]) -> Iterator[None]:
    """``run_into`` makes its controller with ``make`` while inside (restored after)."""
    saved = robot_package.make_controller
    robot_package.make_controller = make  # type: ignore[assignment]
    try:
        yield
    finally:
        robot_package.make_controller = saved


def _figure(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.0f}"


def full_mission(mission_file: Path, work: Path) -> dict[str, Any]:
    """One `rei run` of the mission, everything on, the robot in its own process."""
    hosts: list[MeteredHost] = []

    def make(spec: str, folder: str | None = None) -> Controller:
        hosts.append(MeteredHost(spec, folder))
        return hosts[-1]

    with controllers(make):
        _, record = run_into(mission_file, work / "run")
        # The loop's CPU includes set-up done in it (the world's bodies, the monitor's start,
        # the controller's reset): a run cut after one step measures that part.
        _, cut = run_into(mission_file, work / "cut", duration=0.01)
    cpu = record.cpu_seconds + hosts[0].loop_cpu
    # A noisy cut run can cost about as much as a short mission's loop: then the two cannot
    # be told apart and the figure is left out rather than shown as nonsense.
    steady = cpu - cut.cpu_seconds if cpu - cut.cpu_seconds > 0.1 * cpu else None
    # The robot's process starts while the world is built; what is left of its start-up is
    # waited for in the loop's first call: that wait is start-up, not the loop's.
    wall = record.wall_seconds - getattr(hosts[0], "load_wait", 0.0)  # older hosts: none
    return {"record": record, "rtf": record.duration / wall,
            "cpu_rtf": record.duration / cpu, "cpu": cpu,
            "steady_rtf": record.duration / steady if steady is not None else None,
            "in_loop_setup": cut.cpu_seconds}


def equal_rate(mission_file: Path, work: Path, laser_rate: float) -> dict[str, Any]:
    """The loop without monitor at another laser rate (IR-SIM's), robot in its own process."""
    world_dir = work / "world"
    mission = generate_world(mission_file, world_dir, replace=True)
    manifest = load_manifest(world_dir)
    manifest = replace(manifest, laser=replace(manifest.laser, rate=laser_rate))
    host = MeteredHost("reference")
    try:
        record = run_mission(mission, manifest, load_monitor_config(world_dir), host,
                             [TraceWriter(work / "trace.jsonl")], RunConfig(seed=0))
    finally:
        host.close()
    cpu = record.cpu_seconds + host.loop_cpu
    return {"mission": mission, "manifest": manifest, "record": record,
            "rtf": record.duration / record.wall_seconds, "cpu_rtf": record.duration / cpu}


COMPONENTS = (
    ("pybullet", "physics"), ("runtime/simulation/world/", "physics"),
    # the run's components (rei.runtime.simulation.loop), each under its own name
    ("simulation/loop/physics", "physics"), ("simulation/loop/scans", "laser"),
    ("simulation/loop/dead_reckoning", "odometry"), ("simulation/loop/fault_injection", "faults"),
    ("simulation/loop/tasks", "mission"), ("simulation/loop/humans", "animator"),
    ("simulation/loop/sampling", "collector"), ("simulation/loop/", "run loop"),
    ("simulation/faults", "faults"),
    ("simulation/sensors/laser", "laser"), ("simulation/sensors/odometry", "odometry"),
    ("runtime/raycast", "laser"),
    ("runtime/robot/host", "controller IPC"), ("runtime/robot/watchdog", "run loop"),
    ("runtime/robot/", "navigator"), ("simulation/mission", "mission"),
    ("simulation/animator", "animator"), ("runtime/trace", "trace writer"),
    ("json/", "trace writer"), ("simulation/sampler", "collector"),
    ("observation/evaluator", "evaluator"), ("runtime/observation", "monitor"),
    ("/automata/automata.py", "monitor"), ("reactivex", "monitor"),
    ("simulation/assembly.py", "run loop"), ("runtime/messages", "run loop"),
    ("arpeggio", "set-up"), ("textx", "set-up"), ("jinja2", "set-up"), ("rei/lang", "set-up"),
    ("rei_lang/", "set-up"), ("rei/generators", "set-up"), ("generators/", "set-up"),
    ("<frozen", "set-up"),
)
"""Module path fragment -> component, first match wins (a fragment matches both an installed
path, .../rei/runtime/..., and a checkout's, .../runtime/...)."""
_CALLER_PAYS = ("~", "numpy/", "dataclasses.py", "functools.py", "enum.py", "typing.py",
                "abc.py", "copy.py", "contextlib.py", "threading.py", "queue.py")
"""Builtins and helpers whose own time goes to the component that called them."""


def _component(path: str) -> str | None:
    path = path.replace(os.sep, "/")
    if "/rei/" not in path:  # an editable install: rei.runtime is runtime/, rei.lang rei_lang/
        path = path.replace("/runtime/", "/rei/runtime/").replace("/rei_lang/", "/rei/lang/") \
            .replace("/generators/", "/rei/generators/")
    for fragment, name in COMPONENTS:
        if fragment in path:
            return name
    if path == "~" or any(f in path for f in _CALLER_PAYS):
        return None
    return "other"


def component_shares(stats: pstats.Stats) -> Counter[str]:
    """Own time per component; builtins and numpy share theirs among their callers."""
    table = stats.stats  # type: ignore[attr-defined]
    memo: dict[Any, Counter[str]] = {}

    def owners(func: Any, depth: int = 0) -> Counter[str]:
        if func in memo:
            return memo[func]
        own = _component(func[0]) if "pybullet" not in func[2] else "physics"
        out: Counter[str] = Counter()
        callers = table[func][4] if func in table else {}
        if own is not None or depth > 6 or not callers:
            out[own or "other"] = 1.0
        else:
            total = sum(v[2] for v in callers.values()) or 1.0
            for caller, v in callers.items():
                for name, w in owners(caller, depth + 1).items():
                    out[name] += w * v[2] / total
        memo[func] = out
        return out

    shares: Counter[str] = Counter()
    for func, (_, _, own_time, _, _) in table.items():
        for name, w in owners(func).items():
            shares[name] += own_time * w
    return shares


def profiled(mission_file: Path, work: Path) -> tuple[Counter[str], LoopRecord]:
    """The mission with the navigator in this process, under cProfile during the loop."""
    profile = cProfile.Profile()

    def make(spec: str, folder: str | None = None) -> Controller:
        return load_controller(spec, folder)

    import rei.runtime.simulation.assembly as run_module  # noqa: PLC0415

    loop = run_module.run_mission

    def run_profiled(*args: Any, **kwargs: Any) -> LoopRecord:
        profile.enable()
        try:
            return loop(*args, **kwargs)
        finally:
            profile.disable()

    run_module.run_mission = run_profiled  # type: ignore[assignment]
    try:
        with controllers(make):
            _, record = run_into(mission_file, work / "profiled", watchdog=None)
    finally:
        run_module.run_mission = loop  # type: ignore[assignment]
    return component_shares(pstats.Stats(profile)), record


def in_process_cpu(mission_file: Path, work: Path) -> float:
    """Loop CPU of the mission with the navigator in this process (no messages), less the
    set-up done in the loop (a run cut after one step: the navigator's reset is in it)."""
    with controllers(lambda spec, folder=None: load_controller(spec, folder)):
        _, record = run_into(mission_file, work / "in_process", watchdog=None)
        _, cut = run_into(mission_file, work / "in_process_cut", watchdog=None, duration=0.01)
    return record.cpu_seconds - cut.cpu_seconds


STARTUP_PROBE = """
import resource, sys, time
cpu0, wall0 = time.process_time(), time.perf_counter()
from pathlib import Path
from rei.runtime.runs.session import run_into
cpu1 = time.process_time()
run_into(Path(sys.argv[1]), Path(sys.argv[2]), duration=0.01)
cpu2, wall2 = time.process_time(), time.perf_counter()
child = resource.getrusage(resource.RUSAGE_CHILDREN)
print(cpu0, cpu1 - cpu0, cpu2 - cpu1, child.ru_utime + child.ru_stime, wall2 - wall0)
"""
"""A run cut after its first physics step in a fresh interpreter: CPU before any import,
of the imports of `rei run`'s path, of the run's set-up, of the robot's process; wall."""


def startup(mission_file: Path, work: Path) -> dict[str, float]:
    """The fixed cost of one run (best of the repeats is taken by the caller)."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", STARTUP_PROBE, str(mission_file),
                           str(work / "startup")], capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    python, imports, setup, robot, _ = (float(v) for v in done.stdout.split())
    return {"python": python, "imports": imports, "setup": setup, "robot": robot,
            "total": python + imports + setup + robot, "wall": wall}


SCALING_PROBE = """
import json, resource, sys, time
from pathlib import Path
from rei.runtime.runs.session import run_into

class Windows:
    \"\"\"A sink reading this process's CPU at the sample that opens each sixth of the run:
    the cost of each stretch of simulated time within one run.\"\"\"
    def __init__(self, length):
        self.width, self.marks = length / 6, []
    def start(self, header):
        pass
    def feed(self, sample):
        if sample.time >= len(self.marks) * self.width:
            self.marks.append((sample.time, time.process_time()))
    def finish(self, end_time, outcome, reason):
        self.marks.append((end_time, time.process_time()))

windows = Windows(float(sys.argv[3]))
cpu = time.process_time()
_, record = run_into(Path(sys.argv[1]), Path(sys.argv[2]), duration=float(sys.argv[3]),
                     sinks=[windows])
cpu = time.process_time() - cpu
stretches = [(c1 - c0) / (t1 - t0) for (t0, c0), (t1, c1)
             in zip(windows.marks, windows.marks[1:]) if t1 > t0]
robot = resource.getrusage(resource.RUSAGE_CHILDREN)
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"sim": record.duration, "run": cpu, "robot": robot.ru_utime + robot.ru_stime,
                  "loop": record.cpu_seconds, "rss": rss, "outcome": record.outcome,
                  "components": record.component_cpu, "stretches": stretches}))
"""
"""One whole `rei run` (generation, loop, summary, report) in a fresh interpreter, cut at a
duration: the CPU of the run's process and of the robot's, the loop's, peak memory (MiB),
and the run's process's CPU per simulated second in each sixth of the run (its first sixth
holds the loop's own set-up)."""

SCALING_HALLS = ((42, 22, 192), (92, 46, 992), (130, 64, 1992))
"""(columns, rows, static objects) of the halls of 200, 1,000 and 2,000 objects."""


def whole_run(mission_file: Path, work: Path, duration: float) -> dict[str, Any]:
    """A fresh `rei run` of the mission cut at ``duration`` (see ``SCALING_PROBE``)."""
    done = subprocess.run([sys.executable, "-c", SCALING_PROBE, str(mission_file),
                           str(work / f"run_{duration:g}"), str(duration)],
                          capture_output=True, text=True, check=True)
    figures: dict[str, Any] = json.loads(done.stdout.splitlines()[-1])
    figures["cpu"] = figures["run"] + figures["robot"]
    return figures


def scaling(work: Path, repeat: int, object_seconds: float,
            lengths: tuple[float, ...]) -> None:
    """How a run's cost grows: CPU per simulated second against the objects in the room
    (200, 1,000, 2,000), and against the mission's length in the 200-object hall (each
    length one whole run: the increments between lengths are the slope). Prints tables."""
    print(f"\n## Scaling: objects (a cyclic mission in halls of 200-2,000 objects, "
          f"{object_seconds:g} simulated s; per simulated second, set-up excluded: "
          f"(whole run - run cut after one step) / simulated s; best of {repeat})\n")
    print("| bodies | objects | sim s | whole run CPU s | cut run CPU s | loop CPU s "
          "| CPU ms per sim s | × real time per CPU s | bare pybullet CPU ms per sim s "
          "| loop's world component ms per sim s | loop's other components ms per sim s "
          "| peak MiB |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    missions = {}
    for cols, rows, statics in SCALING_HALLS:
        folder = work / f"hall_{statics}"
        folder.mkdir(parents=True, exist_ok=True)
        mission = missions[statics] = cyclic_hall(folder, cols, rows, statics)
        runs = [whole_run(mission, folder, object_seconds) for _ in range(repeat)]
        run = min(runs, key=lambda r: r["cpu"])
        cut = min((whole_run(mission, folder, 0.01) for _ in range(repeat)),
                  key=lambda r: r["cpu"])
        per = (run["cpu"] - cut["cpu"]) / run["sim"]
        world = run["components"].get("world", 0.0)  # physics and the truth read from it
        manifest = load_manifest(folder / "run_0.01" / "world")
        bodies = len(manifest.walls) + len(manifest.objects) + 1
        bare = max(bare_rate(manifest, 1000)[1] for _ in range(repeat))  # steps per CPU s
        print(f"| {bodies} | {statics + 8} | {run['sim']:.0f} | {run['cpu']:.2f} | "
              f"{cut['cpu']:.2f} | {run['loop']:.2f} | {1e3 * per:.2f} | {1 / per:.0f} | "
              f"{1e3 * 100.0 / bare:.2f} | {1e3 * world / run['sim']:.2f} | "
              f"{1e3 * (sum(run['components'].values()) - world) / run['sim']:.2f} | "
              f"{run['rss']:.0f} |", flush=True)
    print(f"\n## Scaling: mission length (the 200-object hall's cyclic mission cut at "
          f"{', '.join(f'{t:g}' for t in lengths)} simulated s, one whole run each; slope = "
          f"CPU per simulated second between two lengths)\n")
    print("| sim s | outcome | whole run CPU s | loop CPU s | CPU ms per sim s (whole run) "
          "| slope from the previous length, ms per sim s | run's process ms per sim s, "
          "sixths 2-6 of the run | peak MiB |")
    print("|---:|---|---:|---:|---:|---:|---|---:|")
    previous = None
    for seconds in lengths:
        run = min((whole_run(missions[192], work / "hall_192", seconds)
                   for _ in range(repeat)), key=lambda r: r["cpu"])
        slope = "" if previous is None else \
            f"{1e3 * (run['cpu'] - previous['cpu']) / (run['sim'] - previous['sim']):.2f}"
        print(f"| {run['sim']:.0f} | {run['outcome']} | {run['cpu']:.2f} | {run['loop']:.2f} | "
              f"{1e3 * run['cpu'] / run['sim']:.2f} | {slope} | "
              f"{' '.join(f'{1e3 * v:.1f}' for v in run['stretches'][1:])} | "
              f"{run['rss']:.0f} |", flush=True)
        previous = run


def irsim_world(manifest: WorldManifest, goal: tuple[float, float], path: Path) -> None:
    x0, y0, x1, y1 = manifest.bounds
    r = manifest.robot
    laser = manifest.laser
    fp = r.footprint
    out = [
        "world:", f"  height: {y1 - y0}", f"  width: {x1 - x0}", "  step_time: 0.1",
        "  sample_time: 0.1", f"  offset: [{x0}, {y0}]", "  collision_mode: 'stop'", "",
        "robot:", "  - kinematics: {name: 'diff'}",
        f"    shape: {{name: 'rectangle', length: {fp.size_x}, width: {fp.size_y}}}",  # type: ignore[union-attr]
        f"    state: [{r.x}, {r.y}, {r.yaw}]", f"    goal: [{goal[0]}, {goal[1]}, 0]",
        f"    vel_max: [{manifest.drive.max_linear}, {manifest.drive.max_angular}]",
        "    behavior: {name: 'dash'}", "    sensors:", "      - type: 'lidar2d'",
        f"        range_min: {laser.min_range}", f"        range_max: {laser.max_range}",
        f"        angle_range: {laser.fov}", f"        number: {laser.beams}", "",
        "obstacle:",
    ]
    for body in manifest.walls + manifest.objects:
        f = body.footprint
        if hasattr(f, "radius"):
            shape = f"{{name: 'circle', radius: {f.radius}}}"  # type: ignore[union-attr]
        else:
            shape = f"{{name: 'rectangle', length: {f.size_x}, width: {f.size_y}}}"  # type: ignore[union-attr]
        out.append(f"  - shape: {shape}")
        out.append(f"    state: [{body.x}, {body.y}, {body.yaw}]")
        if body.trajectory is not None:
            last = body.trajectory.points[len(body.trajectory.points) // 2]
            out.append("    kinematics: {name: 'omni'}")
            out.append("    vel_max: [1.0, 1.0]")
            out.append(f"    goal: [{last[1]}, {last[2]}, 0]")
            out.append("    behavior: {name: 'dash'}")
    path.write_text("\n".join(out) + "\n", encoding="utf-8")


def irsim_rtf(manifest: WorldManifest, goal: tuple[float, float], seconds: float,
              work: Path) -> tuple[float, float] | None:
    os.environ.setdefault("MPLBACKEND", "Agg")  # headless: no GUI backends tried and reported
    try:
        import irsim  # noqa: PLC0415
    except ImportError:
        return None
    world = work / "irsim.yaml"
    irsim_world(manifest, goal, world)
    env = irsim.make(str(world), display=False, disable_all_plot=True, log_level="ERROR")
    steps = max(1, int(round(seconds / 0.1)))
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(steps):
        env.step()
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    if hasattr(env, "end"):
        env.end(0)
    return steps * 0.1 / wall, steps * 0.1 / cpu


def best(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The fastest of repeated runs: other load on the machine only ever slows a run down."""
    return max(runs, key=lambda r: r["cpu_rtf"])


SHOWN = ("physics", "laser", "odometry", "navigator", "mission", "animator", "collector",
         "trace writer", "monitor", "evaluator", "run loop")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure, best kept")
    parser.add_argument("--skip-irsim", action="store_true")
    parser.add_argument("--world", action="append", default=None,
                        help="only this world (an example's name or 'big'); repeatable")
    parser.add_argument("--scaling", action="store_true",
                        help="only how the cost grows: halls of 200, 1,000 and 2,000 objects, "
                             "and a mission of 5, 20 and 60 simulated minutes")
    parser.add_argument("--lengths", type=float, nargs="+", default=[300.0, 1200.0, 3600.0],
                        metavar="S", help="mission lengths of --scaling (simulated seconds)")
    parser.add_argument("--object-seconds", type=float, default=120.0, metavar="S",
                        help="simulated seconds of each hall of --scaling")
    args = parser.parse_args(argv)
    work_root = Path(args.out or tempfile.mkdtemp(prefix="rei-bench-sim-"))
    if args.scaling:
        load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
        print(f"# rei bench simulation --scaling — {time.strftime('%Y-%m-%d %H:%M')}, "
              f"{os.cpu_count()} cores, load average {load}", flush=True)
        scaling(work_root, args.repeat, args.object_seconds, tuple(args.lengths))
        load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
        print(f"\n# load average at the end: {load}")
        return 0
    missions = [(name, REPO / "examples" / name / f"{name}.mission") for name in EXAMPLES]
    (work_root / "big").mkdir(parents=True, exist_ok=True)
    missions.append(("200 objects", big_room(work_root / "big")))
    if args.world:
        missions = [(n, p) for n, p in missions
                    if n in args.world or (n == "200 objects" and "big" in args.world)]
    load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
    print(f"# rei bench simulation — {time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} "
          f"cores, load average {load}, python {sys.version.split()[0]}, best of "
          f"{args.repeat}; × real time per wall second (per CPU second of the loop, the "
          f"run's and the robot's processes)", flush=True)
    print("| world | bodies | outcome | sim s | full mission | full, set-up excluded (CPU) "
          "| bare pybullet | full / bare | laser numpy ms | laser rayTestBatch ms "
          "| REI, laser 10 Hz | IR-SIM 10 Hz | REI / IR-SIM |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    profiles, startups = [], []
    for name, path in missions:
        work = work_root / name.replace(" ", "_")
        work.mkdir(parents=True, exist_ok=True)
        full = best([full_mission(path, work) for _ in range(args.repeat)])
        equal = best([equal_rate(path, work / "10hz", 10.0) for _ in range(args.repeat)])
        record, manifest, mission = full["record"], equal["manifest"], equal["mission"]
        bare = max((bare_rate(manifest, max(record.steps, 1000)) for _ in range(args.repeat)),
                   key=lambda r: r[1])
        bare = (bare[0] / 100.0, bare[1] / 100.0)
        ours_ms, bullet_ms = min(laser_costs(manifest) for _ in range(args.repeat))
        peer = None
        if not args.skip_irsim:
            goal = mission.tasks()[-1]
            runs = [irsim_rtf(manifest, (goal.x, goal.y), record.duration, work)
                    for _ in range(args.repeat)]
            peer = max((r for r in runs if r is not None), key=lambda r: r[1], default=None)
        bodies = len(manifest.walls) + len(manifest.objects) + 1
        peer_text = f"{peer[0]:.0f} ({peer[1]:.0f})" if peer is not None else "n/a"
        ratio = f"{equal['cpu_rtf'] / peer[1]:.2f}" if peer else "n/a"
        print(f"| {name} | {bodies} | {record.outcome}, {record.measurements['collisions']} "
              f"collisions | {record.duration:.1f} | {full['rtf']:.0f} ({full['cpu_rtf']:.0f}) | "
              f"{_figure(full['steady_rtf'])} | "
              f"{bare[0]:.0f} ({bare[1]:.0f}) | {full['cpu_rtf'] / bare[1]:.2f} | "
              f"{ours_ms:.3f} | {bullet_ms:.3f} | {equal['rtf']:.0f} ({equal['cpu_rtf']:.0f}) | "
              f"{peer_text} | {ratio} |", flush=True)
        inside = min(in_process_cpu(path, work) for _ in range(args.repeat))
        shares, _ = profiled(path, work)
        profiles.append((name, full, inside, shares))
        startups.append((name, min((startup(path, work) for _ in range(args.repeat)),
                                   key=lambda r: r["total"])))
    print("\nWhere the loop's CPU goes, set-up excluded (% of the full mission's loop CPU "
          "in both processes, less the set-up done in the loop as a run cut after one step "
          "measures it). Controller IPC = hosted − in-process loop CPU, both set-up "
          "excluded; the components share the rest as a cProfile run with the navigator "
          "in-process shares its own time (set-up excluded)\n")
    print("| world | loop CPU s | set-up in loop s | in-process, set-up excluded s "
          "| controller IPC | "
          + " | ".join(SHOWN) + " | other |")
    print("|---|---:|---:|---:|---:|" + "---:|" * (len(SHOWN) + 1))
    for name, full, inside, shares in profiles:
        steady = max(full["cpu"] - full["in_loop_setup"], 1e-9)
        ipc = max(steady - inside, 0.0)
        rest = max(steady - ipc, 0.0)
        total = sum(v for k, v in shares.items() if k != "set-up") or 1.0
        cells = [100 * shares.get(c, 0.0) / total * rest / steady for c in SHOWN]
        other = 100 * sum(v for k, v in shares.items() if k not in SHOWN and k != "set-up") \
            / total * rest / steady
        print(f"| {name} | {full['cpu']:.2f} | {full['in_loop_setup']:.2f} | {inside:.2f} | "
              f"{100 * ipc / steady:.0f} % | " + " | ".join(f"{c:.0f} %" for c in cells)
              + f" | {other:.0f} % |")
    print("\nStart-up: the fixed cost of one run in a fresh process (CPU seconds; wall seconds "
          "of the whole process)\n")
    print("| world | interpreter | imports | set-up | robot's process | total CPU | wall |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, st in startups:
        print(f"| {name} | {st['python']:.2f} | {st['imports']:.2f} | {st['setup']:.2f} | "
              f"{st['robot']:.2f} | {st['total']:.2f} | {st['wall']:.2f} |")
    load = " / ".join(f"{v:.1f}" for v in os.getloadavg())
    print(f"\n# load average at the end: {load}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
