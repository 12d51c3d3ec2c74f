"""`rei`: run missions in the simulator, monitor them, evaluate and report."""

from __future__ import annotations

from collections.abc import Sequence

from rei.lang.cli_support import build_parser, command_word, run_main

DESCRIPTION = """\
Run REI missions in pybullet with the robot's navigation software in the loop, monitor them
with event automata generated from .vepl specifications, and evaluate and report the runs.

exit status: 0 every requirement passed, 1 a requirement failed, 2 invalid input,
3 a run error, 130 interrupted
"""


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser("rei", DESCRIPTION, "rei.runtime.commands", command_word(argv))
    return run_main(parser, argv)


if __name__ == "__main__":
    raise SystemExit(main())
