"""`rei campaign MISSIONS... -o DIR`: run many missions, repeated, in parallel; resumable.

Writes the results store (results.parquet / results.csv, a folder per run), report.html and
junit.xml into DIR. Exit status 0 when every run passed every requirement, 1 when any failed,
crashed or hung, 2 for bad input, 130 when interrupted (run the same command to resume).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK


def _positive_int(text: str) -> int:
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


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "campaign",
        help="run many missions (repeated, in parallel, resumable) and report on them",
        description="Run every mission (.mission files, folders, or the index CSV of a suite "
                    "from `rei-gen rooms`) --repeat times with seeds derived from --seed, each "
                    "run in its own `rei run` process under a watchdog. Results go to DIR: "
                    "results.parquet/.csv, runs/RUN_ID/, report.html, junit.xml. Interrupted? "
                    "Run the same command again: only the missing runs run.")
    parser.add_argument("missions", nargs="+", type=Path, metavar="MISSIONS",
                        help=".mission files, folders with .mission files, or a suite index .csv")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="campaign folder (created; an existing one is resumed)")
    parser.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                        help="runs at once with the local engine (default: number of CPUs)")
    parser.add_argument("--repeat", type=_positive_int, default=1, metavar="K",
                        help="runs per mission, each with its own derived seed (default 1)")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="campaign seed the run seeds derive from (default 0)")
    parser.add_argument("--controller", default=None, metavar="NAME",
                        help="controller passed to `rei run` (default: its default)")
    parser.add_argument("--controller-version", default=None, metavar="TEXT",
                        help="version of the controller, for the provenance (default: the "
                             "version of its installed package and/or the git revision of "
                             "its module's source)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitor specification passed to `rei run`")
    parser.add_argument("--duration", type=_seconds, default=None, metavar="S",
                        help="simulated seconds per run, passed to `rei run` (smoke tests)")
    parser.add_argument("--timeout", type=_seconds, default=None, metavar="S",
                        help="wall-clock watchdog per run (default: 10 x --duration + 30 s, "
                             "at least 60 s; 30 min without --duration)")
    parser.add_argument("--engine", choices=("local", "dask"), default="local",
                        help="local worker processes (default) or a Dask distributed cluster")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="Dask scheduler address, e.g. tcp://10.0.0.5:8786 (--engine dask)")
    parser.add_argument("--no-report", action="store_true",
                        help="skip report.html (tables and junit.xml are still written)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import os  # noqa: PLC0415

    from rei.runtime.campaign import (  # noqa: PLC0415
        CampaignError,
        DaskEngine,
        LocalEngine,
        plan_campaign,
        run_campaign,
    )
    from rei.runtime.campaign.engines import CampaignEngine  # noqa: PLC0415
    from rei.runtime.campaign.provenance import collect  # noqa: PLC0415

    plan = plan_campaign(list(args.missions), repeat=args.repeat, seed=args.seed,
                         controller=args.controller, vepl=args.vepl, duration=args.duration)
    engine: CampaignEngine
    if args.engine == "dask":
        if not args.scheduler:
            raise CampaignError("--engine dask: expected --scheduler ADDRESS "
                                "(start one with `dask scheduler`)")
        engine = DaskEngine(args.scheduler, timeout=args.timeout)
    else:
        if args.scheduler:
            raise CampaignError("--scheduler is only used with --engine dask")
        engine = LocalEngine(args.workers or os.cpu_count() or 1, timeout=args.timeout)
    provenance = collect(["rei", *sys.argv[1:]] if sys.argv else [], engine.describe(),
                         args.controller, args.controller_version)
    print(f"campaign: {len(plan.runs)} runs ({len(plan.runs) // plan.repeat} missions x "
          f"{plan.repeat}) on {args.engine} engine -> {args.output}", file=sys.stderr)
    try:
        result = run_campaign(plan, args.output, engine, provenance)
    except KeyboardInterrupt:
        print(f"rei campaign: interrupted; the finished runs are kept in {args.output}. Run "
              f"the same command again to finish the missing ones.", file=sys.stderr)
        return EXIT_INTERRUPTED
    return finish(args.output, no_report=args.no_report, complete=result.complete)


def finish(root: Path, *, no_report: bool = False, complete: bool = True) -> int:
    """Write junit.xml and the report of a campaign folder; the exit status of its verdicts."""
    from rei.runtime.report import build_report  # noqa: PLC0415

    outcome = build_report(root, html=not no_report)
    print(outcome.describe(), file=sys.stderr)
    if not complete:
        return EXIT_INTERRUPTED
    return EXIT_OK if outcome.all_passed else EXIT_FAILED
