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
``rei.runtime.runs.run_into`` is the same work in the caller's process, for the library and
tests; the child's work is ``child_work`` (the run, then its page). Results
(the outcome line, the requirements, the page, the final verdict line) go to stdout,
progress and diagnostics to stderr; --quiet leaves the final verdict line alone. Exit status:
0 every requirement passed (without the monitor: the run did not break), 1 one failed or was
inconclusive, 2 invalid input, 3 a run error (the controller broke the contract or the
simulation's process died or hung), 130 interrupted (the outputs are then marked incomplete).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from rei.lang.cli_support import (
    EXIT_BAD_INPUT,
    EXIT_INTERRUPTED,
)
from rei.lang.errors import printable_lines
from rei.lang.mission.faults import (
    FAULT_OPTION_HELP,
    fault_argument,
)
from rei.lang.source import unreadable
from rei.lang.vepl_parameters import (
    add_functions_option,
    add_parameter_option,
    parameter_values,
)
from rei.runtime.errors import RunError
from rei.runtime.results import PAGE_POLICIES, RunSummary, judge
from rei.runtime.runs.config import apply_run_config, defer_defaults
from rei.runtime.runs.session import (
    check_options,
    execute_request,
    exit_code,
    make_folder,
    read_summary,
    set_aside,
    settle_earlier,
)

if TYPE_CHECKING:
    from rei.runtime.runs.supervisor import RunRequest
    from rei.runtime.simulation.assembly import RunProbe

# The simulator, the monitor and the generators are imported where they are used: `rei run`
# itself only supervises the process that runs them (rei.runtime.runs.supervisor), and pays for
# those imports once, in that process.

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
    make_folder(out)
    # Outputs of an earlier run into the same folder are set aside now (a run that dies must
    # not leave them beside its own error summary) and come back if the child refuses the
    # inputs (exit 2): bad input never costs what was already written.
    earlier = set_aside(out)
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
        ended = supervise(request, child_work, CHILD)
    except BaseException:
        settle_earlier(earlier, restore=True)
        raise
    settle_earlier(earlier, restore=ended.status == EXIT_BAD_INPUT)
    summary = read_summary(out) if ended.status != EXIT_BAD_INPUT else None
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


CHILD = "rei.runtime.commands.run"
"""The module the supervised child runs as when it is executed rather than forked."""


def child_work(request: RunRequest, probe: RunProbe) -> tuple[int, dict[str, Any]]:
    """The supervised child's work: the run (``execute_request``), then its page."""
    return execute_request(request, probe,
                           lambda folder, policy: write_page(folder, policy=policy))


def write_page(out_dir: Path, trace: Path | None = None, policy: str = "all") -> Path | None:
    """Write the run's report.html as ``policy`` asks (``--page``); a page that cannot be
    written is reported (on stderr), never allowed to change the run's verdict or exit
    status."""
    from rei.lang.errors import ReiError  # noqa: PLC0415
    from rei.runtime.presentation.run_page.rendering import write_run_page  # noqa: PLC0415

    try:
        return write_run_page(out_dir, trace, policy=policy)
    except (ReiError, OSError) as exc:
        print(f"  report.html not written: {exc}", file=sys.stderr)
        return None


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


if __name__ == "__main__":  # `rei run`'s supervised child, executed (rei.runtime.runs.supervisor)
    from rei.runtime.runs.supervisor import child_main

    sys.exit(child_main(sys.argv[1:], child_work))
