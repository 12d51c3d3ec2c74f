"""`rei-gen check FILE...`: every problem of every file, located; exit 2 if any error."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_OK
from rei.lang.errors import Diagnostic
from rei.lang.workspace import Workspace, known_suffixes

HELP_EXAMPLES = """\
rei-gen check examples/navigation/navigation.room examples/navigation/navigation.mission
rei-gen check examples/                      # every .room, .mission and .vepl below
rei-gen check --format json my_room.room     # for tools: one JSON object per problem
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "check",
        help="check .room / .mission / .vepl files and report every problem",
        description="Check REI files. Every problem is printed as FILE:LINE:COL: RULE: message "
                    "(see `rei-gen rules`). Folders are searched for REI files. Exit status 0 "
                    "when all files are valid, 2 otherwise.",
    )
    parser.add_argument("files", nargs="+", type=Path, metavar="FILE",
                        help="files or folders to check")
    parser.add_argument("--format", choices=("text", "json"), default="text",
                        help="output format (json: one object per diagnostic)")
    parser.set_defaults(func=run)


def expand(paths: list[Path]) -> list[Path]:
    # Folders are searched for the languages only; a catalogue (.toml) is checked when named.
    suffixes = known_suffixes() - {".toml"}
    out: list[Path] = []
    for path in paths:
        if path.is_dir():
            out.extend(sorted(p for p in path.rglob("*") if p.suffix in suffixes and p.is_file()))
        else:
            out.append(path)
    return out


def run(args: argparse.Namespace) -> int:
    workspace = Workspace()
    files = expand(args.files)
    diagnostics: list[Diagnostic] = []
    for path in files:
        diagnostics.extend(workspace.check(path))
    errors = sum(1 for d in diagnostics if d.is_error)
    if args.format == "json":
        json.dump([{"file": d.span.file, "line": d.span.line, "col": d.span.col,
                    "end_line": d.span.end_line, "end_col": d.span.end_col, "rule": d.rule,
                    "severity": d.severity.value, "message": d.message} for d in diagnostics],
                  sys.stdout, indent=1)
        print()
    else:
        for d in diagnostics:
            print(d)
        print(f"{len(files)} file(s) checked, {errors} error(s)", file=sys.stderr)
    return EXIT_BAD_INPUT if errors or not files else EXIT_OK
