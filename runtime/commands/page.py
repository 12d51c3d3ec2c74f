"""`rei page DIR...`: draw the full page (report.html with plots and map) of runs that have
none, or only the brief one a campaign writes for a passing run (`--pages failed`).

DIR is a run folder (`rei run -o DIR`) or a campaign folder (`rei campaign -o DIR`: every
recorded run in it). A page already full is left as it is, so running it twice costs nothing
the second time; the pages are the bytes `rei run --page all` would have written. This
command must never run a mission or change any file but the runs' report.html.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_OK, EXIT_RUN_ERROR

HELP_EXAMPLES = """\
rei page out/campaign                      # full pages for the campaign's passing runs too
rei page out/campaign/runs/navigation.r00  # one run's folder
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "page", help="draw the full page of runs that have a brief one or none",
        description="Draw report.html with its plots and map for each run folder given, or "
                    "for every recorded run of each campaign folder given, where the page is "
                    "missing or brief (a campaign's passing runs get a brief page by default, "
                    "--pages failed). Full pages are left as they are. Exit status: 0 every "
                    "page is full, 2 a DIR is neither a run folder nor a campaign folder, 3 a "
                    "page could not be written (said on stderr).")
    parser.add_argument("folders", type=Path, nargs="+", metavar="DIR",
                        help="a run folder (with summary.json) or a campaign folder")
    parser.set_defaults(func=run)


def run_folders(folder: Path) -> list[Path]:
    """The run folders ``folder`` stands for: itself (a run folder), or the folders of the
    campaign's recorded runs that ran (crashed and hung runs have no summary to draw from).
    CampaignError when it is neither."""
    from rei.runtime.campaigns import CampaignError, CampaignStore  # noqa: PLC0415
    from rei.runtime.campaigns.store import RUNS  # noqa: PLC0415

    if (folder / "summary.json").is_file():
        return [folder]
    if not folder.is_dir():
        raise CampaignError(f"{folder}: expected a run folder or a campaign folder, found "
                            f"{'nothing' if not folder.exists() else 'a file'}")
    if not (folder / "campaign.json").is_file():
        raise CampaignError(f"{folder}: expected a run folder (with summary.json) or a "
                            f"campaign folder (with campaign.json), found neither")
    _, _, records = CampaignStore.read(folder)
    return [folder / RUNS / r.spec.run_id for r in records
            if r.status == "ran" and (folder / RUNS / r.spec.run_id / "summary.json").is_file()]


def run(args: argparse.Namespace) -> int:
    from rei.lang.errors import ReiError  # noqa: PLC0415
    from rei.runtime.presentation.run_page.rendering import (  # noqa: PLC0415
        page_is_full,
        write_run_page,
    )

    # every DIR checked before any page is drawn: a typo is exit 2, with nothing half done
    folders = [run_folder for folder in args.folders for run_folder in run_folders(folder)]
    drawn = full = failed = 0
    for folder in folders:
        if page_is_full(folder):
            full += 1
            continue
        try:
            write_run_page(folder)
            drawn += 1
        except (ReiError, OSError) as exc:
            failed += 1
            print(f"rei page: {folder}: report.html not written: {exc}", file=sys.stderr)
    print(f"rei page: {drawn} page(s) drawn, {full} already full"
          + (f", {failed} not written" if failed else ""))
    return EXIT_RUN_ERROR if failed else EXIT_OK
