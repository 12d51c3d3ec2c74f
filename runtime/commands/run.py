"""`rei run MISSION -o DIR`: generate the world, run the mission headless, monitor and evaluate it.

Writes into DIR: ``world/`` (the generated `pybullet` and `monitor` targets the run loads),
``automata/`` (the RxPY automata generated from the .vepl), ``trace.jsonl`` (the sample
stream), ``events.csv`` (one row per signal), ``summary.json`` (a RunSummary with verdicts),
``report.html`` (the run's page: verdicts, timeline, distances, speed, map; not with
--no-monitor), ``run.log`` (the mission events and the outcome) and, with --record,
``recording.mcap`` (MCAP with ROS 2 types and the exact trace, docs/recording.md). Every
output is a function of the inputs, the seed and the REI version only: wall-clock time goes to the
terminal, never into DIR. The simulation runs in a child process under
``rei.runtime.runs.supervisor`` (``run`` here validates the options, starts it and prints);
``run_into`` is the same work in the caller's process, for the library and tests. Results
(the outcome line, the requirements, the page, the final verdict line) go to stdout,
progress and diagnostics to stderr; --quiet leaves the final verdict line alone. Exit status:
0 every requirement passed (without the monitor: the run did not break), 1 one failed or was
inconclusive, 2 invalid input, 3 a run error (the controller broke the contract or the
simulation's process died or hung), 130 interrupted (the outputs are then marked incomplete).
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, TextIO

from rei.lang.cli_support import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_RUN_ERROR,
)
from rei.lang.errors import printable_lines
from rei.lang.mission.faults import (
    FAULT_OPTION_HELP,
    FaultDefinition,
    fault_argument,
    parse_fault_option,
)
from rei.lang.source import unreadable
from rei.lang.vepl_parameters import (
    ParameterValues,
    add_functions_option,
    add_parameter_option,
    parameter_text,
    parameter_values,
)
from rei.runtime.errors import RunError
from rei.runtime.results import PAGE_POLICIES, RunSummary, judge
from rei.runtime.runs.config import apply_run_config, defer_defaults
from rei.runtime.runs.supervisor import INTERNAL_ERROR_LOG

if TYPE_CHECKING:
    from rei.runtime.messages.sink import SampleSink
    from rei.runtime.observation.evaluator.signal_log import SignalRow
    from rei.runtime.runs.supervisor import RunRequest
    from rei.runtime.simulation.assembly import RunConfig, RunProbe, RunRecord

# The simulator, the monitor and the generators are imported where they are used: `rei run`
# itself only supervises the process that runs them (rei.runtime.runs.supervisor), and pays for
# those imports once, in that process.

PAGE = "report.html"
TRACE = "trace.jsonl"
SUMMARY = "summary.json"
LOG = "run.log"
EVENTS = "events.csv"
RECORDING = "recording.mcap"
"""Written with --record (rei.runtime.observation.recordings.RECORDING)."""


CONTROLLER_HELP = (
    "robot under test: reference (REI's navigator), teleop:SCRIPT (a scripted drive; "
    "SCRIPT is forward_backward, straight ahead and back, which plain teleop also "
    "means, or circle, circles one way then the other), module:Class of your own "
    "navigator, or ros2:KEY=VALUE,... a ROS 2 stack (Nav2) on rmw_zenoh over a Zenoh "
    "router, e.g. ros2:router=tcp/127.0.0.1:7447,distro=jazzy (docs/ros2.md)")
"""Kept true to rei.runtime.robot.teleop.SCRIPTS by tests/test_help.py (importing the
robot package for every `rei` command line would cost 0.2 s)."""
QUIET_HELP = "no progress; print only the final verdict line (on stdout)"
RUN_VERBOSE_HELP = ("more detail: every requirement with its reason, passed ones too, and the "
                    "mission's events as they happen (on stderr)")
REPLAY_VERBOSE_HELP = "more detail: every requirement with its reason, passed ones too"
CAMPAIGN_VERBOSE_HELP = ("more detail: each failed run with the command that reruns it "
                         "(on stderr)")


def add_verbosity(parser: argparse.ArgumentParser, verbose_help: str = RUN_VERBOSE_HELP,
                  quiet_help: str = QUIET_HELP) -> None:
    """-q/--quiet and -v/--verbose for rei run, replay, campaign and demo: results on stdout,
    progress and diagnostics on stderr; each command says what -v adds for it."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-q", "--quiet", action="store_true", help=quiet_help)
    group.add_argument("-v", "--verbose", action="store_true", help=verbose_help)


HELP_EXAMPLES = """\
rei run examples/simple_wall/simple_wall.mission -o out/wall        # REI's navigator
rei run examples/simple_wall/simple_wall.mission -o out/teleop --controller teleop:circle
rei run examples/navigation/navigation.mission -o out/nav --seed 3 \\
    --vepl examples/navigation/human_safety.vepl                        # your requirements
rei run examples/navigation/navigation.mission -o out/mine --controller my_nav:Navigator
rei run examples/navigation/navigation.mission -o out/rec --record -q  # + recording.mcap
rei run examples/navigation/navigation.mission -o out/n07 --param react_zone=0.7  # your field
rei run examples/simple_wall/simple_wall.mission -o out/quick --page failed  # plots if failed
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "run", help="run a mission in the simulator, monitor it and record what happened",
        description="Check and generate what the mission needs, run it headless in pybullet "
                    "with the robot under test, monitor it with the event automata of a .vepl "
                    "specification, and write trace.jsonl, events.csv, summary.json (with the "
                    "requirement verdicts), report.html (the run's page) and run.log into the "
                    "output folder. Same inputs and seed give byte-identical outputs. The "
                    "simulation runs in a supervised child process: a controller that kills "
                    "it, ends it or hangs it ends the run as an error, with a summary saying "
                    "so. Results go to stdout, progress and diagnostics to stderr. Exit "
                    "status: 0 every requirement passed, 1 one failed or was inconclusive "
                    "(or the .vepl declares no requirement: verdict UNJUDGED, never a pass), "
                    "2 invalid input, 3 a run error, 130 interrupted. With REI_CACHE_DIR=DIR "
                    "the generated world and automata are reused from DIR while the files "
                    "they were made from are unchanged (rei campaign does this for its runs; "
                    "docs/campaign.md).")
    parser.add_argument("mission", type=Path, nargs="?", default=None, metavar="MISSION",
                        help="the .mission file (optional with --config)")
    parser.add_argument("-o", "--output", type=Path, default=None, metavar="DIR",
                        help="output folder (created if missing; required without --config)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    parser.add_argument("--controller", default="reference", metavar="NAME",
                        help=CONTROLLER_HELP + " (default reference)")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="stop after S simulated seconds (default: the mission's time limit)")
    parser.add_argument("--watchdog", type=float, default=5.0, metavar="S",
                        help="wall-clock seconds a controller call may take (default 5); a "
                             "simulation that reports no progress for S + max(S, 5) seconds "
                             "(a hang the call's watchdog cannot see, e.g. native code holding "
                             "the interpreter) is killed")
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
                             "utilities and requirements (default: REI's default.vepl); its "
                             "queries may read only the data the mission collects (its "
                             "monitor block), else exit 2")
    add_parameter_option(parser)
    add_functions_option(parser)
    parser.add_argument("--no-monitor", action="store_true",
                        help="record the trace only (monitor it later with `rei replay`)")
    parser.add_argument("--page", choices=PAGE_POLICIES, default="all",
                        help="report.html: 'all' (default) the full page with plots and map; "
                             "'failed' the full page only if the run did not pass, a brief "
                             "one (verdicts, no plots) if it did: `rei page DIR` draws the "
                             "full one later; 'none' no page (a campaign's --pages none, "
                             "docs/campaign.md)")
    parser.add_argument("--record", action="store_true",
                        help="also write recording.mcap: the run as an MCAP file with ROS 2 "
                             "messages (/scan, /odom, /cmd_vel, /tf, /world/markers, "
                             "/rei/events, /rei/signals) that Foxglove and `ros2 bag` open, "
                             "plus the exact trace (/rei/trace) `rei replay` reads; see "
                             "docs/recording.md")
    parser.add_argument("--fault", action="append", default=None, metavar="ENTRY",
                        type=fault_argument, help=FAULT_OPTION_HELP + "; added to the "
                        "mission's own fault section")
    bus = parser.add_argument_group(
        "distributed run (docs/bus.md)",
        "With --bus the robot under test is the controller `rei robot` runs on the bus (not "
        "--controller), called in lock-step: the simulation waits for each command at most "
        "--watchdog seconds, and a robot gone silent ends the run as an error (exit 3). The "
        "trace is published on the bus for `rei monitor` as it is written.")
    bus.add_argument("--bus", default=None, metavar="URL",
                     help="the endpoint `rei bus` printed (tcp/HOST:PORT)")
    bus.add_argument("--credentials", type=Path, default=None, metavar="DIR",
                     help="the bus's credentials folder (default: $REI_BUS_CREDENTIALS)")
    bus.add_argument("--bus-wait", type=float, default=30.0, metavar="S",
                     help="wall seconds to wait for the robot (and with --wait-for-monitor, "
                          "a monitor) to join before the run begins (default 30)")
    bus.add_argument("--wait-for-monitor", action="store_true",
                     help="begin only when a monitor (`rei monitor`) reads the trace, so it "
                          "sees every sample")
    add_verbosity(parser)
    defer_defaults(parser)
    parser.set_defaults(func=run)


def _finite(name: str, value: float | None) -> None:
    if value is not None and not math.isfinite(value):
        raise RunError(f"{name}: expected a finite number, found {value}")


MAX_PHYSICS_RATE = 10_000.0
"""Physics steps per simulated second: beyond it a run takes hours per simulated second."""
MAX_WATCHDOG = 86_400.0
"""Wall-clock seconds a controller call may take, at most (the supervisor adds its margin)."""
MAX_SEED = 2**64 - 1
"""The largest seed: numpy's generators take whole numbers from 0; the trace records it."""


def check_options(mission_path: Path, duration: float | None, watchdog: float | None,
                  physics_rate: float, odom_drift: float, laser_noise: float | None,
                  seed: int = 0) -> None:
    """RunError for an option out of range, before anything is generated or started."""
    if physics_rate > MAX_PHYSICS_RATE:
        raise RunError(f"--physics-rate: expected at most {MAX_PHYSICS_RATE:g} steps per "
                       f"simulated second, found {physics_rate:g}")
    if watchdog is not None and watchdog > MAX_WATCHDOG:
        raise RunError(f"--watchdog: expected at most {MAX_WATCHDOG:g} s (a day), found "
                       f"{watchdog:g}")
    if not 0 <= seed <= MAX_SEED:
        raise RunError(f"--seed: expected a whole number from 0 to 2**64-1, found {seed}")
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


def _make_folder(out_dir: Path) -> None:
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunError(f"cannot create the output folder '{out_dir}': {exc.strerror}") from None


RUN_OUTPUTS = (SUMMARY, TRACE, EVENTS, PAGE, RECORDING)
"""What the running process writes into its folder besides run.log, world/ and automata/
(which generation replaces only once the inputs are checked)."""
EARLIER_OUTPUTS = (*RUN_OUTPUTS, TRACE + ".partial", INTERNAL_ERROR_LOG)
"""Everything of an earlier run `rei run` sets aside: the outputs, and what a run that died
leaves (its unfinished trace, ``TraceWriter.partial``; the supervisor's report of an
internal error)."""
ASIDE = ".earlier"


def _set_aside(out: Path) -> list[Path]:
    """Rename an earlier run's outputs in ``out`` to NAME.earlier; the renamed files."""
    moved = []
    for name in EARLIER_OUTPUTS:
        path = out / name
        if path.exists():
            aside = path.with_name(path.name + ASIDE)
            path.replace(aside)
            moved.append(aside)
    return moved


def _settle_earlier(moved: Sequence[Path], restore: bool) -> None:
    """Put the set-aside outputs back (``restore``: the new run wrote nothing) or drop them."""
    for aside in moved:
        original = aside.with_name(aside.name[:-len(ASIDE)])
        if restore and not original.exists():
            aside.replace(original)
        else:
            aside.unlink(missing_ok=True)


def run_into(mission_path: Path, out_dir: Path, controller: str = "reference", seed: int = 0,
             duration: float | None = None, watchdog: float | None = 5.0,
             physics_rate: float = 100.0, odom_drift: float = 0.0,
             sinks: Sequence[SampleSink] = (), progress: IO[str] | None = None,
             vepl: Path | None = None, monitor: bool = True, laser_noise: float | None = None,
             variation: bool = True, probe: RunProbe | None = None,
             echo: IO[str] | None = None, functions: str | None = None,
             recording: bool = False, faults: Sequence[FaultDefinition] = (),
             bus: str | None = None, bus_credentials: Path | None = None,
             bus_wait: float = 30.0, wait_monitor: bool = False,
             parameters: ParameterValues = ()
             ) -> tuple[RunSummary, RunRecord]:
    """Everything `rei run` does, in this process: generate, run, monitor with the .vepl's
    automata (the default specification unless ``vepl``; none when ``monitor`` is False),
    write outputs. Extra ``sinks`` see the same stream as the trace and the monitor; ``probe``
    hears the loop's progress; ``echo`` gets run.log's lines as they are written; ``recording``
    also writes recording.mcap (``rei.runtime.observation.recordings``), with the monitor's signals.
    With ``bus`` (an endpoint of `rei bus`) the robot under test is the one answering on the
    bus (`rei robot`, awaited at most ``bus_wait`` seconds, like a monitor with
    ``wait_monitor``) and the trace is published there as it is written
    (``rei.runtime.bus.distributed_run``; closing the robot leaves the bus). ``parameters``
    (`--param`)
    replace the specification's values; those other than the file's are in the summary.

    The controller runs in this process: a controller that ends or stalls the process ends
    the caller too. `rei run` supervises it instead (``rei.runtime.runs.supervisor.supervise``).
    """
    from rei.generators.output import open_output  # noqa: PLC0415
    from rei.lang.vepl.document import changed_parameters, load_vepl  # noqa: PLC0415
    from rei.runtime.artifacts.monitor import load_monitor_config  # noqa: PLC0415
    from rei.runtime.artifacts.world import load_manifest  # noqa: PLC0415
    from rei.runtime.observation.evaluator import merge_summary, write_summary  # noqa: PLC0415
    from rei.runtime.observation.monitor import MonitorSink, generate_automata  # noqa: PLC0415
    from rei.runtime.observation.monitor.functions import load_functions  # noqa: PLC0415
    from rei.runtime.observation.monitor.needs import check_needs  # noqa: PLC0415
    from rei.runtime.robot import make_controller  # noqa: PLC0415
    from rei.runtime.runs.cache import ArtifactCache  # noqa: PLC0415
    from rei.runtime.simulation.assembly import (  # noqa: PLC0415
        RunConfig,
        generate_world,
        run_mission,
        summary_of,
    )
    from rei.runtime.simulation.faults.composition import fault_stage  # noqa: PLC0415
    from rei.runtime.simulation.faults.configuration import run_faults  # noqa: PLC0415
    from rei.runtime.simulation.world.start_jitter import START_JITTER  # noqa: PLC0415
    from rei.runtime.trace import TraceWriter  # noqa: PLC0415

    check_options(mission_path, duration, watchdog, physics_rate, odom_drift, laser_noise, seed)
    _make_folder(out_dir)
    # The specification is checked and generated first: a bad .vepl is reported (exit 2)
    # before any world is built.
    # With $REI_CACHE_DIR (rei campaign sets it) generation is reused from earlier runs of the
    # same files (rei.runtime.runs.cache): the same bytes, without parsing or rendering again.
    cache = ArtifactCache.from_environment()
    automata = None
    if monitor:
        automata = (cache.automata(vepl, out_dir / "automata", parameters) if cache is not None
                    else generate_automata(vepl, out_dir / "automata", replace=True,
                                           parameters=parameters))
    user = load_functions(functions, vepl) if monitor else {}
    monitor_sink = MonitorSink(vepl, out_dir, functions=user, automata=automata,
                               parameters=parameters) if monitor else None
    world_dir = out_dir / "world"
    mission = (cache.world(mission_path, world_dir) if cache is not None
               else generate_world(mission_path, world_dir, replace=True))
    if probe is not None:
        probe.begin(mission.name, mission.world.name)
    manifest = load_manifest(world_dir)
    monitor_config = load_monitor_config(world_dir)
    specification = load_vepl(vepl, parameters) if monitor else None
    # checked with --no-monitor too (a name the .vepl lacks is bad input); recorded only
    # beside the verdicts they were judged with
    changed = changed_parameters(vepl, parameters)
    if not monitor:
        changed = ()
    if specification is not None:
        # Never judge on data the collector will not forward (a false PASS): refuse first.
        check_needs(specification, monitor_config.data, f"the mission '{mission.name}' to "
                    f"collect", "name that data in the mission's monitor block, or drop the query")
    config = RunConfig(seed=seed, physics_rate=physics_rate, duration=duration,
                       watchdog=watchdog, odom_drift=odom_drift, laser_noise=laser_noise,
                       jitter=START_JITTER if variation else None, vary=variation)
    injected = run_faults(mission.faults, faults,
                          None if specification is None
                          else tuple(s.name for s in specification.signals),
                          str(mission_path), str(vepl) if vepl is not None else "default.vepl",
                          mission.time_limit if duration is None
                          else min(duration, mission.time_limit),
                          _fault_periods(config, monitor_config.rate, manifest.laser.rate),
                          (-manifest.laser.fov / 2, manifest.laser.fov / manifest.laser.beams,
                           manifest.laser.beams))
    bus_sinks: list[SampleSink] = []
    if bus is None:
        robot: Any = make_controller(controller)
    else:
        from rei.runtime.bus.distributed_run import open_run_bus  # noqa: PLC0415

        robot = open_run_bus(bus, bus_credentials, watchdog, bus_wait, wait_monitor, world_dir)
        controller = f"bus:{robot.name}"
    for stale in RUN_OUTPUTS:
        (out_dir / stale).unlink(missing_ok=True)
    trace_writer = TraceWriter(out_dir / TRACE)
    if bus is not None:  # right after the trace writer: it publishes the line just written
        bus_sinks.append(robot.publisher(trace_writer))
    recorder: list[SampleSink] = []
    if recording:
        from rei.runtime.observation.recordings import McapRecorder  # noqa: PLC0415

        def fired() -> Sequence[SignalRow]:
            host = monitor_sink.host if monitor_sink is not None else None
            return host.log.rows if host is not None else ()

        # after the trace writer (its lines are carried as written) and the monitor (a
        # sample's signals have fired when the recorder sees it)
        recorder.append(McapRecorder(out_dir / RECORDING, fired, trace=trace_writer))

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
            if echo is not None:
                echo.write(("\n" if progress is not None else "") + line + "\n")
                echo.flush()

        log(f"mission {mission.name} in room {mission.world.name}, controller {controller}, "
            f"seed {seed}")
        if changed:
            log(f"specification parameters set by --param: {parameter_text(changed)}")
        for fault in injected:
            log(f"fault {fault.name}: {fault.text()}")
        record = run_mission(mission, manifest, monitor_config, robot,
                             [trace_writer, *bus_sinks,
                              *([monitor_sink] if monitor_sink is not None else []), *recorder,
                              *sinks],
                             config,
                             progress=show if progress is not None else None, log=log,
                             probe=probe, faults=fault_stage(injected, seed))
    if progress is not None:
        progress.write("\n")
    summary = summary_of(record, mission, controller, seed)
    if monitor_sink is not None and monitor_sink.result is not None:
        summary = merge_summary(summary, monitor_sink.result)
    summary = replace(summary, parameters=dict(changed))
    write_summary(summary, out_dir)
    return summary, record


def execute_request(request: RunRequest, probe: RunProbe) -> tuple[int, dict[str, Any]]:
    """The supervised child's work: run ``request``, write the page; (exit status, the
    loop's wall and CPU seconds and the page's path for the supervisor)."""
    summary, record = run_into(
        Path(request.mission), Path(request.output), request.controller, request.seed,
        request.duration, request.watchdog, request.physics_rate, request.odom_drift,
        progress=sys.stderr if request.progress else None,
        vepl=Path(request.vepl) if request.vepl is not None else None,
        monitor=request.monitor, laser_noise=request.laser_noise,
        variation=request.variation, probe=probe,
        echo=sys.stderr if request.echo_events else None, functions=request.functions,
        recording=request.record,
        faults=tuple(parse_fault_option(text) for text in request.faults),
        bus=request.bus, bus_credentials=Path(request.bus_credentials)
        if request.bus_credentials is not None else None, bus_wait=request.bus_wait,
        wait_monitor=request.wait_monitor, parameters=request.parameters)
    page = write_page(Path(request.output), policy=request.page) if request.monitor else None
    written = (Path(request.output) / SUMMARY).read_bytes()
    return exit_code(summary, request.monitor), {
        "wall": record.wall_seconds, "cpu": record.cpu_seconds,
        "page": str(page) if page is not None else None,
        # The supervisor accepts summary.json only as written here (see supervise).
        "summary_sha256": hashlib.sha256(written).hexdigest()}


def run(args: argparse.Namespace) -> int:
    from rei.runtime.runs.supervisor import RunRequest, supervise  # noqa: PLC0415

    args = apply_run_config(args)
    out: Path = args.output
    check_options(args.mission, args.duration, args.watchdog, args.physics_rate,
                  args.odom_drift, args.laser_noise, args.seed)
    if args.bus is not None:
        from rei.runtime.bus.client import parse_endpoint  # noqa: PLC0415

        parse_endpoint(args.bus)
        if not (math.isfinite(args.bus_wait) and args.bus_wait > 0):
            raise RunError(f"--bus-wait: expected a positive number of seconds, found "
                           f"{args.bus_wait}")
    problem = unreadable(args.mission)  # before an output folder is made for nothing
    if problem is not None:
        raise RunError(str(problem))
    parameters = parameter_values(args.param)
    if parameters:  # every name declared, every rule kept: before the outputs are touched
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, parameters)
    _make_folder(out)
    # Outputs of an earlier run into the same folder are set aside now (a run that dies must
    # not leave them beside its own error summary) and come back if the child refuses the
    # inputs (exit 2): bad input never costs what was already written.
    earlier = _set_aside(out)
    request = RunRequest(
        # absolute: the process under test may change its working folder
        str(args.mission), os.path.abspath(out), args.controller, args.seed, args.duration,
        args.watchdog, args.physics_rate, args.odom_drift, args.laser_noise,
        str(args.vepl) if args.vepl is not None else None, not args.no_monitor,
        not args.no_variation, progress=not args.quiet and sys.stderr.isatty(),
        echo_events=args.verbose, functions=args.functions, record=args.record,
        faults=tuple(f.text() for f in args.fault or ()), bus=args.bus,
        bus_credentials=os.path.abspath(args.credentials) if args.credentials else None,
        bus_wait=args.bus_wait, wait_monitor=args.wait_for_monitor, parameters=parameters,
        page=args.page)
    try:
        ended = supervise(request)
    except BaseException:
        _settle_earlier(earlier, restore=True)
        raise
    _settle_earlier(earlier, restore=ended.status == EXIT_BAD_INPUT)
    summary = _read_summary(out) if ended.status != EXIT_BAD_INPUT else None
    if summary is None:
        # bad input (the child said why on stderr), or interrupted before anything was run
        if ended.status == EXIT_INTERRUPTED:
            print(f"verdict: INTERRUPTED (before the run started); outputs in {out}")
        return ended.status
    if not args.quiet and ended.wall_seconds > 0:
        rtf = summary.duration / ended.wall_seconds
        cpu_rtf = summary.duration / ended.cpu_seconds if ended.cpu_seconds > 0 else math.inf
        print(f"  {rtf:.0f}x real time ({cpu_rtf:.0f}x per CPU second)", file=sys.stderr)
    return print_results(summary, out, monitored=not args.no_monitor,
                         page=out / Path(ended.page).name if ended.page else None,
                         quiet=args.quiet,
                         verbose=args.verbose)


def _read_summary(out: Path) -> RunSummary | None:
    import json  # noqa: PLC0415

    try:
        return RunSummary.from_json(json.loads((out / SUMMARY).read_text(encoding="utf-8")))
    except (OSError, ValueError, TypeError, KeyError):
        return None


def write_page(out_dir: Path, trace: Path | None = None, policy: str = "all") -> Path | None:
    """Write the run's report.html as ``policy`` asks (``--page``); a page that cannot be
    written is reported (on stderr), never allowed to change the run's verdict or exit
    status."""
    from rei.lang.errors import ReiError  # noqa: PLC0415
    from rei.runtime.presentation.run_page.page import write_run_page  # noqa: PLC0415

    try:
        return write_run_page(out_dir, trace, policy=policy)
    except (ReiError, OSError) as exc:
        print(f"  report.html not written: {exc}", file=sys.stderr)
        return None


def exit_code(summary: RunSummary, monitored: bool = True) -> int:
    """The exit status of the one pass rule (rei.runtime.results.judge): 0 pass (or, without
    the monitor, unjudged), 1 fail or inconclusive, 3 run error, 130 interrupted."""
    verdict = judge(summary)
    if verdict == "error":
        return EXIT_RUN_ERROR
    if verdict == "interrupted":
        return EXIT_INTERRUPTED
    if not monitored or verdict == "pass":
        return EXIT_OK
    return EXIT_FAILED


def verdict_lines(summary: RunSummary, verbose: bool) -> list[str]:
    """One line per requirement that kept the run from passing (every requirement, with its
    reason, when ``verbose``), then how many passed or did not apply when not all shown."""
    lines = []
    hidden: dict[str, int] = {}
    for v in summary.verdicts:
        if not verbose and v.status in ("pass", "not_applicable"):
            hidden[v.status] = hidden.get(v.status, 0) + 1
            continue
        at = f" at t={v.decided_at:g} s" if v.decided_at is not None and v.status in (
            "fail", "inconclusive") else ""
        lines.append(f"  {v.requirement}: {v.status.replace('_', ' ')}{at} ({v.reason})")
    if hidden:
        words = {"pass": "passed", "not_applicable": "not applicable"}
        lines.append("  " + ", ".join(f"{hidden[s]} {words[s]}" for s in words if s in hidden))
    return lines


def final_line(summary: RunSummary, out_dir: Path, monitored: bool = True) -> str:
    """The last line on stdout: the run's one verdict, and where the outputs are."""
    verdict = judge(summary)
    if verdict in ("error", "interrupted"):
        return f"verdict: {verdict.upper()} ({summary.reason}); outputs in {out_dir}"
    if not monitored:
        return (f"verdict: NOT JUDGED (--no-monitor: judge the trace with `rei replay`); "
                f"outputs in {out_dir}")
    if verdict == "unjudged":  # monitored, yet no requirement: nothing could pass
        return (f"verdict: UNJUDGED (the .vepl declares no requirement, so the run cannot "
                f"pass: add a `requirement` to it, or leave out --vepl for REI's default "
                f"ones); total utility {summary.total_utility:g}; outputs in {out_dir}")
    return (f"verdict: {verdict.upper()}; total utility {summary.total_utility:g}; outputs "
            f"in {out_dir}")


def print_results(summary: RunSummary, out_dir: Path, *, monitored: bool = True,
                  page: Path | None = None, quiet: bool = False, verbose: bool = False,
                  stream: TextIO | None = None) -> int:
    """Print the run's results on stdout and return its exit status (``exit_code``):
    the outcome, the requirements (``verdict_lines``), the page and the final verdict line;
    with ``quiet`` the final line alone."""
    target = stream if stream is not None else sys.stdout

    def say(line: str) -> None:
        # names and reasons come from the run (or a recording): shown, never interpreted
        print(printable_lines(line), file=target)

    if not quiet:
        m = summary.measurements
        if "tasks_succeeded" in m:
            say(f"{summary.mission}: {summary.outcome} ({summary.reason}) after "
                f"{summary.duration:.1f} s simulated, {m['tasks_succeeded']} task(s) "
                f"succeeded, {m['tasks_failed']} failed, {m['collisions']} collision(s)")
        else:
            say(f"{summary.mission}: {summary.outcome} ({summary.reason})")
        for line in verdict_lines(summary, verbose):
            say(line)
        if page is not None:
            say(f"  run page: {page}")
    say(final_line(summary, out_dir, monitored))
    return exit_code(summary, monitored)


def _fault_periods(config: RunConfig, sample_rate: float, scan_rate: float
                   ) -> tuple[float, float, float]:
    """(shortest time from a sample to the next control tick after it, control tick, scan
    period) in seconds, as ``run_faults`` checks fault windows against them. Samples and
    ticks fall on physics steps: from a sample the next tick is gcd(steps per sample, steps
    per tick) steps away at the least (a whole tick when every sample is on a tick)."""
    from rei.runtime.simulation.loop.scheduler import every  # noqa: PLC0415

    steps = config.physics_rate
    # the scheduler's own step counts (and its check that each rate divides the physics rate)
    tick = every(steps, config.control_rate, "the control rate")
    sample = every(steps, sample_rate, "the monitor's sample rate")
    gap = tick if sample % tick == 0 else math.gcd(tick, sample)
    return gap / steps, tick / steps, 1.0 / scan_rate
