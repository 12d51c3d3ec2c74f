"""`rei campaign MISSIONS... -o DIR`: run many missions, repeated, in parallel; resumable.

Writes the results store (results.parquet / results.csv, a folder per run), report.html and
junit.xml into DIR. Each mission gets a verdict against the required pass rate (--pass-rate,
judged on the Wilson interval of its rate; see docs/campaign.md). Exit status (one rule for
`rei campaign`, `rei demo` and `rei report`: rei.runtime.campaigns.stats.campaign_outcome) 0
when every mission passes, 1 when a mission fails, is flaky or is inconclusive, 2 for bad
input, 3 when any run errored (crashed, hung, a run error), 130 when interrupted — Ctrl-C or
SIGTERM of the campaign, the only way a run goes unrecorded (run the same command to resume).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from rei.lang.cli_support import EXIT_INTERRUPTED
from rei.lang.vepl_parameters import add_functions_option, add_parameter_option, parameter_values

if TYPE_CHECKING:
    from rei.runtime.campaigns.engines import CampaignEngine

EXIT_STATUS_HELP = ("Exit status: 0 every mission passes (--pass-rate), 1 a mission fails, is "
                    "flaky or is inconclusive (none failed, one could not be decided), 2 bad "
                    "input, 3 a run errored (crashed, hung, the controller raised), 130 "
                    "interrupted.")
"""The exit rule as `rei campaign`, `rei demo` and `rei report` state it in their --help."""


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, found {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1, found {value}")
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, found {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive finite number, found {text!r}")
    return value


def _rate(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a rate from 0 to 1, found {text!r}") \
            from None
    if not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise argparse.ArgumentTypeError(f"expected a rate from 0 to 1 (0.9 for 90 %), "
                                         f"found {text!r}")
    return value


HELP_EXAMPLES = """\
rei campaign examples/ -o out/campaign --repeat 3 --workers 2
rei campaign examples/navigation/navigation.mission -o out/nav5 --repeat 5 --pass-rate 0.8
rei campaign suite/index.csv -o out/suite --controller my_nav:Navigator -v
rei campaign examples/ -o out/campaign --repeat 3   # again: resumes, runs only what is missing
rei campaign examples/ -o out/slow07 --param react_zone=0.7   # a robot that slows nearer
rei campaign examples/ -o out/all-pages --pages all  # plots and map for passing runs too
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rei.runtime.commands.run import (  # noqa: PLC0415
        CAMPAIGN_VERBOSE_HELP,
        CONTROLLER_HELP,
        add_verbosity,
    )

    parser = sub.add_parser(
        "campaign",
        help="run many missions (repeated, in parallel, resumable) and report on them",
        description="Run every mission (.mission files, folders, or the index CSV of a suite "
                    "from `rei-gen rooms`) --repeat times with seeds derived from --seed, each "
                    "run in its own `rei run` process under a watchdog. Results go to DIR: "
                    "results.parquet/.csv, runs/RUN_ID/, report.html, junit.xml. Interrupted "
                    "(Ctrl-C, SIGTERM)? Run the same command again: only the missing runs run. "
                    "A run that dies any other way (kill -9, out of memory, a crash) is "
                    "recorded as crashed, and runs killed with the campaign die with it. "
                    + EXIT_STATUS_HELP)
    parser.add_argument("missions", nargs="+", type=Path, metavar="MISSIONS",
                        help=".mission files, folders with .mission files, or a suite index .csv")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="campaign folder (created; an existing one is resumed)")
    parser.add_argument("--repeat", type=positive_int, default=1, metavar="K",
                        help="runs per mission, each with its own derived seed (default 1)")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="campaign seed the run seeds derive from (default 0)")
    parser.add_argument("--controller", default=None, metavar="NAME",
                        help=CONTROLLER_HELP + "; passed to every `rei run` (default "
                             "reference)")
    parser.add_argument("--controller-version", default=None, metavar="TEXT",
                        help="version of the controller, for the provenance (default: the "
                             "version of its installed package and/or the git revision of "
                             "its module's source)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitor specification passed to `rei run`")
    add_parameter_option(parser, "passed to `rei run` and recorded in the plan (a resume "
                                 "with other values is refused, exit 2): ")
    add_functions_option(parser, "; passed to every `rei run`")
    parser.add_argument("--duration", type=_seconds, default=None, metavar="S",
                        help="simulated seconds per run, passed to `rei run` (smoke tests)")
    add_engine_arguments(parser)
    parser.add_argument("--pass-rate", type=_rate, default=1.0, metavar="P",
                        help="required pass rate of each mission, 0..1 (default 1: every run "
                             "must pass). A mission passes when the 95%% Wilson interval of its "
                             "rate lies at or above P, or straddles P with every run passed; "
                             "fails when it lies below P, or no run passed; is flaky when it "
                             "straddles P and runs disagree (repeat more). It can change "
                             "between sessions: it judges runs, it does not plan them")
    parser.add_argument("--pair-static", action="store_true",
                        help="pair every run with a run of the same seed in the same room "
                             "without humans and dynamic objects (written to DIR/static/), so "
                             "the report tells failures caused by people from failures the "
                             "room causes anyway; doubles the runs")
    parser.add_argument("--no-variation", action="store_true",
                        help="passed to `rei run`: no seeded start-pose jitter, every repeat "
                             "starts at the exact declared scene (only the laser noise differs)")
    parser.add_argument("--record", action="store_true",
                        help="passed to `rei run`: every run also writes recording.mcap (MCAP "
                             "with ROS 2 types and the exact trace; see docs/recording.md)")
    from rei.lang.mission.faults import FAULT_OPTION_HELP, fault_argument  # noqa: PLC0415

    parser.add_argument("--fault", action="append", default=None, metavar="ENTRY",
                        type=fault_argument, help="passed to `rei run`: " + FAULT_OPTION_HELP)
    parser.add_argument("--no-report", action="store_true",
                        help="skip report.html (tables and junit.xml are still written)")
    add_verbosity(parser, CAMPAIGN_VERBOSE_HELP)  # -q: the final verdict line alone
    parser.set_defaults(func=run)


def add_pages_argument(parser: argparse.ArgumentParser) -> None:
    """--pages of `rei campaign`, `rei search` and `rei demo`: which runs get their page."""
    from rei.runtime.results import PAGE_POLICIES  # noqa: PLC0415

    parser.add_argument("--pages", choices=PAGE_POLICIES, default="failed",
                        help="passed to `rei run --page`: 'failed' (default) draws the full "
                             "page (plots, map) of every run that did not pass and a brief "
                             "one (verdicts) for the others, which `rei page DIR` completes "
                             "later; 'all' full pages for every run; 'none' no run pages "
                             "(the campaign report still lists every run)")


def add_engine_arguments(parser: argparse.ArgumentParser) -> None:
    """--workers, --timeout, --engine, --scheduler and --pages: where and how the runs of
    `rei campaign` and `rei search` execute (``engine_of`` reads them)."""
    parser.add_argument("--workers", type=positive_int, default=None, metavar="N",
                        help="runs at once with the local engine (default: number of CPUs)")
    parser.add_argument("--timeout", type=_seconds, default=None, metavar="S",
                        help="wall-clock watchdog per run (default: 10 x --duration + 30 s, "
                             "at least 60 s; 30 min without --duration)")
    parser.add_argument("--engine", choices=("local", "dask"), default="local",
                        help="local worker processes (default) or a Dask distributed cluster")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="Dask scheduler address, e.g. tcp://10.0.0.5:8786 (--engine dask)")
    add_pages_argument(parser)


def engine_of(args: argparse.Namespace) -> CampaignEngine:
    """The campaign engine the options of ``add_engine_arguments`` ask for."""
    from rei.runtime.campaigns import CampaignError, DaskEngine, LocalEngine  # noqa: PLC0415

    if args.engine == "dask":
        if not args.scheduler:
            raise CampaignError("--engine dask: expected --scheduler ADDRESS "
                                "(start one with `dask scheduler`)")
        return DaskEngine(args.scheduler, timeout=args.timeout, pages=args.pages)
    if args.scheduler:
        raise CampaignError("--scheduler is only used with --engine dask")
    return LocalEngine(args.workers or os.cpu_count() or 1, timeout=args.timeout,
                       pages=args.pages)


def _faults(args: argparse.Namespace) -> tuple[str, ...]:
    """The --fault entries as written for every run, checked before any run starts: a
    signal the specification does not define would fail every run alike."""
    from rei.lang.vepl.document import load_vepl  # noqa: PLC0415
    from rei.runtime.simulation.faults.configuration import run_faults  # noqa: PLC0415

    faults = tuple(args.fault or ())
    if any(f.activation.signal or f.activation.stop for f in faults):
        signals = tuple(s.name for s in load_vepl(args.vepl).signals)
        run_faults((), faults, signals, "", str(args.vepl or "default.vepl"))
    else:
        run_faults((), faults, (), "", "")
    return tuple(f.text() for f in faults)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.campaigns import plan_campaign, run_campaign  # noqa: PLC0415
    from rei.runtime.campaigns.plan import STATIC  # noqa: PLC0415
    from rei.runtime.campaigns.provenance import collect  # noqa: PLC0415

    plan = plan_campaign(list(args.missions), repeat=args.repeat, seed=args.seed,
                         controller=args.controller, vepl=args.vepl, duration=args.duration,
                         static_dir=args.output / STATIC if args.pair_static else None,
                         variation=not args.no_variation, functions=args.functions,
                         record=args.record, faults=_faults(args),
                         vepl_parameters=parameter_values(args.param))
    engine = engine_of(args)
    provenance = {**collect(["rei", *sys.argv[1:]] if sys.argv else [], engine.describe(),
                            args.controller, args.controller_version),
                  "pass_rate": args.pass_rate}
    twins = " + static twins" if args.pair_static else ""
    missions = len({s.mission_file for s in plan.runs if not s.static_pair})
    if not args.quiet:
        print(f"campaign: {len(plan.runs)} runs ({missions} missions x {plan.repeat}{twins}) "
              f"on {args.engine} engine -> {args.output}", file=sys.stderr)
    try:
        with _terminate_as_interrupt(), open(os.devnull, "w", encoding="utf-8") as silent:
            result = run_campaign(plan, args.output, engine, provenance,
                                  stream=silent if args.quiet else None)
    except KeyboardInterrupt:
        print(f"rei campaign: interrupted; the finished runs are kept in {args.output}. Run "
              f"the same command again to finish the missing ones.", file=sys.stderr)
        return EXIT_INTERRUPTED
    return finish(args.output, no_report=args.no_report, complete=result.complete,
                  pass_rate=args.pass_rate, quiet=args.quiet, verbose=args.verbose)


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM (a cancelled CI job, `kill`) stops the campaign as Ctrl-C does: its runs are
    stopped, the finished ones kept and the tables written, instead of dying mid-write."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers belong to the main thread (a campaign run from a library)
        return

    def interrupt(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def finish(root: Path, *, no_report: bool = False, complete: bool = True,
           pass_rate: float | None = None, quiet: bool = False, verbose: bool = False) -> int:
    """Write junit.xml and the report of a campaign folder; the exit status of the campaign
    (``campaign_outcome``) on its mission verdicts against ``pass_rate`` (None: the rate the
    campaign's last session required). ``complete`` False: the session was interrupted."""
    from rei.runtime.campaigns import CampaignStore  # noqa: PLC0415
    from rei.runtime.campaigns.stats import campaign_outcome, classify_pairs, mission_verdicts
    from rei.runtime.campaigns.store import required_pass_rate  # noqa: PLC0415
    from rei.runtime.presentation.campaign_report import build_report  # noqa: PLC0415

    outcome = build_report(root, html=not no_report)
    if not quiet:
        print(outcome.describe(), file=sys.stderr)
    plan, manifest, records = CampaignStore.read(root)
    required = required_pass_rate(manifest) if pass_rate is None else pass_rate
    verdicts = mission_verdicts(records, required)
    causes = {p.mission: p.cause for p in classify_pairs(records)}
    for verdict in verdicts:
        cause = causes.get(verdict.mission)
        if not quiet:
            print(f"  {verdict.verdict.upper():5}  {verdict.mission}: {verdict.reason}"
                  + (f"; {cause}" if cause and cause != "passes" else ""), file=sys.stderr)
    if verbose:
        from rei.runtime.presentation.campaign_report.build import rerun_command  # noqa: PLC0415

        for record in outcome.failed:
            print(f"    {record.spec.run_id}: {record.verdict}; rerun: "
                  f"{rerun_command(record.spec)}", file=sys.stderr)
    status = campaign_outcome(records, verdicts, planned=len(plan.runs),
                              interrupted=not complete)
    where = f"; report: {outcome.html}" if outcome.html is not None else ""
    print(status.line() + where)
    return status.exit_code
