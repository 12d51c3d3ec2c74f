"""Supervising a run: the simulation runs in a child process the robot under test cannot
end, stall or fake.

The controller runs inside the simulation's process (it is called every control tick), so
whatever it does to that process — ``os._exit(0)``, a signal, a loop in C that never gives
the interpreter lock back — the run's own watchdog thread cannot report. ``supervise`` runs
the run in a child process (forked, or a fresh interpreter running the module `rei run`
names, ``rei.runtime.commands.run``; in its own process group: the work it does is
``child_work``, given by `rei run`) and waits on a pipe over which the child reports how far it got:
the mission it loaded, each control tick's simulated time, the end of the loop and, last,
its exit status. Two wall-clock limits apply (never simulated time, which a stalled process
does not advance):

- while the loop runs (the controller is being called): no tick for ``stall_limit(watchdog)``
  seconds, the controller's own watchdog plus a margin of at least 5 s, so that a hang the
  watchdog thread can see is still reported by it with its precise reason, and a loaded
  machine's scheduling noise is never taken for a hang;
- while REI's own work runs (imports, generation, building the world, writing outputs):
  ``SETUP_LIMIT`` seconds between two reports.

Past a limit the child's process group is killed (SIGKILL; the child is started and stopped
with ``rei.runtime.platform.processes``, as the campaign starts its runs). A child that ends without
having reported its exit status (killed by a signal, ``os._exit``, an internal error) or
that is killed for a hang gets summary.json written by this process: outcome ``error`` and
a reason naming what happened and when ("the simulation process was killed by signal 9
(SIGKILL) at t≈1.9 s"); the trace it left stays ``trace.jsonl.partial`` (a trace file that
exists is complete, see ``rei.runtime.trace``). Ctrl-C and SIGTERM are passed on
to the child, which ends the run ``interrupted`` with consistent outputs; a second Ctrl-C
kills it. The child dies with this process (Linux: PR_SET_PDEATHSIG; elsewhere at its next
report, when the pipe is broken, it ends its run as interrupted).

The child's temporary files (the hosted controller's working folder ``rei-controller-*``,
whatever a controller puts in ``$TMPDIR``) are made in a folder this process creates, hands
down (``TMPDIR`` and ``tempfile.tempdir`` of the child, so of every process it starts) and
removes however the child ended: a child killed with SIGKILL cannot clean up after itself.
The folder's name says which process owns it (``rei.runtime.platform.scratch``), and each supervisor
first removes those of supervisors that are gone: a `rei run` killed with SIGKILL leaves its
folder only until the next `rei run` starts.

This module must never import the simulator or the monitor in the supervising process: its
cost there is an interpreter start-up, not a second copy of REI's heavy imports. It is one
idea in one module, a little over 450 lines: the limits, the watch over the child's reports,
the signals passed on and the summary written for a dead child must agree on every state.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import select
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from rei.runtime.platform.processes import (
    Child,
    child_status,
    keep_private,
    one_math_thread,
    start_child,
    stop_child,
)
from rei.runtime.platform.scratch import make_scratch, sweep_stale

SETUP_LIMIT = 120.0
"""Wall-clock seconds REI's own set-up or output writing may go without a report."""

MIN_MARGIN = 5.0
"""Seconds the supervisor waits beyond the controller's watchdog, at least."""

SCRATCH_PREFIX = "rei-run-scratch-"
"""The name of the folders of the children's temporary files begins with it."""

EXIT_RUN_ERROR = 3
EXIT_INTERRUPTED = 130


def stall_limit(watchdog: float) -> float:
    """Wall-clock seconds the running loop may go without a tick before it is killed."""
    return watchdog + max(watchdog, MIN_MARGIN)


@dataclass(frozen=True)
class RunRequest:
    """Everything the child needs to run ``run_into``: plain values that cross a process."""

    mission: str
    output: str
    controller: str = "reference"
    seed: int = 0
    duration: float | None = None
    watchdog: float = 5.0
    physics_rate: float = 100.0
    odom_drift: float = 0.0
    laser_noise: float | None = None
    vepl: str | None = None
    monitor: bool = True
    variation: bool = True
    progress: bool = False
    """Draw the progress bar on the (inherited) stderr."""
    echo_events: bool = False
    """Print the mission events on stderr as they happen (``--verbose``)."""
    functions: str | None = None
    """The module of the specification's user functions (``--functions``)."""
    record: bool = False
    """Also write recording.mcap (``--record``)."""
    faults: tuple[str, ...] = ()
    """Fault entries of ``--fault`` (as written: the child parses them again)."""
    bus: str | None = None
    """The endpoint of `rei bus` the robot under test answers on (``--bus``)."""
    bus_credentials: str | None = None
    bus_wait: float = 30.0
    wait_monitor: bool = False
    parameters: tuple[tuple[str, float], ...] = ()
    """The specification's parameter values of ``--param``, sorted by name."""
    page: str = "all"
    """Which page to write (``--page``: rei.runtime.results.PAGE_POLICIES)."""

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=False)

    @staticmethod
    def from_json(text: str) -> RunRequest:
        data = json.loads(text)
        data["faults"] = tuple(data.get("faults", ()))
        data["parameters"] = tuple((str(n), float(v)) for n, v in data.get("parameters", ()))
        return RunRequest(**data)


@dataclass(frozen=True)
class SupervisedRun:
    """How the child ended, as the supervisor saw it."""

    status: int
    """The exit status `rei run` returns for it (the summary's when there is one)."""
    reported: bool
    """The child reported its own end (False: it died or hung, and ``failure`` says how)."""
    failure: str = ""
    wall_seconds: float = 0.0
    """Wall-clock seconds of the child's simulation loop (0 when it did not report them)."""
    cpu_seconds: float = 0.0
    page: str | None = None
    """report.html, when the child wrote it."""


class _Watch:
    """What the parent knows of the child from its reports."""

    def __init__(self) -> None:
        self.mission = ""
        self.room = ""
        self.time: float | None = None
        self.phase = "setup"  # setup -> running -> finishing
        self.end: dict[str, Any] | None = None
        self.crash = ""

    def hear(self, line: bytes) -> None:
        try:
            message = json.loads(line)
        except ValueError:
            return  # not ours (a controller writing into a descriptor it found); ignored
        if not isinstance(message, dict):
            return
        if "t" in message and isinstance(message["t"], int | float):
            self.time, self.phase = float(message["t"]), "running"
        elif "begin" in message and isinstance(message["begin"], dict):
            self.mission = str(message["begin"].get("mission", ""))
            self.room = str(message["begin"].get("room", ""))
        elif "end" in message and isinstance(message["end"], int | float):
            self.time, self.phase = float(message["end"]), "finishing"
        elif "crash" in message:
            self.crash = str(message["crash"])
        elif "exit" in message:
            self.end = message

    def at(self) -> str:
        if self.phase == "setup":
            return "while setting up the run"
        if self.phase == "finishing":
            return f"after the run (t≈{self.time:.1f} s), while writing its outputs"
        return f"at t≈{self.time:.1f} s"


def _signal_name(number: int) -> str:
    try:
        return f"signal {number} ({signal.Signals(number).name})"
    except ValueError:
        return f"signal {number}"


def _signal_group(process: Child, number: int) -> None:
    try:
        os.killpg(process.pid, number)
    except (ProcessLookupError, PermissionError):
        pass


ChildWork = Callable[[RunRequest, Any], tuple[int, dict[str, Any]]]
"""What the child does with the request and its channel to the supervisor (the run's probe):
(exit status, what the supervisor reads back). `rei run` gives
``rei.runtime.commands.run.child_work``: the supervisor knows nothing of what a run is."""


def supervise(request: RunRequest, work: ChildWork, module: str) -> SupervisedRun:
    """Run ``request`` in a child process doing ``work`` and wait for it under the liveness
    limits; a child that dies or hangs gets summary.json written here (outcome error). The
    child is forked when it can be; otherwise it is `python -m module`, whose main calls
    ``child_main`` with the same ``work``."""
    # The folders of runs killed with SIGKILL (this process could not remove them) first.
    sweep_stale(SCRATCH_PREFIX)
    scratch = make_scratch(SCRATCH_PREFIX)
    try:
        return _supervise(request, scratch, work, module)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _supervise(request: RunRequest, scratch: str, work: ChildWork,
               module: str) -> SupervisedRun:
    read_end, write_end = os.pipe()
    args = [str(write_end), request.to_json(), scratch]
    argv = [sys.executable, "-m", module, *args]
    try:
        # The child's stdout is this process's stderr: stdout carries the results `rei run`
        # prints, never what a controller or a library prints while running. Forked when it
        # can be (rei.runtime.platform.warm): REI's imports are then those this process has made.
        process = start_child(argv, stdout=2, pass_fds=(write_end,),
                              warm=lambda: child_main(args, work))
    finally:
        os.close(write_end)
    watch = _Watch()
    failure = ""
    interrupted = False
    stall = stall_limit(request.watchdog)
    previous_term = None
    if threading.current_thread() is threading.main_thread():
        def on_term(signum: int, frame: FrameType | None) -> None:
            raise KeyboardInterrupt
        previous_term = signal.signal(signal.SIGTERM, on_term)
    try:
        buffer = b""
        heard = time.monotonic()
        eof = False
        while True:
            try:
                limit = stall if watch.phase == "running" else SETUP_LIMIT
                if watch.end is not None:
                    limit = MIN_MARGIN  # reported; only a thread left running can hold it
                if not eof:
                    ready, _, _ = select.select([read_end], [], [], 0.2)
                    if ready:
                        chunk = os.read(read_end, 65536)
                        if chunk:
                            heard = time.monotonic()
                            buffer += chunk
                            *lines, buffer = buffer.split(b"\n")
                            for line in lines:
                                watch.hear(line)
                        else:
                            eof = True
                else:
                    time.sleep(0.05)
                ended = child_status(process) is not None  # its group is swept then
                if ended and (eof or watch.end is not None):
                    break
                if ended and not select.select([read_end], [], [], 0)[0]:
                    break  # ended; a descriptor kept open by a grandchild gives no EOF
                if time.monotonic() - heard > limit:
                    stop_child(process)
                    if watch.end is not None:
                        break  # its result stands; what kept it from exiting is not the run
                    failure = (f"the simulation stopped responding {watch.at()}: no "
                               f"progress for {limit:g} s (a controller holding the "
                               f"interpreter, or a hang in native code); killed")
                    break
            except KeyboardInterrupt:
                if interrupted:  # the second Ctrl-C: stop waiting for a clean end
                    stop_child(process)
                    failure = "interrupted"
                    break
                interrupted = True
                _signal_group(process, signal.SIGINT)
    finally:
        if previous_term is not None:
            signal.signal(signal.SIGTERM, previous_term)
        os.close(read_end)
        code = stop_child(process)  # ended already, or stopping it is all that is left
    if not failure and watch.end is not None:
        end = watch.end
        failure = _doubt(request, watch)
        if not failure:
            page = end.get("page")
            return SupervisedRun(end["exit"], True, "", _seconds(end.get("wall")),
                                 _seconds(end.get("cpu")), page if isinstance(page, str) else None)
    if failure == "interrupted" or (interrupted and code in (EXIT_INTERRUPTED, -signal.SIGINT)):
        reason = "interrupted by the user (output incomplete)"
        _write_failure(request, watch, "interrupted", reason)
        return SupervisedRun(EXIT_INTERRUPTED, False, reason)
    if not failure:
        if watch.crash:
            failure = (f"the simulation process failed {watch.at()}: {watch.crash} (an "
                       f"internal error of REI: please report it with {INTERNAL_ERROR_LOG} "
                       f"and the command line)")
        elif code < 0:
            failure = f"the simulation process was killed by {_signal_name(-code)} {watch.at()}"
        else:
            failure = (f"the simulation process exited with status {code} {watch.at()} "
                       f"without a result (did the controller end the process?)")
    _write_failure(request, watch, "error", failure)
    return SupervisedRun(EXIT_RUN_ERROR, False, failure)


def _seconds(value: Any) -> float:
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else 0.0


def _doubt(request: RunRequest, watch: _Watch) -> str:
    """Why the end the child reported cannot be taken as the run's result ("" when it can).

    The report comes over a pipe and summary.json from a folder the process under test could
    reach, so neither is taken on trust: the status must be one `rei run` gives, invalid input
    can only be found before the run starts, and a run that ran must leave exactly the
    summary.json whose digest it reported — a missing or rewritten one is a run error, never
    the verdict it claims."""
    assert watch.end is not None
    status = watch.end.get("exit")
    if not isinstance(status, int) or isinstance(status, bool) or status not in (0, 1, 2, 3, 130):
        return (f"the simulation process reported an exit status `rei run` never gives "
                f"{watch.at()}: {status!r}")
    if status == 2:
        return "" if watch.phase == "setup" else (
            f"the simulation process reported invalid input {watch.at()}, after the run had "
            f"started")
    if status == EXIT_INTERRUPTED and watch.phase == "setup":
        return ""  # stopped before anything ran: there is no summary to check
    digest = watch.end.get("summary_sha256")
    try:
        written = (Path(request.output) / "summary.json").read_bytes()
    except OSError:
        return f"the simulation process ended {watch.at()} without leaving its summary.json"
    if not isinstance(digest, str) or hashlib.sha256(written).hexdigest() != digest:
        return (f"summary.json is not the one the run wrote {watch.at()} (changed or replaced "
                f"after it was written)")
    return ""


def _write_failure(request: RunRequest, watch: _Watch, outcome: str, reason: str) -> None:
    """summary.json for a child that could not write its own, and the end of run.log."""
    from rei.generators.output import append_output  # noqa: PLC0415
    from rei.runtime.observation.evaluator.summary import (  # noqa: PLC0415  (heavy package)
        write_summary,
    )
    from rei.runtime.results import RESULTS_VERSION, RunSummary  # noqa: PLC0415

    out = Path(request.output)
    when = watch.time if watch.time is not None else 0.0
    mission = watch.mission or Path(request.mission).stem
    summary = RunSummary(RESULTS_VERSION, mission, watch.room, request.seed, request.controller,
                         "error" if outcome == "error" else "interrupted", reason, when, 0.0,
                         {}, (), {"incomplete": True})
    out.mkdir(parents=True, exist_ok=True)
    write_summary(summary, out)
    try:
        with append_output(out / "run.log") as log:
            log.write(f"t={when:9.3f}  {outcome}: {reason}\n")
    except OSError:
        pass  # the summary says it; the log is a courtesy


class _Channel:
    """The child's end of the pipe: one JSON line per report."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.broken = False

    def send(self, message: dict[str, Any]) -> None:
        if self.broken:
            return
        data = (json.dumps(message, allow_nan=False) + "\n").encode()
        try:
            os.write(self.fd, data)
        except OSError:
            # The supervisor is gone (killed): end the run the way Ctrl-C does.
            self.broken = True
            raise KeyboardInterrupt from None

    def begin(self, mission: str, room: str) -> None:
        self.send({"begin": {"mission": mission, "room": room}})

    def tick(self, time: float) -> None:
        self.send({"t": time if math.isfinite(time) else 0.0})

    def end(self, time: float) -> None:
        self.send({"end": time})


INTERNAL_ERROR_LOG = "internal-error.txt"


def _save_traceback(out_dir: Path, exc: BaseException) -> str:
    """Write the traceback of an internal error beside the outputs (for a bug report); what
    to tell the user about it."""
    import traceback  # noqa: PLC0415

    from rei.generators.output import open_output  # noqa: PLC0415

    try:
        with open_output(out_dir / INTERNAL_ERROR_LOG) as log:
            log.write("".join(traceback.format_exception(exc)))
    except OSError as err:
        return f"its traceback could not be saved ({err.strerror})"
    return f"please report it with {out_dir / INTERNAL_ERROR_LOG} and the command line"


def child_main(argv: list[str], work: ChildWork) -> int:
    """The child: do ``work`` on the request, report to the supervisor, return the exit
    status.
    ``argv``: the pipe's descriptor, the request, and the folder for temporary files that
    the supervisor removes (optional)."""
    fd, text = int(argv[0]), argv[1]
    if len(argv) > 2:
        # Every temporary file of the run (and of the processes it starts) in the folder the
        # supervisor removes whatever way this process ends.
        os.environ["TMPDIR"] = tempfile.tempdir = argv[2]
    keep_private()  # the robot under test cannot reach this pipe through /proc
    one_math_thread(os.environ)  # before numpy is imported; the campaign's runs have it too
    channel = _Channel(fd)
    from rei.lang.errors import LanguageError, ReiError, printable_lines  # noqa: PLC0415

    request = RunRequest.from_json(text)
    result: dict[str, Any] = {}
    try:
        status, result = work(request, channel)
    except LanguageError as exc:
        for diagnostic in exc.diagnostics:
            print(diagnostic, file=sys.stderr)
        status = 2
    except ReiError as exc:
        print(f"rei run: error: {printable_lines(str(exc))}", file=sys.stderr)
        status = 2
    except KeyboardInterrupt:
        if not channel.broken:
            print("rei run: interrupted", file=sys.stderr)
        status = EXIT_INTERRUPTED
    except BaseException as exc:  # noqa: BLE001  (an internal error: reported, never a traceback)
        saved = _save_traceback(Path(request.output), exc)
        print(f"rei run: internal error: {type(exc).__name__}: {exc}; {saved}",
              file=sys.stderr)
        try:
            channel.send({"crash": f"{type(exc).__name__}: {exc}"})
        except KeyboardInterrupt:
            pass
        return EXIT_RUN_ERROR
    try:
        channel.send({"exit": status, **result})
    except KeyboardInterrupt:
        pass
    return status
