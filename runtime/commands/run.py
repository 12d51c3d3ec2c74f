"""`rei run MISSION -o DIR`: generate the world, run the mission headless, monitor and evaluate it.

Writes into DIR: ``world/`` (the generated `pybullet` and `monitor` targets the run loads),
``automata/`` (the RxPY automata generated from the .vepl), ``trace.jsonl`` (the sample
stream), ``events.csv`` (one row per signal), ``summary.json`` (a RunSummary with verdicts),
``report.html`` (the run's page: verdicts, timeline, distances, speed, map; not with
--no-monitor) and ``run.log`` (the mission events and the outcome). Every output is a
function of the inputs, the seed and the REI version only: wall-clock time goes to the
terminal, never into DIR. Exit status: 0 every requirement passed, 1 one failed or was
inconclusive (without the monitor: a task failed or the time ran out), 2 invalid input, 3 a
run error, 130 interrupted (the outputs are then marked incomplete).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import IO

from rei.generators.output import open_output
from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_ERROR
from rei.lang.errors import ReiError
from rei.runtime.collector import SampleSink, TraceWriter, load_monitor_config
from rei.runtime.commands.run_config import apply_run_config, defer_defaults
from rei.runtime.errors import RunError
from rei.runtime.evaluator import merge_summary, write_summary
from rei.runtime.monitor import MonitorSink, generate_automata
from rei.runtime.monitor.functions import load_functions
from rei.runtime.results import RunSummary, judge
from rei.runtime.robot import BUILT_IN, make_controller
from rei.runtime.run import RunConfig, RunRecord, generate_world, run_mission, summary_of
from rei.runtime.world import load_manifest
from rei.runtime.world.start_jitter import START_JITTER

PAGE = "report.html"
TRACE = "trace.jsonl"
SUMMARY = "summary.json"
LOG = "run.log"
EVENTS = "events.csv"


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "run", help="run a mission in the simulator, monitor it and record what happened",
        description="Check and generate what the mission needs, run it headless in pybullet "
                    "with the robot under test, monitor it with the event automata of a .vepl "
                    "specification, and write trace.jsonl, events.csv, summary.json (with the "
                    "requirement verdicts), report.html (the run's page) and run.log into the "
                    "output folder. Same inputs and "
                    "seed give byte-identical outputs. Exit status: 0 every requirement passed, "
                    "1 one failed or was inconclusive, 2 invalid input, 3 a run error, "
                    "130 interrupted.")
    parser.add_argument("mission", type=Path, nargs="?", default=None, metavar="MISSION",
                        help="the .mission file (optional with --config)")
    parser.add_argument("-o", "--output", type=Path, default=None, metavar="DIR",
                        help="output folder (created if missing; required without --config)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    parser.add_argument("--controller", default="reference", metavar="NAME",
                        help=f"robot under test: {', '.join(BUILT_IN)}, or module:Class "
                             f"(default reference)")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="stop after S simulated seconds (default: the mission's time limit)")
    parser.add_argument("--watchdog", type=float, default=5.0, metavar="S",
                        help="wall-clock seconds a controller call may take (default 5)")
    parser.add_argument("--physics-rate", type=float, default=100.0, metavar="HZ",
                        help="physics steps per simulated second (default 100)")
    parser.add_argument("--odom-drift", type=float, default=0.0, metavar="SIGMA",
                        help="relative odometry error per control tick (default 0: exact)")
    parser.add_argument("--laser-noise", type=float, default=None, metavar="SIGMA",
                        help="standard deviation (m) of the laser's range error (default: the "
                             "robot's catalogue type, 0.01 for the TurtleBot3 Waffle; 0: exact)")
    parser.add_argument("--no-variation", action="store_true",
                        help="run exactly the declared scene: no seeded variation (by default "
                             "the seed jitters the robot's start pose by up to 5 cm and 5 "
                             "degrees and draws each human's start delay and speed scale, so "
                             "repeats explore)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitoring specification: queries, event patterns, signals with "
                             "utilities and requirements (default: REI's default.vepl)")
    parser.add_argument("--functions", default=None, metavar="MODULE",
                        help="Python module (dotted name or .py file) defining the user "
                             "functions the specification declares with 'function'")
    parser.add_argument("--no-monitor", action="store_true",
                        help="record the trace only (monitor it later with `rei replay`)")
    parser.add_argument("--quiet", action="store_true", help="no progress display")
    defer_defaults(parser)
    parser.set_defaults(func=run)


def _finite(name: str, value: float | None) -> None:
    if value is not None and not math.isfinite(value):
        raise RunError(f"{name}: expected a finite number, found {value}")


def run_into(mission_path: Path, out_dir: Path, controller: str = "reference", seed: int = 0,
             duration: float | None = None, watchdog: float | None = 5.0,
             physics_rate: float = 100.0, odom_drift: float = 0.0,
             sinks: Sequence[SampleSink] = (), progress: IO[str] | None = None,
             vepl: Path | None = None, monitor: bool = True, laser_noise: float | None = None,
             variation: bool = True, functions: str | None = None
             ) -> tuple[RunSummary, RunRecord]:
    """Everything `rei run` does: generate, run, monitor with the .vepl's automata (the
    default specification unless ``vepl``; none when ``monitor`` is False), write outputs.
    Extra ``sinks`` see the same stream as the trace and the monitor."""
    for name, value in (("--duration", duration), ("--watchdog", watchdog),
                        ("--physics-rate", physics_rate), ("--odom-drift", odom_drift),
                        ("--laser-noise", laser_noise)):
        _finite(name, value)
    if duration is not None and duration <= 0:
        raise RunError(f"--duration: expected a positive number of seconds, found {duration:g}")
    if physics_rate <= 0 or odom_drift < 0 or (watchdog is not None and watchdog <= 0):
        raise RunError("--physics-rate and --watchdog expected positive numbers, --odom-drift "
                       "a non-negative one")
    if laser_noise is not None and not 0 <= laser_noise <= 1:
        raise RunError(f"--laser-noise: expected metres from 0 to 1, found {laser_noise:g}")
    if mission_path.suffix != ".mission":
        raise RunError(f"expected a .mission file to run, found '{mission_path}'")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunError(f"cannot create the output folder '{out_dir}': {exc.strerror}") from None
    # The specification is checked and generated first: a bad .vepl is reported (exit 2)
    # before any world is built.
    automata = generate_automata(vepl, out_dir / "automata", replace=True) if monitor else None
    user = load_functions(functions, vepl) if monitor else {}
    monitor_sink = MonitorSink(vepl, out_dir, functions=user, automata=automata) \
        if monitor else None
    world_dir = out_dir / "world"
    mission = generate_world(mission_path, world_dir, replace=True)
    manifest = load_manifest(world_dir)
    monitor_config = load_monitor_config(world_dir)
    robot = make_controller(controller)
    config = RunConfig(seed=seed, physics_rate=physics_rate, duration=duration,
                       watchdog=watchdog, odom_drift=odom_drift, laser_noise=laser_noise,
                       jitter=START_JITTER if variation else None, vary=variation)
    for stale in (out_dir / SUMMARY, out_dir / TRACE, out_dir / EVENTS, out_dir / PAGE):
        stale.unlink(missing_ok=True)

    def show(now: float, end: float) -> None:
        if progress is None:
            return
        width = 30
        done = int(width * now / end) if end > 0 else width
        progress.write(f"\r  {mission.name}: {now:7.1f} / {end:.0f} s  "
                       f"[{'#' * done}{'.' * (width - done)}]")
        progress.flush()

    with open_output(out_dir / LOG) as log_file:
        def log(line: str) -> None:
            log_file.write(line + "\n")
            log_file.flush()

        log(f"mission {mission.name} in room {mission.world.name}, controller {controller}, "
            f"seed {seed}")
        record = run_mission(mission, manifest, monitor_config, robot,
                             [TraceWriter(out_dir / TRACE),
                              *([monitor_sink] if monitor_sink is not None else []), *sinks],
                             config,
                             progress=show if progress is not None else None, log=log)
    if progress is not None:
        progress.write("\n")
    summary = summary_of(record, mission, controller, seed)
    if monitor_sink is not None and monitor_sink.result is not None:
        summary = merge_summary(summary, monitor_sink.result)
    write_summary(summary, out_dir)
    return summary, record


def run(args: argparse.Namespace) -> int:
    args = apply_run_config(args)
    progress = None if args.quiet or not sys.stderr.isatty() else sys.stderr
    summary, record = run_into(args.mission, args.output, args.controller, args.seed,
                               args.duration, args.watchdog, args.physics_rate, args.odom_drift,
                               progress=progress, vepl=args.vepl, monitor=not args.no_monitor,
                               laser_noise=args.laser_noise, variation=not args.no_variation,
                               functions=args.functions)
    rtf = record.duration / record.wall_seconds if record.wall_seconds > 0 else math.inf
    cpu_rtf = record.duration / record.cpu_seconds if record.cpu_seconds > 0 else math.inf
    m = summary.measurements
    print(f"{summary.mission}: {summary.outcome} ({summary.reason}) after "
          f"{summary.duration:.1f} s simulated, {m['tasks_succeeded']} task(s) succeeded, "
          f"{m['tasks_failed']} failed, {m['collisions']} collision(s); "
          f"{rtf:.0f}x real time ({cpu_rtf:.0f}x per CPU second); outputs in {args.output}",
          file=sys.stderr)
    if not args.no_monitor:
        write_page(args.output)
    return exit_status(summary, args.output, monitored=not args.no_monitor)


def write_page(out_dir: Path, trace: Path | None = None) -> Path | None:
    """Write the run's report.html; a page that cannot be written is reported, never allowed
    to change the run's verdict or exit status."""
    from rei.runtime.report.run_page import write_run_page  # noqa: PLC0415  (matplotlib)

    try:
        page = write_run_page(out_dir, trace)
    except (ReiError, OSError) as exc:
        print(f"  report.html not written: {exc}", file=sys.stderr)
        return None
    print(f"  run page: {page}", file=sys.stderr)
    return page


def exit_status(summary: RunSummary, out_dir: Path, monitored: bool = True) -> int:
    """Print the verdicts and return the exit status of the one pass rule
    (rei.runtime.results.judge): 0 pass (or, without the monitor, unjudged), 1 fail or
    inconclusive, 3 run error, 130 interrupted."""
    verdict = judge(summary)
    if verdict == "error":
        print(f"rei run: error: {summary.reason}", file=sys.stderr)
        return EXIT_RUN_ERROR
    if verdict == "interrupted":
        return EXIT_INTERRUPTED
    if not monitored:
        print("  not judged (--no-monitor): judge the trace with `rei replay`", file=sys.stderr)
        return EXIT_OK
    for v in summary.verdicts:
        at = f" at t={v.decided_at:g} s" if v.decided_at is not None and v.status in (
            "fail", "inconclusive") else ""
        print(f"  {v.requirement}: {v.status.replace('_', ' ')}{at} ({v.reason})",
              file=sys.stderr)
    print(f"  verdict: {verdict.upper()}; total utility {summary.total_utility:g}; events in "
          f"{out_dir / EVENTS}", file=sys.stderr)
    return EXIT_OK if verdict == "pass" else EXIT_FAILED
