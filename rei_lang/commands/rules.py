"""`rei-gen rules`: the table of rules the checks enforce."""

from __future__ import annotations

import argparse

from rei.lang.cli_support import EXIT_OK
from rei.lang.rules import RULES

HELP_EXAMPLES = """\
rei-gen rules | grep GRID      # the rules about grids
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser("rules", help="list the rules `rei-gen check` enforces",
                            description="List every rule id with what it checks.")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    width = max(len(r.id) for r in RULES)
    for rule in RULES:
        origin = f"  [{rule.source}]" if rule.source else ""
        print(f"{rule.id:<{width}}  {rule.languages:<14} {rule.summary}{origin}")
    return EXIT_OK
