"""`rei bus`: start the bus (a Zenoh router) other REI components join.

Writes the bus's folder (credentials per role and the router's configuration, readable by
the owner only), starts the router on the endpoint, prints the endpoint and the folder, and
runs until SIGINT or SIGTERM, then stops the router and exits 0 (130 after Ctrl-C is the
shell's convention for an interrupted *run*; a bus asked to stop has done its job). Exit
status: 0 stopped as asked, 2 invalid input (a bad address or port, TLS files missing), 3
the router could not start (the port is taken, ...).
"""

from __future__ import annotations

import argparse
import signal
import sys
import tempfile
import threading
from pathlib import Path
from types import FrameType

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_OK, EXIT_RUN_ERROR

EXAMPLES = """\
examples:
  rei bus                         # loopback, a free port, credentials in a fresh folder
  rei bus --port 7447 --dir ~/.rei/bus
  export REI_BUS_CREDENTIALS=DIR  # the folder it printed: components find their role's file
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "bus", help="start the bus (a Zenoh router) the components of a distributed run join",
        description="Start a Zenoh router for REI's components (`rei run --bus`, "
                    "`rei robot`, `rei monitor`, viewers): loopback unless --host says "
                    "otherwise, multicast scouting off, authentication always on with "
                    "credentials generated for each role, access rules per role enforced by "
                    "the router, TLS when --tls-cert and --tls-key are given. Prints the "
                    "endpoint and the folder of the credentials (mode 0700, files 0600), then "
                    "runs until Ctrl-C or SIGTERM. See docs/bus.md.",
        epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1: this machine only)")
    parser.add_argument("--port", type=int, default=None,
                        help="TCP port (default: one chosen free)")
    parser.add_argument("--dir", type=Path, default=None, metavar="DIR",
                        help="folder for the credentials and the router's configuration "
                             "(default: a fresh private temporary folder)")
    parser.add_argument("--tls-cert", type=Path, default=None, metavar="PEM",
                        help="the router's TLS certificate (with --tls-key and --tls-ca)")
    parser.add_argument("--tls-key", type=Path, default=None, metavar="PEM",
                        help="the router's TLS private key")
    parser.add_argument("--tls-ca", type=Path, default=None, metavar="PEM",
                        help="the CA certificate clients check the router's against")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.bus.errors import BusError  # noqa: PLC0415
    from rei.runtime.bus.router import Tls, start  # noqa: PLC0415

    if args.port is not None and not 0 < args.port < 65536:
        print(f"rei bus: error: --port: a port 1..65535 expected, found {args.port}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    tls_files = (args.tls_cert, args.tls_key, args.tls_ca)
    tls = None
    if any(f is not None for f in tls_files):
        missing = [name for name, f in zip(("--tls-cert", "--tls-key", "--tls-ca"), tls_files,
                                           strict=True) if f is None or not f.is_file()]
        if missing:
            print(f"rei bus: error: TLS needs a certificate, a key and a CA file: "
                  f"{', '.join(missing)} missing", file=sys.stderr)
            return EXIT_BAD_INPUT
        tls = Tls(args.tls_cert.resolve(), args.tls_key.resolve(), args.tls_ca.resolve())
    folder = args.dir if args.dir is not None else Path(tempfile.mkdtemp(prefix="rei-bus-"))
    stop = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        try:
            router = start(folder.resolve(), args.host, args.port, tls=tls)
        except BusError as exc:
            print(f"rei bus: error: {exc}", file=sys.stderr)
            bad_input = "expected" in str(exc)
            return EXIT_BAD_INPUT if bad_input else EXIT_RUN_ERROR
        with router:
            print(f"endpoint {router.bus.endpoint}", flush=True)
            print(f"credentials {router.bus.path}", flush=True)
            print(f"rei bus: ready; components join with --bus {router.bus.endpoint} "
                  f"and REI_BUS_CREDENTIALS={router.bus.path}; Ctrl-C stops", file=sys.stderr,
                  flush=True)
            while not stop.wait(0.5):
                pass
        print("rei bus: stopped", file=sys.stderr)
        return EXIT_OK
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
