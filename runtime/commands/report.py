"""`rei report DIR`: rebuild report.html, junit.xml and the results tables of a campaign folder."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP_EXAMPLES = """\
rei report out/campaign              # tables, report.html and junit.xml again
rei report out/campaign --no-html    # tables and junit.xml only (for CI)
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from rei.runtime.commands.campaign import EXIT_STATUS_HELP  # noqa: PLC0415

    parser = sub.add_parser(
        "report", help="rebuild report.html and junit.xml of a campaign folder",
        description="Rebuild the results tables, report.html and junit.xml of a campaign folder "
                    "written by `rei campaign`, and judge it again as `rei campaign` does "
                    "(each mission against the pass rate its last session required). "
                    + EXIT_STATUS_HELP.replace("2 bad input", "2 DIR is not a campaign folder")
                    + " A folder with planned runs not yet recorded exits 1 (incomplete).")
    parser.add_argument("folder", type=Path, metavar="DIR", help="the -o folder of a campaign")
    parser.add_argument("--no-html", action="store_true", help="only the tables and junit.xml")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.commands.campaign import finish  # noqa: PLC0415

    return finish(args.folder, no_report=args.no_html)
