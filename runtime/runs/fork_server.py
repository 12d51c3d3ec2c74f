"""The fork server of a campaign worker: REI imported once, a fresh `rei run` process per run.

``WarmWorkers`` gives each worker thread of a campaign its own fork server (a "zygote",
``python -m rei.runtime.runs.fork_server``), started by that thread with
``rei.runtime.platform.processes.start_child`` (it dies with the thread, hence with the campaign).
The server imports what a run needs (``PRELOAD``: numpy, pybullet, textX and REI's grammars,
the monitor, the navigator, matplotlib for the run page), then, for each request, forks a
child that is exactly the process `python -m rei.runtime.commands run ...` would have been: own
process group, death with the server (so with the campaign), the run's standard output and
error, environment and working folder, running the program ``PROGRAM`` by name on the run's
arguments. A run is one request at a time over a socket pair (``SOCK_SEQPACKET``: one message
each, the output files' descriptors passed along): the server answers with the child's pid,
kills its process group when asked ("kill"), and answers with its exit status once it has ended (the
group swept first, as ``child_status`` does). So the campaign's watchdog, Ctrl-C and crash
handling see the same process they saw before, only started warm.

Staleness: the server holds imported code and nothing else (no parsed input: the artifact
cache, keyed by content, does that). Before each fork it takes REI's code fingerprint again
(``rei.runtime.runs.cache.code_fingerprint``: every file of REI's packages by size and time) and,
when it changed, refuses with "stale" and ends; a new server is started for the run. A server
that died (killed, out of memory) ends the run it was forking for (its child dies with it),
which is recorded as crashed, and is replaced for the next run. A server that cannot be
started, or fails twice, leaves the run to a fresh interpreter, said in its error output.

This module must never fork with a second thread alive, hold anything of one run for the
next, or signal a process group other than the one of the run it forked and has not reaped.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import importlib
import json
import os
import runpy
import select
import socket
import subprocess
import sys
import tempfile
import threading
from collections.abc import Mapping, Sequence
from typing import Any

from rei.runtime.platform.processes import (
    Child,
    child_status,
    die_with_parent,
    start_child,
    stop_child,
)

PRELOAD = (
    "rei.runtime.commands.cli",
    "rei.runtime.commands.run",
    "rei.runtime.runs.supervisor",
    "rei.runtime.simulation.assembly",
    "rei.runtime.runs.cache",
    "rei.runtime.observation.monitor",
    "rei.runtime.observation.monitor.functions",
    "rei.runtime.trace",
    "rei.runtime.simulation.sampler",
    "rei.runtime.artifacts.monitor_config",
    "rei.runtime.observation.monitor.needs",
    "rei.runtime.observation.evaluator",
    "rei.runtime.simulation.faults.composition",
    "rei.runtime.simulation.faults.configuration",
    "rei.runtime.simulation.world",
    "rei.runtime.simulation.world.start_jitter",
    "rei.runtime.robot.selection",
    "rei.runtime.robot.host",
    "rei.runtime.presentation.run_page.rendering",
    "rei.runtime.presentation.run_page.run_plots",
    "rei.lang.vepl.document",
    "rei.generators.output",
)
"""What `rei run` imports on its way (each: the modules it imports too)."""

LANGUAGES = ("room", "mission", "vepl")
"""textX metamodels built in the server (``rei.lang.parsing.metamodel``: immutable, from
REI's grammars, which the code fingerprint covers)."""

MAX_MESSAGE = 1 << 20
READY_LIMIT = 300.0
"""Wall seconds a new server may take to import everything (a loaded machine is slow)."""
ANSWER_LIMIT = 60.0
"""Wall seconds the server may take to answer a request with the forked pid."""


class WarmUnavailable(Exception):  # noqa: N818  (a condition, handled by starting cold)
    """The fork server cannot start this run (why: the message); start it cold."""


def _send(sock: socket.socket, message: dict[str, Any], fds: Sequence[int] = ()) -> None:
    data = json.dumps(message).encode()
    if fds:
        socket.send_fds(sock, [data], list(fds))
    else:
        sock.send(data)


def _receive(sock: socket.socket, limit: float | None) -> dict[str, Any] | None:
    """The next message (None: the other side is gone); WarmUnavailable past ``limit`` s."""
    if limit is not None:
        ready, _, _ = select.select([sock], [], [], limit)
        if not ready:
            raise WarmUnavailable(f"the fork server did not answer within {limit:g} s")
    try:
        data = sock.recv(MAX_MESSAGE)
    except OSError:
        return None
    if not data:
        return None
    message = json.loads(data)
    return message if isinstance(message, dict) else None


# -- the campaign's side --------------------------------------------------------------------


class ForkServer:
    """One fork server, started by (and dying with) the calling thread."""

    def __init__(self, env: Mapping[str, str]) -> None:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._socket = ours
        try:
            self._process = start_child(
                [sys.executable, "-m", "rei.runtime.runs.fork_server", str(theirs.fileno())],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=dict(env),
                pass_fds=(theirs.fileno(),))
        finally:
            theirs.close()
        self.env = dict(env)
        try:
            ready = _receive(ours, READY_LIMIT)
        except WarmUnavailable:
            self.close()
            raise
        if ready is None or "ready" not in ready:
            self.close()
            why = ready.get("error") if ready is not None else None
            raise WarmUnavailable(f"the fork server did not start ({why or 'it ended'})")

    @property
    def pid(self) -> int:
        return self._process.pid

    def alive(self) -> bool:
        return child_status(self._process) is None

    def spawn(self, args: Sequence[str], env: Mapping[str, str], cwd: str,
              stdout: int, stderr: int) -> WarmRun:
        """Fork `rei run`-as-``args`` (the arguments after ``rei``); WarmUnavailable when
        the server cannot (stale code, a thread alive, dead): it is then closed."""
        try:
            _send(self._socket, {"args": list(args), "env": dict(env), "cwd": cwd},
                  (stdout, stderr))
            answer = _receive(self._socket, ANSWER_LIMIT)
        except (OSError, WarmUnavailable) as exc:
            self.close()
            raise WarmUnavailable(f"the fork server failed: {exc}") from None
        if answer is None or not isinstance(answer.get("pid"), int):
            self.close()
            why = answer.get("refused") if answer is not None else "it ended"
            raise WarmUnavailable(f"the fork server did not start the run ({why})")
        return WarmRun(self, answer["pid"])

    def close(self) -> None:
        """End the server (and a run it is forking for)."""
        with contextlib.suppress(OSError):
            self._socket.close()
        if hasattr(self, "_process"):
            stop_child(self._process)

    def _socket_of(self) -> socket.socket:
        return self._socket


class WarmRun:
    """A run forked by a ``ForkServer``: not this process's child, so it is waited for and
    killed through the server (which alone may reap it, so its pid cannot be reused under
    a kill). ``lost``: the server died, and the run with it."""

    def __init__(self, server: ForkServer, pid: int) -> None:
        self.server = server
        self.pid = pid
        self.returncode: int | None = None
        self.lost = False

    def status(self) -> int | None:
        """The run's exit status once it has ended (negative: a signal), else None."""
        if self.returncode is None:
            self._hear(0.0)
        return self.returncode

    def stop(self) -> int:
        """Kill the run's process group and wait for its status."""
        if self.returncode is None:
            with contextlib.suppress(OSError):
                _send(self.server._socket_of(), {"kill": True})
            while self.returncode is None:
                self._hear(None)
        return self.returncode

    def _hear(self, limit: float | None) -> None:
        sock = self.server._socket_of()
        try:
            ready, _, _ = select.select([sock], [], [], limit)
        except (OSError, ValueError):
            ready = [sock]
        if not ready:
            return
        try:
            message = _receive(sock, None)
        except (OSError, ValueError):
            message = None
        if message is None:  # the server died: the run died with it (PR_SET_PDEATHSIG)
            self.lost = True
            self.returncode = -9
            self.server.close()
        elif isinstance(message.get("exit"), int):
            self.returncode = message["exit"]


TEMPORARY_VARIABLE = "TMPDIR"
"""Where a run makes its temporary files: a folder of its own (rei.runtime.campaigns.execute),
so the only variable of a run's environment that differs from run to run."""


def server_environment(env: Mapping[str, str]) -> dict[str, str]:
    """``env`` as a fork server gets it: the campaign's own temporary folder, not a run's."""
    out = {k: v for k, v in env.items() if k != TEMPORARY_VARIABLE}
    if TEMPORARY_VARIABLE in os.environ:
        out[TEMPORARY_VARIABLE] = os.environ[TEMPORARY_VARIABLE]
    return out


class WarmWorkers:
    """The fork servers of a campaign's worker threads, one per thread, each started by the
    thread that uses it (so it dies with that thread). ``close`` ends them all."""

    def __init__(self) -> None:
        self._local = threading.local()
        self._servers: list[ForkServer] = []
        self._lock = threading.Lock()
        self._cold: dict[tuple[tuple[str, str], ...], str] = {}
        """Why a server could not start, per environment: its runs then start cold at once
        instead of paying for a server's imports again on every run."""

    def start(self, args: Sequence[str], env: Mapping[str, str], cwd: str, stdout: int,
              stderr: int) -> tuple[WarmRun | None, str]:
        """The run forked by this thread's server (started or replaced as needed), or
        (None, why) when it must start cold. The run gets ``env``; the server the same
        without the run's own temporary folder (each run has its own: no reason to replace
        the server), which its child sets."""
        env, run_env = server_environment(env), env
        key = tuple(sorted(env.items()))
        with self._lock:
            known = self._cold.get(key)
        if known is not None:
            return None, known
        why = ""
        for _ in range(2):
            server: ForkServer | None = getattr(self._local, "server", None)
            if server is not None and (server.env != dict(env) or not server.alive()):
                server.close()  # the runs' environment changed (imports saw the old one)
                server = None
            if server is None:
                try:
                    server = ForkServer(env)
                except (OSError, WarmUnavailable) as exc:
                    with self._lock:
                        self._cold[key] = str(exc)
                    return None, str(exc)
                self._local.server = server
                with self._lock:
                    self._servers.append(server)
            try:
                return server.spawn(args, run_env, cwd, stdout, stderr), ""
            except WarmUnavailable as exc:
                why = str(exc)
                self._local.server = None
        return None, why

    def close(self) -> None:
        with self._lock:
            servers, self._servers = self._servers, []
        for server in servers:
            server.close()


# -- the server's side ----------------------------------------------------------------------


def preload() -> None:
    """Import what a run needs and build the languages' metamodels."""
    from rei.runtime.runs.cache import code_fingerprint  # noqa: PLC0415

    for name in PRELOAD:
        importlib.import_module(name)
    from rei.lang.parsing import metamodel  # noqa: PLC0415

    for language in LANGUAGES:
        metamodel(language)
    code_fingerprint()  # cached: the children inherit it (checked fresh before each fork)
    # What is imported now lives as long as the server: out of the collector's sight, so its
    # passes in the children do not touch (and copy) those pages of the shared memory.
    gc.collect()
    gc.freeze()


PROGRAM = "rei.runtime.commands"
"""The program a run is: what `python -m PROGRAM ARGS` runs (the campaign's runner,
rei.runtime.campaigns.execute.DEFAULT_RUNNER). The child runs it by name, as that process
would: this wing never imports the command line."""


def _run(request: dict[str, Any]) -> int:
    """The forked child: `python -m rei.runtime.commands` (`rei`) with the run's arguments,
    environment and folder."""
    os.environ.clear()
    os.environ.update(request["env"])
    tempfile.tempdir = None  # found again from the run's TMPDIR, not the server's
    sys.argv = [PROGRAM, *(str(a) for a in request["args"])]
    try:
        runpy.run_module(PROGRAM, run_name="__main__", alter_sys=True)
    except SystemExit as ended:
        code = ended.code
        if code is None or isinstance(code, int):
            return code or 0
        print(code, file=sys.stderr)
        return 1
    return 0


def serve(sock: socket.socket, fingerprint: str) -> None:
    """Answer requests until the campaign's side is gone."""
    from rei.runtime.platform.fork import fork_child, threads_alive  # noqa: PLC0415
    from rei.runtime.runs.cache import code_fingerprint  # noqa: PLC0415

    while True:
        try:
            data, fds, _, _ = socket.recv_fds(sock, MAX_MESSAGE, 2)
        except OSError:
            return
        if not data:
            return
        try:
            request = json.loads(data)
            if isinstance(request, dict) and request.get("kill") and not fds:
                continue  # a stop that crossed the end of the run it was meant for
            refused = ""
            if code_fingerprint.__wrapped__() != fingerprint:
                refused = "stale: REI's code changed since the server imported it"
            elif threads_alive() != 1:
                refused = "a thread is alive in the fork server"
            elif len(fds) != 2:
                refused = "the run's output descriptors were not passed"
            if refused:
                _send(sock, {"refused": refused})
                return
            child = fork_child(functools.partial(_run, request), stdout=fds[0], stderr=fds[1],
                               cwd=request["cwd"], die_with_parent=die_with_parent())
        finally:
            for fd in fds:
                os.close(fd)
        _send(sock, {"pid": child.pid})
        status = _wait(sock, child)
        if status is None:
            return
        _send(sock, {"exit": status})


def _wait(sock: socket.socket, child: Child) -> int | None:
    """The run's exit status; None when the campaign's side is gone (the run killed)."""
    pidfd = os.pidfd_open(child.pid)
    try:
        while True:
            ready, _, _ = select.select([sock.fileno(), pidfd], [], [])
            if pidfd in ready:
                status = child_status(child)  # its group swept, then reaped
                if status is not None:
                    return status
            if sock.fileno() in ready:
                message = _receive(sock, None)
                if message is None:
                    stop_child(child)
                    return None
                if message.get("kill"):
                    stop_child(child)
                    return child.returncode
    finally:
        os.close(pidfd)


def main(argv: list[str]) -> int:
    sock = socket.socket(fileno=int(argv[0]))
    try:
        preload()
    except Exception as exc:  # noqa: BLE001  (said to the campaign, which starts runs cold)
        with contextlib.suppress(OSError):
            _send(sock, {"error": f"{type(exc).__name__}: {exc}"})
        return 1
    from rei.runtime.platform.fork import can_fork  # noqa: PLC0415
    from rei.runtime.runs.cache import code_fingerprint  # noqa: PLC0415

    if not can_fork():  # e.g. OMP_NUM_THREADS > 1 left a math thread alive after the imports
        with contextlib.suppress(OSError):
            _send(sock, {"error": "this server cannot fork (a thread is alive after its "
                                  "imports, or the kernel lacks pidfd_open)"})
        return 1
    _send(sock, {"ready": os.getpid()})
    serve(sock, code_fingerprint())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
