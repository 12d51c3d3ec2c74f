"""`rei-gen`: check REI files and generate what the testbed loads."""

from __future__ import annotations

from collections.abc import Sequence

from rei.lang.cli_support import build_parser, command_word, run_main

DESCRIPTION = """\
Check .room, .mission and .vepl files, and generate artifacts from them.

exit status: 0 ok, 2 invalid input (every problem is printed as FILE:LINE:COL: RULE: message)
"""


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser("rei-gen", DESCRIPTION, "rei.lang.commands", command_word(argv))
    return run_main(parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
