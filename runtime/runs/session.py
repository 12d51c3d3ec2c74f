"""One run as a session: generate, run, monitor and write a mission's outputs into a folder
(``run_into``, the library's way to run a mission), and the supervised child's work
(``execute_request``), with the checks of a run's options and the rules of its output folder.

What `rei run` prints and parses is the command line's (rei.runtime.commands.run); the run's
page is the presentation wing's, handed in by the caller. This module must never import the
command line or the presentation wing.
"""

from __future__ import annotations

import hashlib
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_ERROR
from rei.lang.mission.faults import FaultDefinition, parse_fault_option
from rei.lang.vepl_parameters import ParameterValues, parameter_text
from rei.runtime.errors import RunError
from rei.runtime.results import RunSummary, judge
from rei.runtime.runs.supervisor import INTERNAL_ERROR_LOG

if TYPE_CHECKING:
    from rei.runtime.messages.sink import SampleSink
    from rei.runtime.observation.evaluator.signal_log import SignalRow
    from rei.runtime.runs.supervisor import RunRequest
    from rei.runtime.simulation.assembly import LoopRecord, RunConfig, RunProbe

# The simulator, the monitor and the generators are imported where they are used: `rei run`
# itself only supervises the process that runs them (rei.runtime.runs.supervisor), and pays
# for those imports once, in that process.

PAGE = "report.html"
TRACE = "trace.jsonl"
SUMMARY = "summary.json"
LOG = "run.log"
EVENTS = "events.csv"
RECORDING = "recording.mcap"
"""Written with --record (rei.runtime.observation.recordings.RECORDING)."""


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


def make_folder(out_dir: Path) -> None:
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


def set_aside(out: Path) -> list[Path]:
    """Rename an earlier run's outputs in ``out`` to NAME.earlier; the renamed files."""
    moved = []
    for name in EARLIER_OUTPUTS:
        path = out / name
        if path.exists():
            aside = path.with_name(path.name + ASIDE)
            path.replace(aside)
            moved.append(aside)
    return moved


def settle_earlier(moved: Sequence[Path], restore: bool) -> None:
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
             ) -> tuple[RunSummary, LoopRecord]:
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
    from rei.runtime.artifacts.monitor_config import load_monitor_config  # noqa: PLC0415
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
    make_folder(out_dir)
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


def execute_request(request: RunRequest, probe: RunProbe,
                    draw_page: Callable[[Path, str], Path | None] | None = None
                    ) -> tuple[int, dict[str, Any]]:
    """The supervised child's work: run ``request``, then ``draw_page(folder, policy)`` when
    the run was monitored (the run's page belongs to the presentation wing, above this one:
    `rei run` passes it in); (exit status, the loop's wall and CPU seconds and the page's path
    for the supervisor)."""
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
    page = (draw_page(Path(request.output), request.page)
            if request.monitor and draw_page is not None else None)
    written = (Path(request.output) / SUMMARY).read_bytes()
    return exit_code(summary, request.monitor), {
        "wall": record.wall_seconds, "cpu": record.cpu_seconds,
        "page": str(page) if page is not None else None,
        # The supervisor accepts summary.json only as written here (see supervise).
        "summary_sha256": hashlib.sha256(written).hexdigest()}


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


def read_summary(out: Path) -> RunSummary | None:
    import json  # noqa: PLC0415

    try:
        return RunSummary.from_json(json.loads((out / SUMMARY).read_text(encoding="utf-8")))
    except (OSError, ValueError, TypeError, KeyError):
        return None


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
