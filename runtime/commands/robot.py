"""`rei robot --bus URL --controller X`: the robot under test as a bus client.

Joins the bus with the robot role's credentials and answers the robot contract's calls
(``rei.runtime.bus.remote_robot``) with a fresh controller per run, the same controller `rei run
--controller X` runs; the simulation (`rei run --bus`) advances in lock-step with it. Runs
until Ctrl-C or SIGTERM (with --once: until its first run ends). The controller runs in this
process: this process is the robot's side of the boundary. Exit status: 0 stopped as asked,
2 invalid input (an unknown controller, bad credentials), 3 the bus could not be joined or
was lost.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_OK, EXIT_RUN_ERROR
from rei.runtime.commands.run import CONTROLLER_HELP

if TYPE_CHECKING:
    from rei.runtime.bus import BusSession

EXAMPLES = """\
examples:
  rei robot --bus tcp/127.0.0.1:7447 --controller reference
  rei robot --bus tcp/127.0.0.1:7447 --credentials ~/.rei/bus --controller mynav:Navigator
"""


def add_bus_options(parser: argparse.ArgumentParser, required: bool = True) -> None:
    """--bus and --credentials, the same for every component that joins a bus."""
    parser.add_argument("--bus", required=required, metavar="URL",
                        help="the bus's endpoint as `rei bus` printed it (tcp/HOST:PORT)")
    parser.add_argument("--credentials", type=Path, default=None, metavar="DIR",
                        help="the bus's credentials folder `rei bus` printed, or this role's "
                             "file in it (default: $REI_BUS_CREDENTIALS)")


def join_bus(args: argparse.Namespace, role: str) -> BusSession | int:
    """A session of ``role`` on the bus of ``--bus``/``--credentials``, or the exit status
    after saying in one line why not (2: bad input or refused credentials, 3: no bus)."""
    from rei.runtime.bus import BusError, connect  # noqa: PLC0415

    try:
        return connect(args.bus, role=role, credentials=args.credentials)
    except BusError as exc:
        print(f"rei {args.command}: error: {exc}", file=sys.stderr)
        text = str(exc)
        refused = "expected" in text or "refused" in text or "credentials" in text
        return EXIT_BAD_INPUT if refused else EXIT_RUN_ERROR


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "robot", help="run a controller as the robot under test of a distributed run",
        description="Join the bus as the robot under test and answer the simulation's calls "
                    "(reset, goals, a velocity command every control period) with the "
                    "controller named by --controller, a fresh one per run. The simulation "
                    "(`rei run MISSION --bus URL`) waits for each answer, at most its "
                    "watchdog. Runs until Ctrl-C or SIGTERM, or with --once until its first "
                    "run ends. See docs/bus.md.",
        epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bus_options(parser)
    parser.add_argument("--controller", default="reference", metavar="NAME",
                        help=CONTROLLER_HELP + " (default reference)")
    parser.add_argument("--once", action="store_true",
                        help="stop after the first run ends")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.bus.remote_robot import serve_robot  # noqa: PLC0415
    from rei.runtime.robot.loading import load_controller  # noqa: PLC0415

    folder = os.getcwd()
    load_controller(args.controller, folder)  # a bad name is said before joining (exit 2)
    stop = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    def say(line: str) -> None:
        print(f"rei robot: {line}", file=sys.stderr, flush=True)

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        session = join_bus(args, "robot")
        if isinstance(session, int):
            return session
        with session:
            say(f"{args.controller} ready on {session.endpoint}")
            runs = serve_robot(session, lambda: load_controller(args.controller, folder),
                               args.once, stop, say)
        say(f"stopped after {runs} run{'s' if runs != 1 else ''}")
        return EXIT_OK
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
