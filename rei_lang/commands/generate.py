"""`rei-gen generate FILE --target NAME|all -o DIR`: the artifacts the testbed loads (4.1.3.2).

The file is checked first (exit 2 with every diagnostic when it is invalid); then the chosen
target(s) render in memory and the files are written all at once, so a failure — a template
error, a catalogue type without geometry, an output folder that cannot be written — leaves
the output folder as it was. This module must never write a file itself.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rei.generators.errors import GenerationError
from rei.lang.cli_support import EXIT_OK
from rei.lang.vepl_parameters import add_parameter_option, parameter_values


def _targets_help() -> str:
    from rei.generators.targets import available_targets  # noqa: PLC0415  (only for --help)

    lines = [f"  {name:<10} {t.description} (from {', '.join(t.accepts)})"
             for name, t in sorted(available_targets().items())]
    return "targets:\n" + "\n".join(lines) + "\n  all        every target that accepts the file"


HELP_EXAMPLES = """\
rei-gen generate examples/navigation/navigation.mission -t gazebo -o out/gazebo
rei-gen generate examples/navigation/navigation.mission -t all -o out/all
rei-gen generate examples/navigation/human_safety.vepl -t rx -o out/automata
rei-gen generate rei_lang/vepl/default.vepl -t rx -o out/slow07 --param react_zone=0.7
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "generate",
        help="generate simulator worlds, launch files, mission XML, ... from a .room/.mission",
        description="Check FILE, map it to coordinates (graph traversal from the robot's floor) "
                    "and the catalogue, and write the artifacts of a target into DIR. With "
                    "--target all, every target that accepts the file writes into DIR/<target>/. "
                    "Nothing is written unless every target succeeded. Exit status 0 ok, 2 invalid "
                    "input or a generation error.",
        epilog=_targets_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", type=Path, metavar="FILE", help="a .room, .mission or .vepl file")
    parser.add_argument("--target", "-t", required=True, metavar="NAME",
                        help="a target name (see below) or 'all'")
    parser.add_argument("--output", "-o", required=True, type=Path, metavar="DIR",
                        help="the output folder (created if missing)")
    parser.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                        help="a target option, e.g. seed=7 (repeatable)")
    add_parameter_option(parser, "a .vepl file only (the generated automata carry the "
                                 "values): ")
    parser.set_defaults(func=run)


def parse_options(items: list[str]) -> dict[str, str]:
    options: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise GenerationError(f"--option: expected KEY=VALUE, found '{item}'")
        if key in options:
            raise GenerationError(f"--option: expected each key once, found '{key}' twice")
        options[key] = value
    return options


def run(args: argparse.Namespace) -> int:
    from rei.generators.pipeline import generate  # noqa: PLC0415  (keeps `rei-gen --help` fast)

    options = parse_options(args.option)
    result, written = generate(args.file, args.target, args.output, options,
                               parameters=parameter_values(args.param))
    for warning in result.warnings:
        print(warning, file=sys.stderr)
    print(f"rei-gen: {args.file}: wrote {len(written)} file(s) of {', '.join(result.targets)} "
          f"into {args.output}", file=sys.stderr)
    return EXIT_OK
