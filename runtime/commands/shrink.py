"""`rei shrink CASE.mission -o DIR`: the smallest case that still fails the same requirement.

Delta debugging over the case's humans, objects, goals, trajectory vertices and grid floors,
then rounding its numbers; each step is kept only when the shrunk case checks clean and the
same requirement fails on every one of K seeds (rei.runtime.campaigns.shrink). Exit status (the one
pass
rule applied to the case): 1 the case fails (the smallest failing case is written; also when
the requirement fails on some seeds only: flaky, nothing shrunk), 0 the case passes on every
seed (nothing to shrink, said so; no case written), 2 bad input, 3 a run of the original case
broke, 130 interrupted (the best case so far is kept in DIR).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from rei.lang.cli_support import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_RUN_ERROR,
)
from rei.lang.errors import printable_lines
from rei.lang.vepl_parameters import add_functions_option, add_parameter_option, parameter_values

HELP_EXAMPLES = """\
rei shrink examples/navigation/navigation.mission -o out/shrunk \\
    --controller bench.defects.planning:FootprintTooSmall          # 3 seeds, 2 at once
rei shrink case.mission -o out/min --requirement SPEED_LIMIT --seeds 5 --workers 4
rei shrink case.mission -o out/min --keep floors --max-runs 60   # rooms as they are, cheaper
rei shrink case.mission -o out/min07 --requirement REACTION_TIME --param react_zone=0.7
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rei.runtime.campaigns.shrink.shrinker import STAGES  # noqa: PLC0415
    from rei.runtime.commands.campaign import positive_int  # noqa: PLC0415
    from rei.runtime.commands.run import CONTROLLER_HELP  # noqa: PLC0415

    parser = sub.add_parser(
        "shrink", help="delta-debug a failing case down to the smallest one that still fails",
        description="Remove what does not matter from a failing case: humans, dynamic objects, "
                    "objects and goals, trajectory vertices (straighter paths), grid floors "
                    "(made wall), then round numbers, keeping each step only when the result "
                    "checks clean (`rei-gen check`) and the same requirement still fails on "
                    "every one of --seeds seeds. DIR gets the smallest .mission and .room "
                    "(rewritten as they improve), before-after.png, shrink.json (requirement, "
                    "seeds, sizes before and after per kind, runs spent, the replay command) "
                    "and shrink-runs.jsonl (judged candidates: the same command again resumes "
                    "without rerunning them). Exit status: 1 the case fails (the smallest "
                    "failing case is written; flaky when the requirement fails on some seeds "
                    "only: nothing shrunk), 0 it passes on every seed (nothing to shrink; no "
                    "case written), 2 invalid input (also a --controller `rei run` cannot "
                    "load), 3 a run of the original broke, 130 "
                    "interrupted (the best case so far is kept). See docs/shrink.md.")
    parser.add_argument("mission", type=Path, metavar="CASE",
                        help="the failing .mission (its room is read through its import)")
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="output folder (created; not the case's own folder)")
    parser.add_argument("--requirement", default=None, metavar="NAME",
                        help="the requirement that must keep failing (default: the first one "
                             "the original fails on every seed)")
    parser.add_argument("--seeds", type=positive_int, default=3, metavar="K",
                        help="a step is kept when the requirement fails on all K seeds "
                             "(default 3)")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="the first seed; the seeds are S, S+1, ..., S+K-1 (default 0)")
    parser.add_argument("--max-runs", type=positive_int, default=200, metavar="N",
                        help="stop after N runs with the best case so far (default 200; runs "
                             "remembered from an earlier session count too, so a resumed "
                             "shrink ends where an uninterrupted one would)")
    parser.add_argument("--keep", action="append", choices=STAGES, default=None,
                        help="leave this part of the case as it is (repeatable): elements "
                             "(humans, objects, goals, cycles), trajectories, floors, numbers")
    parser.add_argument("--workers", type=positive_int, default=2, metavar="N",
                        help="runs at once (default 2)")
    parser.add_argument("--controller", default=None, metavar="NAME",
                        help=CONTROLLER_HELP + " (default reference)")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="monitoring specification passed to `rei run`")
    add_parameter_option(parser, "passed to `rei run`: ")
    add_functions_option(parser, "; passed to every `rei run`")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="simulated seconds per run, passed to `rei run`")
    parser.add_argument("--timeout", type=float, default=None, metavar="S",
                        help="wall-clock watchdog per run (as `rei campaign --timeout`)")
    parser.add_argument("--no-variation", action="store_true",
                        help="passed to `rei run`: no seeded start-pose jitter")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress; print only the final line")
    parser.set_defaults(func=run)


def _check(args: argparse.Namespace) -> None:
    from rei.runtime.errors import RunError  # noqa: PLC0415
    from rei.runtime.runs.session import MAX_SEED  # noqa: PLC0415

    if args.mission.suffix != ".mission" or not args.mission.is_file():
        raise RunError(f"{args.mission}: expected a .mission file to shrink, found "
                       f"{'another kind of file' if args.mission.exists() else 'nothing'}")
    for name, value in (("--duration", args.duration), ("--timeout", args.timeout)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise RunError(f"{name}: expected a positive finite number of seconds, found "
                           f"{value}")
    if not 0 <= args.seed or args.seed + args.seeds - 1 > MAX_SEED:
        raise RunError(f"--seed: expected seeds from 0 to 2**64-1, found {args.seed}")
    if args.vepl is not None and not args.vepl.is_file():
        raise RunError(f"--vepl: file '{args.vepl}' does not exist")
    if args.param:  # every name declared, every rule kept: before any run (LanguageError)
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415

        load_vepl(args.vepl, parameter_values(args.param))
    if args.output.exists() and not args.output.is_dir():
        raise RunError(f"-o {args.output}: expected a folder (new or existing), found a file")
    if args.output.resolve() == args.mission.resolve().parent:
        raise RunError(f"-o {args.output}: expected a folder other than the case's own (the "
                       f"shrunk files would replace the originals)")


def run(args: argparse.Namespace) -> int:
    from rei.runtime.campaigns.shrink.oracle import RunSettings  # noqa: PLC0415
    from rei.runtime.campaigns.shrink.workflow import shrink_into  # noqa: PLC0415

    _check(args)
    if args.functions is not None and Path(args.functions).is_file():
        args.functions = str(Path(args.functions).resolve())
    settings = RunSettings(
        seeds=tuple(range(args.seed, args.seed + args.seeds)), controller=args.controller,
        vepl=str(args.vepl.resolve()) if args.vepl is not None else None,
        functions=args.functions, duration=args.duration, variation=not args.no_variation,
        workers=args.workers, timeout=args.timeout,
        vepl_parameters=parameter_values(args.param))

    def progress(line: str) -> None:
        if not args.quiet:
            print(f"  shrink: {printable_lines(line)}", file=sys.stderr, flush=True)

    try:
        report = shrink_into(args.mission, args.output, settings, requirement=args.requirement,
                             max_runs=args.max_runs, keep=frozenset(args.keep or ()),
                             progress=progress)
    except KeyboardInterrupt:
        print(f"rei shrink: interrupted; the best case so far is in {args.output}",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    return _print(report, args.output, args.quiet)


def _print(report: object, out: Path, quiet: bool) -> int:
    import json  # noqa: PLC0415

    from rei.runtime.campaigns.shrink.shrinker import SUMMARY, ShrinkReport  # noqa: PLC0415

    assert isinstance(report, ShrinkReport)
    summary = json.loads((out / SUMMARY).read_text(encoding="utf-8"))
    seeds = ", ".join(str(o.seed) for o in report.original)
    if report.result == "invalid_input":
        refused = next(o for o in report.original if o.verdict == "invalid")
        print(f"rei shrink: error: `rei run` refused the case's input: "
              f"{printable_lines(refused.message.splitlines()[-1] if refused.message else '')}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    if report.result == "run_error":
        broken = next(o for o in report.original if o.verdict == "error")
        print(f"verdict: ERROR: a run of the original case broke (seed {broken.seed}: "
              f"{printable_lines(broken.message)}); nothing shrunk; see {out / SUMMARY}")
        return EXIT_RUN_ERROR
    if report.result == "passes":
        what = f"{report.requirement} passes" if report.requirement else "every requirement " \
            "passes or is inconclusive"
        print(f"verdict: NOTHING TO SHRINK: {what} on every seed ({seeds}); no case written; "
              f"see {out / SUMMARY}")
        return EXIT_OK if all(o.verdict == "pass" for o in report.original) else EXIT_FAILED
    if report.result == "flaky":
        failing = [str(o.seed) for o in report.original if report.requirement in o.failed]
        print(f"verdict: FLAKY: {report.requirement} fails on seed(s) {', '.join(failing)} of "
              f"{seeds} only; nothing shrunk (choose seeds where it always fails, or fewer "
              f"--seeds); see {out / SUMMARY}")
        return EXIT_FAILED
    before, after = summary["sizes"]["before"], summary["sizes"]["after"]
    if not quiet:
        from rei.runtime.campaigns.shrink.case import ELEMENT_KINDS  # noqa: PLC0415

        kinds = ", ".join(f"{k.replace('_', ' ')} {before[k]} -> {after[k]}"
                          for k in ELEMENT_KINDS if before[k])
        print(f"{report.requirement} still fails on seeds {seeds}: {before['elements']} -> "
              f"{after['elements']} elements ({kinds}); {report.runs} runs")
        if report.stopped:
            print(f"  stopped early ({report.stopped}): the best case so far is written")
        print(f"  minimal case: {out / report.best.mission_name}; picture: "
              f"{out / summary['files']['picture']}")
        print(f"  replay: {summary['replay']}")
    print(f"verdict: FAIL ({report.requirement}, shrunk {before['elements']} -> "
          f"{after['elements']} elements); outputs in {out}")
    return EXIT_FAILED


__all__ = ["register", "run"]
