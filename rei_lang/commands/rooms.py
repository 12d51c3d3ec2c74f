"""`rei-gen rooms`: generate a suite of checked .room / .mission pairs, an index and a
coverage report. Refuses impossible requests with exit status 2; never loops forever."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rei.lang.cli_support import EXIT_OK

OVERRIDES = (
    ("shape", "room shapes: rect, L, joined (two rooms joined by a doorway)"),
    ("size", "interior sizes in tiles, WIDTHxHEIGHT (e.g. 14x9,16x10)"),
    ("objects", "object counts (e.g. 5,10) or densities as a share of floors (e.g. 10%%,25%%)"),
    ("mix", "object type mixes: mixed, furniture, clutter, or types joined by '+' "
            "(e.g. table+box)"),
    ("humans", "numbers of walking humans"),
    ("vertices", "control vertices per human trajectory (>= 2)"),
    ("speed", "human walking speeds, m/s"),
    ("loop", "whether trajectories loop: yes, no"),
    ("crossing", "cross: every human crosses the robot's route; any: no constraint"),
    ("goals", "goals per mission, the robot's start included (>= 2)"),
    ("spacing", "least straight distance between consecutive goals, metres"),
    ("cycles", "how often the mission repeats its goals"),
    ("behaviour", "how humans react to the robot: scripted, yielding, social, mix (yielding "
                  "and social in turn)"),
    ("heading", "whether the final goal has a heading: yes, no"),
    ("max_speed", "the mission's speed limit, m/s, or none"),
    ("stressor", "a stress scenario on the first leg: none, emerge (a person steps out from "
                 "behind a corner), oncoming (a person in a one-tile corridor), crossing (a "
                 "cart crosses at a right angle), gap (a furniture gap narrower than the "
                 "robot on the direct line), doorway (a person steps out of a doorway "
                 "beside the route as the robot comes level), standing (a person stands in "
                 "a one-tile corridor, giving way to nobody, for a while)"),
)


HELP_EXAMPLES = """\
rei-gen rooms -o suite --count 20 --seed 1              # 20 rooms and missions
rei-gen rooms -o dense --preset small --objects 10%,25% --humans 0,1
rei-gen rooms -o doors --preset stress --stressor doorway --count 4   # people in doorways
rei-gen rooms --describe examples/navigation/navigation.mission
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "rooms",
        help="generate test rooms and missions, valid by construction, with difficulty "
             "descriptors",
        description="Generate N pairs of .room and .mission files (each passes `rei-gen "
                    "check`, goals reachable in order), an index.csv with every room's "
                    "parameters and difficulty descriptors, and coverage.txt. Each factor "
                    "option takes a comma-separated list of levels and replaces the preset's "
                    "levels. Same seed and version give byte-identical files.",
    )
    parser.add_argument("-o", "--output", type=Path, default=None, metavar="DIR",
                        help="folder to write into (created if missing)")
    parser.add_argument("--describe", nargs="+", type=Path, default=None, metavar="MISSION",
                        help="instead of generating: print the difficulty descriptors of "
                             "existing .mission files (hand-written or edited) as CSV")
    parser.add_argument("--count", type=int, default=None, metavar="N",
                        help="rooms to generate (default: the design's rows for systematic, "
                             "10 for random)")
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (default 0)")
    parser.add_argument("--preset", choices=("small", "medium", "large", "stress"),
                        default="medium",
                        help="thesis 7.4 room classes: small and dense, medium with a moving "
                             "human, large; or stress: one stressor per room, timed from the "
                             "robot's planned arrival (default: medium)")
    parser.add_argument("--strategy", choices=("systematic", "random"), default="random",
                        help="systematic: full grid of levels, or a pairwise covering array "
                             "when the grid is larger than --max-grid; random: seeded picks, "
                             "balanced (every level of a factor with n levels once in each "
                             "block of n rooms)")
    parser.add_argument("--design", choices=("auto", "full", "pairwise"), default="auto",
                        help="for systematic: force the full grid or the pairwise array")
    parser.add_argument("--max-grid", type=int, default=256, metavar="N",
                        help="largest full grid before systematic switches to pairwise "
                             "(default 256)")
    parser.add_argument("--prefix", default="room",
                        help="file and room name prefix (default 'room')")
    for name, text in OVERRIDES:
        parser.add_argument(f"--{name.replace('_', '-')}", default=None, metavar="LEVELS",
                            help=text)
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress display and no coverage report; only the final "
                             "line (on stderr)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.generators.rooms import SuiteRequest, coverage_report, generate, write_suite
    from rei.generators.rooms.space import ParameterError, preset_space
    from rei.lang import __version__

    if args.describe is not None:
        return describe_missions(args.describe)
    if args.output is None:
        raise ParameterError("output", "-o DIR, the folder to write the suite into",
                             "no -o option")
    if args.max_grid <= 0:
        raise ParameterError("max-grid", "a whole number of at least 1", f"{args.max_grid}")
    if not args.prefix.isidentifier():
        raise ParameterError("prefix", "a name of letters, digits and '_' not starting with a "
                                       "digit", f"'{args.prefix}'")
    overrides = {}
    for name, _ in OVERRIDES:
        value = getattr(args, name)
        if value is not None:
            levels = tuple(v.strip() for v in value.split(",") if v.strip())
            if not levels or len(set(levels)) != len(levels):
                raise ParameterError(name.replace("_", "-"),
                                     "a comma-separated list of distinct levels",
                                     f"'{value}'")
            overrides[name] = levels
    space = preset_space(args.preset).replaced(overrides)
    request = SuiteRequest(space=space, strategy=args.strategy, count=args.count,
                           seed=args.seed, max_grid=args.max_grid, design=args.design,
                           prefix=args.prefix, version=__version__)
    with RoomsProgress(enabled=not args.quiet and sys.stderr.isatty()) as progress:
        suite = generate(request, args.output, progress=progress.update)
    report = coverage_report(suite)
    write_suite(suite, args.output, report)
    if not args.quiet:
        print(report, end="")
    print(f"{len(suite.pairs)} room(s) and mission(s) written to {args.output} "
          f"(index.csv, coverage.txt)", file=sys.stderr)
    return EXIT_OK


class RoomsProgress:
    """The progress display of a long generation on a terminal: a bar of rooms built of how
    many, and the time left (rich, on stderr). Off the terminal (a log, a pipe) it shows
    nothing, so logs and the generated files stay the same."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.display: Any = None
        self.task: Any = None

    def update(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.display is None:
            from rich.console import Console  # noqa: PLC0415  (only on a terminal)
            from rich.progress import (  # noqa: PLC0415
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeRemainingColumn,
            )

            self.display = Progress(TextColumn("rooms"), BarColumn(), MofNCompleteColumn(),
                                    TextColumn("left"), TimeRemainingColumn(),
                                    console=Console(file=sys.stderr), transient=True)
            self.display.start()
            self.task = self.display.add_task("rooms", total=total)
        self.display.update(self.task, completed=done)

    def __enter__(self) -> RoomsProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.display is not None:
            self.display.stop()


def describe_missions(paths: list[Path]) -> int:
    """Descriptors of existing missions, one CSV row each; invalid files exit 2."""
    import csv

    from rei.generators.rooms import describe, scene_of_documents
    from rei.generators.rooms.descriptors import DESCRIPTOR_NAMES, UnreachableGoals
    from rei.lang.errors import Diagnostic, LanguageError, Span
    from rei.lang.workspace import Workspace, load_mission

    wrong = [Diagnostic(Span.point(str(path)), "INPUT-KIND",
                        f"--describe: expected a .mission file, found "
                        f"'{path.suffix or path.name}'")
             for path in paths if path.suffix != ".mission"]
    if wrong:
        raise LanguageError(wrong)
    workspace = Workspace()
    rows = []
    for path in paths:
        doc = load_mission(path, workspace)
        try:
            values = describe(scene_of_documents(doc.room, doc)).as_row()
        except UnreachableGoals:
            raise LanguageError([Diagnostic(Span.point(str(path)), "GOAL-UNREACHABLE",
                                            "expected goals reachable in order by the robot, "
                                            "found a leg without a path")]) from None
        assert doc.mission is not None
        rows.append((str(path), doc.mission.room_path, *values.values()))
    writer = csv.writer(sys.stdout, lineterminator="\n")
    writer.writerow(("mission", "room", *DESCRIPTOR_NAMES))
    writer.writerows(rows)
    return EXIT_OK
