"""`rei demo -o DIR`: generate a small room suite, run a campaign on it, write the report.

The README's first command: everything on the embedded defaults (catalogue, default .vepl,
reference controller), a couple of minutes on two cores; ``--controller`` and ``--vepl`` put a
user's own navigator and monitoring specification on the same suite, as `rei campaign` would.
It uses `rei-gen rooms` when that generator is installed and the bundled examples otherwise.
It exits as `rei campaign` does (one rule, rei.runtime.campaigns.stats.campaign_outcome), so a
CI job gating a navigator on `rei demo --controller X` fails when the navigator does: 0 every
mission passes, 1 a mission fails or is inconclusive, 2 bad input, 3 a run errored, 130
interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_OK
from rei.lang.vepl_parameters import add_parameter_option, parameter_values
from rei.runtime.commands.campaign import EXIT_STATUS_HELP, add_pages_argument, positive_int

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


HELP_EXAMPLES = """\
rei demo -o out/demo                                   # a small suite, run and reported
rei demo -o out/demo-mine --controller my_nav:Navigator --count 4 --repeat 2
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rei.runtime.commands.run import (  # noqa: PLC0415
        CAMPAIGN_VERBOSE_HELP,
        CONTROLLER_HELP,
        add_verbosity,
    )

    parser = sub.add_parser(
        "demo", help="generate a small suite, run a campaign on it and write its report",
        description="Generate a small suite of rooms and missions with `rei-gen rooms`, run "
                    "every mission --repeat times in parallel with `rei campaign`, and write "
                    "DIR/campaign/report.html. Test your own navigator on the defaults with "
                    "--controller module:Class (and your requirements with --vepl FILE). Run "
                    "the same command again to resume an interrupted demo. " + EXIT_STATUS_HELP)
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="folder for the suite (DIR/suite) and the campaign (DIR/campaign)")
    parser.add_argument("--count", type=positive_int, default=DEMO_ROOMS, metavar="N",
                        help=f"rooms to generate (default {DEMO_ROOMS}: 3 small, 4 stress, "
                             f"2 doorway; with the small preset half of them, at most "
                             f"{STRESS_ROOMS}, are stress rooms and, from {DOORWAY_FROM} rooms "
                             f"on, {DOORWAY_ROOMS} of the others are doorway rooms: a person "
                             "steps out beside the route, on the robot's left in one and on its "
                             "right in the other)")
    parser.add_argument("--repeat", type=positive_int, default=2, metavar="K",
                        help="runs per mission, each with its own seed (default 2)")
    parser.add_argument("--preset", choices=("small", "medium", "large", "stress"),
                        default="small",
                        help="room class of the suite (default small, with stress rooms: a "
                             "person emerging from behind a corner, a crossing cart, a gap "
                             "narrower than the robot, and people stepping out of doorways)")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="seed of the generated suite and of the campaign's runs (default 0)")
    parser.add_argument("--workers", type=positive_int, default=None, metavar="N",
                        help="runs at once (default: number of CPUs)")
    parser.add_argument("--controller", default=None, metavar="NAME",
                        help=CONTROLLER_HELP + "; passed to every `rei run` (default "
                             "reference)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitoring specification passed to every `rei run` (default: "
                             "REI's default.vepl)")
    add_parameter_option(parser, "passed to every `rei run`: ")
    add_pages_argument(parser)
    add_verbosity(parser, CAMPAIGN_VERBOSE_HELP)  # as `rei campaign`
    parser.set_defaults(func=run)


STRESS_ROOMS = 4
"""Stress rooms the demo takes at most, half its rooms with the small preset: the stress
preset's first systematic rows, a person emerging from behind a corner, a crossing cart, a
gap narrower than the robot and a person standing in a door on the phone (the one situation
of the demo in which a sound navigator must wait and run its recoveries: without it, no run
of the demo exercises a recovery, rei.runtime.campaigns.coverage)."""


DOORWAY_ROOMS = 2
"""Doorway rooms the demo adds (`--stressor doorway`): a person steps out of a doorway beside
the route as the robot comes level, first seen 60-120 degrees off its heading. Two rooms, so
the suite's alternating sides (stressors.side_of) put one doorway on the robot's left and one
on its right on every seed: a navigator blind on either side meets its blind side in every
demo. Two rooms rather than one room with a doorway on each side: each encounter then starts
from a robot that has seen nothing nearby, where a second doorway down the same leg could
find the robot still slowed for the first person (the reference keeps its slow zone 3 s)."""
DOORWAY_FROM = 8
"""The smallest ``--count`` with the doorway pair: smaller demos keep their rooms as before."""
DEMO_ROOMS = 9
"""The default ``--count``: 3 small rooms, 4 stress rooms, the doorway pair."""


def stress_share(count: int, preset: str) -> int:
    """How many of the demo's ``count`` rooms are the stress preset's systematic rows."""
    return min(STRESS_ROOMS, count // 2) if preset == "small" else 0


def doorway_share(count: int, preset: str) -> int:
    """How many of the demo's ``count`` rooms are doorway rooms (DOORWAY_ROOMS or none)."""
    return DOORWAY_ROOMS if preset == "small" and count >= DOORWAY_FROM else 0


def generate_suite(out: Path, count: int, preset: str, seed: int) -> list[Path]:
    """The suite's indexes, generated with `rei-gen rooms`: ``count`` rooms of ``preset``,
    with the small preset ``stress_share`` of them stress rooms (in DIR/suite/stress) and
    ``doorway_share`` doorway rooms (in DIR/suite/doorway); the bundled examples without the
    generator."""
    try:
        from rei.lang.cli import main as rei_gen  # noqa: PLC0415
        from rei.lang.commands import rooms  # noqa: F401, PLC0415
    except ImportError:
        print(f"rei demo: `rei-gen rooms` is not installed; using {EXAMPLES}", file=sys.stderr)
        return [EXAMPLES]
    stress, doorways = stress_share(count, preset), doorway_share(count, preset)
    suites = [(out, ["--count", str(count - stress - doorways), "--preset", preset])]
    if stress:
        suites.append((out / "stress", ["--count", str(stress), "--preset", "stress",
                                        "--strategy", "systematic", "--prefix", "stress"]))
    if doorways:
        suites.append((out / "doorway", ["--count", str(doorways), "--preset", "stress",
                                         "--stressor", "doorway", "--prefix", "doorway"]))
    indexes = []
    for folder, options in suites:
        index = folder / "index.csv"
        indexes.append(index)
        if index.is_file():
            continue  # resuming: the same seed gave these files, keep them
        report = io.StringIO()
        with contextlib.redirect_stdout(report):  # the coverage report is in coverage.txt
            status = rei_gen(["rooms", "-o", str(folder), *options, "--seed", str(seed)])
        if status != EXIT_OK or not index.is_file():
            sys.stderr.write(report.getvalue())
            raise SystemExit(status or EXIT_BAD_INPUT)
    return indexes


def run(args: argparse.Namespace) -> int:
    from rei.runtime.campaigns import CampaignError, LocalEngine, plan_campaign, run_campaign
    from rei.runtime.campaigns.provenance import collect  # noqa: PLC0415
    from rei.runtime.commands.campaign import finish  # noqa: PLC0415

    out: Path = args.output
    if args.vepl is not None and not args.vepl.is_file():  # before minutes of generation
        raise CampaignError(f"--vepl: file '{args.vepl}' does not exist")
    parameters = parameter_values(args.param)
    if parameters:  # every name declared, every rule kept: before minutes of generation too
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, parameters)

    def say(text: str) -> None:
        if not args.quiet:
            print(text, file=sys.stderr)

    stress, doorways = stress_share(args.count, args.preset), doorway_share(args.count,
                                                                            args.preset)
    shares = [(args.count - stress - doorways, args.preset), (stress, "stress"),
              (doorways, "doorway")]
    named = [f"{n} {kind}" for n, kind in shares if n]
    rooms = ", ".join(named[:-1]) + " and " + named[-1] if len(named) > 1 else named[0]
    say(f"1/3 generating {rooms} rooms into {out / 'suite'}")
    inputs = generate_suite(out / "suite", args.count, args.preset, args.seed)
    plan = plan_campaign(inputs, repeat=args.repeat, seed=args.seed, controller=args.controller,
                         vepl=args.vepl, vepl_parameters=parameters)
    engine = LocalEngine(args.workers or os.cpu_count() or 1, pages=args.pages)
    who = f" of {args.controller}" if args.controller else ""
    say(f"2/3 running {len(plan.runs)} runs{who} on {engine.workers} worker(s) into "
        f"{out / 'campaign'}")
    provenance = collect(["rei", *sys.argv[1:]], engine.describe(), args.controller, None)
    try:
        with open(os.devnull, "w", encoding="utf-8") as silent:
            run_campaign(plan, out / "campaign", engine, provenance,
                         stream=silent if args.quiet else None)
    except KeyboardInterrupt:
        print("rei demo: interrupted; run the same command again to finish", file=sys.stderr)
        return EXIT_INTERRUPTED
    say("3/3 writing the report")
    status = finish(out / "campaign", quiet=args.quiet, verbose=args.verbose)
    report = (out / "campaign" / "report.html").resolve()
    print(f"{'' if args.quiet else chr(10)}Open the report: {report.as_uri()}")
    if not args.quiet:
        print(f"Re-run any failure with the command listed in it; rebuild it with "
              f"`rei report {out / 'campaign'}`.")
    return status
