"""`rei-gen show FILE -o OUT.png|OUT.svg`: a top-down picture of a room, or a contact sheet.

FILE is a .room (floors, walls, objects, humans with their trajectories, the robot), a
.mission (the same, with its goals numbered in order), or a folder / an index CSV of many
(one small drawing each, titled by name). An invalid file is reported like `rei-gen check`
does (exit 2). The picture is written atomically. This module must never open a window.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rei.lang.cli_support import EXIT_OK

HELP_EXAMPLES = """\
rei-gen show examples/navigation/navigation.mission --output nav.png
rei-gen show suite/index.csv --output suite.png       # every room of a suite on one sheet
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "show",
        help="draw a room or mission from above (PNG or SVG), or a contact sheet of many",
        description="Draw FILE from above: floors, walls, objects, humans with their "
                    "trajectories (times at the control vertices), the robot with its heading "
                    "and, for a .mission, the goals numbered in order with their tolerance. "
                    "FILE may also be a folder or an index CSV (columns room and/or mission, "
                    "relative to the CSV; optional name): then every room is drawn small on "
                    "one contact sheet. The format follows the output's suffix (.png or .svg).",
    )
    parser.add_argument("file", type=Path, metavar="FILE",
                        help="a .room or .mission file, a folder, or an index .csv")
    parser.add_argument("--output", "-o", required=True, type=Path, metavar="OUT",
                        help="the picture to write (.png or .svg)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    # Imported here: matplotlib is slow to import and only this command needs it.
    from rei.generators.errors import GenerationError  # noqa: PLC0415
    from rei.generators.output import OutputTree, write_tree  # noqa: PLC0415
    from rei.generators.picture import FORMATS, render_file, render_sheet, sheet_entries  # noqa: PLC0415

    out: Path = args.output
    fmt = out.suffix.lower().lstrip(".")
    if fmt not in FORMATS:
        raise GenerationError(f"--output: expected a file ending in .png or .svg, found "
                              f"'{out.name}'")
    source: Path = args.file
    if source.is_dir() or source.suffix.lower() == ".csv":
        entries = sheet_entries(source)
        data = render_sheet(entries, fmt)
        what = f"a contact sheet of {len(entries)} room(s)"
    else:
        data = render_file(source, fmt)
        what = "a picture"
    tree = OutputTree()
    tree.add_bytes(out.name, data)
    write_tree(tree, out.parent if str(out.parent) else Path("."))
    print(f"rei-gen: wrote {what} to {out}", file=sys.stderr)
    return EXIT_OK
