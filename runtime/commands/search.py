"""`rei search -o DIR`: look for scenarios that fail the robot, steered by a margin.

Candidates are rows of the room generator (factor levels, LOW:HIGH ranges of the numeric
factors, the layout seed), written as checked .room/.mission pairs and run as a campaign in
DIR, a batch at a time; the strategy minimises the chosen requirement's robustness margin.
Exit status by the campaign's one rule (rei.runtime.campaigns.stats.campaign_outcome): 0 every
candidate's run passed (nothing found), 1 a run failed (a failing scenario was found: a fail
verdict on the navigator) or was inconclusive, 2 bad input, 3 a run errored, 130 interrupted
(run the same command again: it resumes and ends as an uninterrupted search would).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rei.lang.cli_support import EXIT_INTERRUPTED
from rei.lang.vepl_parameters import add_parameter_option, parameter_values

if TYPE_CHECKING:
    from rei.runtime.campaigns.search import SearchConfig

HELP_EXAMPLES = """\
rei search -o out/search --controller my_nav:Navigator --budget 200 --workers 2
rei search -o out/slow --preset stress --strategy map-elites --requirement HUMAN_SLOW_ZONE
rei search -o out/limit --max-speed 0.05:0.3 --requirement SPEED_LIMIT --budget 12 --batch 4
rei search -o out/phase --phase 0:20 --speed 0.6:1.0 --requirement HUMAN_SLOW_ZONE
rei search -o out/emerge --preset stress --stressor emerge --stress-shift=-4:4 --budget 24
rei search -o out/place --object-shift=-0.1:0.3 --goal-shift 0:0.25 --budget 16
rei search -o out/walk --path-shift=-0.2:0.2 --phase 0:10 --requirement HUMAN_SLOW_ZONE
rei search -o out/noise --fault-range laser_noise.sigma=0.01:0.2 --requirement REACTION_TIME
rei search -o out/search --controller my_nav:Navigator --budget 200   # again: resumes
rei search -o out/slow07 --preset stress --requirement REACTION_TIME --param react_zone=0.7
"""

EXIT_HELP = ("Exit status (the campaign's rule): 0 no run failed (nothing found), 1 a run "
             "failed (a failing scenario found) or was inconclusive, 2 bad input, 3 a run "
             "errored, 130 interrupted (run the same command again to resume).")


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rei.catalogue import default_catalogue  # noqa: PLC0415
    from rei.generators.rooms.scenario import (  # noqa: PLC0415
        MAX_PHASE,
        MAX_PLACEMENT,
        MAX_SHIFT,
        object_room,
    )
    from rei.lang.commands.rooms import OVERRIDES  # noqa: PLC0415
    from rei.runtime.campaigns.search.strategies import DEFAULT_MEASURES, MEASURE_RANGES, STRATEGIES
    from rei.runtime.commands.campaign import _seconds, add_engine_arguments  # noqa: PLC0415
    from rei.runtime.commands.run import CONTROLLER_HELP  # noqa: PLC0415

    parser = sub.add_parser(
        "search",
        help="search generated rooms and missions for runs that fail (or nearly fail) the "
             "robot",
        description="Search the room generator's factors and continuous parameters for runs "
                    "that minimise a requirement's robustness margin (default: the smallest "
                    "margin of any requirement), within --budget simulations. Every candidate "
                    "is a checked .room/.mission pair in DIR/candidates/, run as a campaign "
                    "in DIR (so `rei report DIR` reads it); DIR/search.csv lists every "
                    "candidate with its margin and verdict. Factor options take levels as "
                    "`rei-gen rooms` does; --speed, --spacing and --max-speed also take a "
                    "range LOW:HIGH searched as a continuous value, and so do the scenario's "
                    "--phase, --stress-shift, --object-shift, --goal-shift, --path-shift "
                    "and --fault-range. The layout (which tiles hold the objects, the "
                    "humans' paths and the goals) is searched as a seed unless --layout "
                    "fixes it; the shifts move them within their tiles. Same options and "
                    "seed give the same candidates and results, with any number of "
                    "workers. " + EXIT_HELP)
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="search folder (created; an existing one is resumed)")
    parser.add_argument("--strategy", choices=STRATEGIES, default="tpe",
                        help="random, sobol, halton (baselines), tpe, cmaes (Optuna), "
                             "map-elites (pyribs, diverse failures) (default tpe)")
    parser.add_argument("--budget", type=int, default=100, metavar="N",
                        help="candidates to try, at most one simulation each (default 100); "
                             "a candidate the generator cannot build counts and does not run")
    parser.add_argument("--batch", type=int, default=8, metavar="K",
                        help="candidates proposed, run and learnt from together (default 8); "
                             "part of the search's identity, unlike --workers")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="seed of the strategy and of the runs (default 0)")
    parser.add_argument("--requirement", default=None, metavar="NAME",
                        help="requirement whose margin is minimised (default: the smallest "
                             "margin of any requirement in each run)")
    parser.add_argument("--measures", default=",".join(DEFAULT_MEASURES), metavar="A,B",
                        help="two difficulty descriptors for map-elites' grid, of "
                             + ", ".join(MEASURE_RANGES) + " (default %(default)s)")
    parser.add_argument("--preset", choices=("small", "medium", "large", "stress"),
                        default="small", help="the factor levels to start from (default small)")
    for name, text in OVERRIDES:
        parser.add_argument(f"--{name.replace('_', '-')}", default=None, metavar="LEVELS",
                            help=text)
    parser.add_argument("--phase", default=None, metavar="LOW:HIGH",
                        help="search the humans' start phase: the second (0 to "
                             f"{MAX_PHASE:g}) at which every generated human passes its first "
                             "vertex (one with an open path waits there until then; a looping "
                             "one is already on its loop)")
    parser.add_argument("--stress-shift", default=None, metavar="LOW:HIGH",
                        help="search when the stressor's person sets off: seconds later "
                             f"(negative: earlier, -{MAX_SHIFT:g} to {MAX_SHIFT:g}) than "
                             "timed, which moves the encounter along the robot's first leg; "
                             "write --stress-shift=-4:4 for a negative LOW")
    most = f"{MAX_PLACEMENT:g}"
    table = default_catalogue().types["table"]
    table_x, table_y = (2 * h for h in table.footprint.half_extents())
    along, across = (round(r, 3) for r in object_room(table, 0.0))
    parser.add_argument("--object-shift", default=None, metavar="LOW:HIGH",
                        help=f"search object placement: metres (-{most} to {most}) every "
                             "generated object moves towards the nearest tile of the robot's "
                             "route (away when negative), as far as its footprint stays on "
                             "its tile: at most (tile - its extent)/2 along each axis, so a "
                             f"{table_x:g} x {table_y:g} m table on a 1 m tile moves at most "
                             f"{along:g} m along its length and {across:g} m across "
                             "(docs/search.md: every kind); written as `offset DX DY`")
    parser.add_argument("--goal-shift", default=None, metavar="LOW:HIGH",
                        help=f"search goal positions: metres (-{most} to {most}) every goal but "
                             "the start moves towards the nearest wall or object (away when "
                             "negative), as far as the robot standing there stays on the "
                             "goal's tile")
    parser.add_argument("--path-shift", default=None, metavar="LOW:HIGH",
                        help=f"search the humans' paths: metres (-{most} to {most}) every vertex "
                             "of a generated human's trajectory moves towards the nearest "
                             "tile of the robot's route (away when negative), within its "
                             "tile; a curve that then grazes a wall or object is refused "
                             "(docs/search.md)")
    parser.add_argument("--fault-range", action="append", default=[],
                        metavar="KIND.PARAM=LOW:HIGH",
                        help="search a sensor fault's parameter (repeatable): the missions "
                             "get a `fault { }` entry of KIND active the whole run, PARAM "
                             "drawn from LOW:HIGH (e.g. laser_noise.sigma=0.01:0.1, "
                             "laser_dropout.share=0.05:0.5, laser_delay.seconds=0.1:0.6; "
                             "every required parameter of a kind needs a range; docs/faults.md)")
    parser.add_argument("--layout", type=int, default=None, metavar="SEED",
                        help="fix the room's construction seed instead of searching it")
    parser.add_argument("--stop-on-failure", action="store_true",
                        help="end after the first batch with a failing run")
    parser.add_argument("--controller", default=None, metavar="NAME",
                        help=CONTROLLER_HELP + " (default reference)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitor specification passed to `rei run`")
    add_parameter_option(parser, "passed to every `rei run`: ")
    parser.add_argument("--duration", type=_seconds, default=None, metavar="S",
                        help="simulated seconds per run (runs cut short are inconclusive and "
                             "give no margin: use it for smoke tests only)")
    add_engine_arguments(parser)
    parser.add_argument("--no-report", action="store_true", help="skip report.html")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress line; only the final verdict line")
    parser.set_defaults(func=run)


def config_of(args: argparse.Namespace) -> SearchConfig:
    from rei.generators.rooms.space import ParameterError  # noqa: PLC0415
    from rei.lang import __version__  # noqa: PLC0415
    from rei.lang.commands.rooms import OVERRIDES  # noqa: PLC0415
    from rei.runtime.campaigns.search import SearchConfig, SearchError  # noqa: PLC0415

    levels: list[tuple[str, str]] = []
    for name, _ in OVERRIDES:
        value = getattr(args, name)
        if value is None:
            continue
        parts = [v.strip() for v in value.split(",") if v.strip()]
        if not parts or len(set(parts)) != len(parts):
            raise ParameterError(name.replace("_", "-"),
                                 "a comma-separated list of distinct levels, or LOW:HIGH",
                                 f"'{value}'")
        if any(":" in p for p in parts) and len(parts) > 1:
            raise ParameterError(name.replace("_", "-"), "levels or one range LOW:HIGH, "
                                 "not both", f"'{value}'")
        levels.append((name, ",".join(parts)))
    scenario: list[tuple[str, str]] = []
    if args.phase is not None:
        scenario.append(("phase", args.phase))
    if args.stress_shift is not None:
        scenario.append(("stress_shift", args.stress_shift))
    for name in ("object_shift", "goal_shift", "path_shift"):
        if getattr(args, name) is not None:
            scenario.append((name, getattr(args, name)))
    for text in args.fault_range:
        name, sep, value = text.partition("=")
        if not sep or not name.strip():
            raise ParameterError("fault-range", "KIND.PARAM=LOW:HIGH (e.g. "
                                 "laser_noise.sigma=0.01:0.1)", f"'{text}'")
        scenario.append((name.strip(), value.strip()))
    measures = tuple(m.strip() for m in args.measures.split(","))
    if len(measures) != 2:
        raise SearchError(f"--measures: expected two descriptor names A,B, found "
                          f"'{args.measures}'")
    return SearchConfig(
        preset=args.preset, levels=tuple(levels), scenario=tuple(scenario),
        layout=args.layout, strategy=args.strategy,
        seed=args.seed, budget=args.budget, batch=args.batch, requirement=args.requirement,
        measures=(measures[0], measures[1]), controller=args.controller,
        vepl=str(args.vepl.resolve()) if args.vepl is not None else None,
        duration=args.duration, stop_on_failure=args.stop_on_failure, version=__version__,
        vepl_parameters=parameter_values(args.param))


def run(args: argparse.Namespace) -> int:
    from rei.runtime.campaigns import CampaignError  # noqa: PLC0415
    from rei.runtime.campaigns.engines import kept_workers  # noqa: PLC0415
    from rei.runtime.campaigns.provenance import collect  # noqa: PLC0415
    from rei.runtime.campaigns.search import run_search  # noqa: PLC0415
    from rei.runtime.campaigns.search.driver import check_config, fail_line  # noqa: PLC0415
    from rei.runtime.commands.campaign import (  # noqa: PLC0415
        _terminate_as_interrupt,
        engine_of,
        finish,
    )

    config = config_of(args)
    check_config(config)  # bad options stop here, before the folder or an engine exists
    if args.vepl is not None and not args.vepl.is_file():
        raise CampaignError(f"--vepl: file '{args.vepl}' does not exist")
    if config.vepl_parameters:  # every name declared, every rule kept: before any run
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, config.vepl_parameters)
    engine = engine_of(args)
    provenance = {**collect(["rei", *sys.argv[1:]] if sys.argv else [], engine.describe(),
                            args.controller, None), "pass_rate": 1.0}
    if not args.quiet:
        print(f"search: {config.strategy}, budget {config.budget} in batches of "
              f"{config.batch}, seed {config.seed}, on {args.engine} engine -> {args.output}",
              file=sys.stderr)
    try:
        # One pool of workers (and fork servers) for every batch, closed when the search ends.
        with _terminate_as_interrupt(), open(os.devnull, "w", encoding="utf-8") as silent, \
                kept_workers(engine) as kept:
            result = run_search(config, args.output, kept, provenance,
                                stream=silent if args.quiet else None)
    except KeyboardInterrupt:
        print(f"rei search: interrupted; the finished runs are kept in {args.output}. Run the "
              f"same command again to continue the search.", file=sys.stderr)
        return EXIT_INTERRUPTED
    if not args.quiet:
        failing = result.failing
        print(f"search: {len(result.results)} candidates, "
              f"{sum(r.record is not None for r in result.results)} simulated, "
              f"{len(failing)} failing (see {args.output / 'search.csv'})", file=sys.stderr)
        for r in sorted(failing, key=lambda r: r.objective)[:10]:
            pair = r.candidate.pair
            assert pair is not None
            print(f"  FAIL  {args.output / 'candidates' / pair.mission_file}: "
                  f"{fail_line(r, config.requirement)}", file=sys.stderr)
    return finish(args.output, no_report=args.no_report, complete=result.complete,
                  pass_rate=1.0, quiet=True)
