"""Forking a child that runs a Python function, set up as an executed child would be.

``fork_child`` is what ``rei.runtime.platform.processes.start_child`` does instead of executing a
new
interpreter when it is given the child's entry function and ``can_fork()`` says yes. The child
gets what an executed child gets and nothing of its parent's it was not given: its own
process group, death with the thread that started it (Linux ``PR_SET_PDEATHSIG``), standard
streams as asked, the descriptors of ``pass_fds`` and no other (a forked host must not hold the
supervisor's pipe), its working folder, default signal dispositions, and none of its parent's
exit handlers (a parent's temporary folder is the parent's to remove). It runs the entry
function, then its own exit handlers, and ends with ``os._exit``: it never returns into the
code that forked it. Only a process with a single thread may fork (another thread's locks
would be held forever in the child): ``can_fork`` checks the kernel's count, not Python's.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import os
import select
import signal
import subprocess
import sys
import traceback
import weakref
from collections.abc import Callable, Mapping, Sequence
from typing import IO, Any

from rei.runtime.platform.warm import warm_enabled

Stream = int | IO[bytes] | None

EXIT_UNCAUGHT = 1
"""The status of a child whose entry raised (as an interpreter's uncaught exception)."""


def threads_alive() -> int:
    """Threads of this process, as the kernel counts them (native ones included)."""
    try:
        return len(os.listdir("/proc/self/task"))
    except OSError:
        return 0  # unknown: treated as unsafe below


def can_fork(env: Mapping[str, str] | None = None) -> bool:
    """Whether a warm child may be forked here: Linux (where the rest of ``start_child``'s
    guarantees hold) with ``pidfd_open`` (a forked child is waited for through it: Linux
    5.3, and not refused by a container's seccomp profile), warm processes not turned off,
    and this process single-threaded."""
    return (sys.platform.startswith("linux") and warm_enabled(env) and pidfd_supported()
            and threads_alive() == 1)


_PIDFD: list[bool] = []
"""pidfd_supported's answer, found once per process."""


def pidfd_supported() -> bool:
    """Whether ``os.pidfd_open`` works here (tried on this process itself, once)."""
    if not _PIDFD:
        try:
            os.close(os.pidfd_open(os.getpid()))
            _PIDFD.append(True)
        except (AttributeError, OSError):
            _PIDFD.append(False)
    return _PIDFD[0]


class ForkedChild:
    """A forked child, with the part of ``subprocess.Popen``'s interface REI uses: ``pid``,
    ``returncode`` (negative: the signal that ended it), ``stdin``/``stdout`` (with PIPE),
    ``poll`` and ``wait``."""

    def __init__(self, pid: int, stdin: IO[bytes] | None, stdout: IO[bytes] | None) -> None:
        self.pid = pid
        self.stdin = stdin
        self.stdout = stdout
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            with contextlib.suppress(ChildProcessError):
                pid, status = os.waitpid(self.pid, os.WNOHANG)
                if pid == 0:
                    return None
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is not None:
            return self.returncode
        if timeout is not None:
            pidfd = os.pidfd_open(self.pid)
            try:
                ready, _, _ = select.select([pidfd], [], [], max(0.0, timeout))
            finally:
                os.close(pidfd)
            if not ready:
                raise subprocess.TimeoutExpired(f"forked child {self.pid}", timeout)
        try:
            _, status = os.waitpid(self.pid, 0)
        except ChildProcessError:  # reaped elsewhere: its status is lost
            self.returncode = -signal.SIGKILL
        else:
            self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode


def _resolve(stream: Stream, default: int, reading: bool,
             opened: list[int]) -> tuple[int, int | None]:
    """(descriptor for the child, the parent's end of a pipe or None)."""
    if stream is None:
        return default, None
    if stream == subprocess.DEVNULL:
        fd = os.open(os.devnull, os.O_RDONLY if reading else os.O_WRONLY)
        opened.append(fd)
        return fd, None
    if stream == subprocess.PIPE:
        read_end, write_end = os.pipe()
        child, parent = (read_end, write_end) if reading else (write_end, read_end)
        opened.append(child)
        return child, parent
    if isinstance(stream, int):
        return stream, None
    return stream.fileno(), None


def fork_child(entry: Callable[[], int | None], *, stdin: Stream = subprocess.DEVNULL,
               stdout: Stream = None, stderr: Stream = None,
               cwd: str | os.PathLike[str] | None = None, pass_fds: Sequence[int] = (),
               die_with_parent: Callable[[], None] | None = None) -> ForkedChild:
    """Fork a child that runs ``entry()`` (its return value, or SystemExit's, is the exit
    status); call only when ``can_fork()``. Streams are as ``subprocess.Popen``'s (None:
    inherited, DEVNULL, PIPE, a descriptor or a file); ``die_with_parent`` is the
    ``preexec_fn`` of ``rei.runtime.platform.processes.die_with_parent``, resolved by the caller."""
    if stderr == subprocess.PIPE:
        raise ValueError("fork_child: stderr=PIPE is not supported (nobody reads it)")
    opened: list[int] = []
    parent_ends: list[int | None] = []
    try:
        child_fds = []
        for stream, default, reading in ((stdin, 0, True), (stdout, 1, False),
                                         (stderr, 2, False)):
            fd, parent_end = _resolve(stream, default, reading, opened)
            child_fds.append(fd)
            parent_ends.append(parent_end)
        for text in (sys.stdout, sys.stderr):  # or the child would write it a second time
            with contextlib.suppress(Exception):
                text.flush()
        # Garbage with unflushed buffers is collected (and flushed) here, once, not in the
        # child into descriptors it still shares with this process.
        gc.collect()
        pid = os.fork()
        if pid == 0:
            _child(entry, child_fds, cwd, tuple(pass_fds), die_with_parent)  # never returns
        # Both sides set the child's process group (the child does it too): when this call
        # returns, stop_child's killpg reaches the child even if it has not run yet.
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.setpgid(pid, pid)
    except BaseException:
        for end in parent_ends:
            if end is not None:
                os.close(end)
        raise
    finally:
        for fd in opened:
            os.close(fd)
    stdin_end, stdout_end = parent_ends[0], parent_ends[1]
    return ForkedChild(pid, os.fdopen(stdin_end, "wb") if stdin_end is not None else None,
                       os.fdopen(stdout_end, "rb") if stdout_end is not None else None)


def _child(entry: Callable[[], int | None], fds: list[int], cwd: str | os.PathLike[str] | None,
           pass_fds: tuple[int, ...], die_with_parent: Callable[[], None] | None) -> None:
    """The forked child's whole life: set up as an executed child, run, exit."""
    code: int = EXIT_UNCAUGHT
    try:
        try:
            os.setpgid(0, 0)
            if die_with_parent is not None:
                die_with_parent()
            _forget_exit_handlers()
            _standard_streams(fds, pass_fds)
            if cwd is not None:
                os.chdir(cwd)
            _default_signals()
            code = _status(entry())
        except SystemExit as exc:
            code = _exit_status(exc.code)
        except KeyboardInterrupt:
            # As an interpreter ends on an uncaught Ctrl-C: killed by SIGINT.
            _flush()
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        except BaseException:  # noqa: BLE001  (reported as the interpreter would report it)
            with contextlib.suppress(BaseException):
                traceback.print_exc()
            code = EXIT_UNCAUGHT
        with contextlib.suppress(BaseException):
            atexit._run_exitfuncs()
        _flush()
    finally:
        os._exit(code)


def _status(value: int | None) -> int:
    return 0 if value is None else int(value)


def _exit_status(value: object) -> int:
    """What an interpreter makes of ``sys.exit(value)``."""
    if value is None:
        return 0
    if isinstance(value, int):
        return value & 0xFF
    with contextlib.suppress(BaseException):
        print(value, file=sys.stderr)
    return 1


def _flush() -> None:
    for text in (sys.stdout, sys.stderr):
        with contextlib.suppress(BaseException):
            text.flush()


def _forget_exit_handlers() -> None:
    """Drop the parent's exit handlers and ``weakref.finalize`` hooks in this copy of its
    memory (they clean up the parent's resources), so that only what the child registers
    runs when it ends. ``finalize`` registers its exit hook once per process, hence the
    flag."""
    atexit._clear()
    registry: dict[Any, Any] = getattr(weakref.finalize, "_registry", {})
    for finalizer in list(registry):
        with contextlib.suppress(BaseException):
            finalizer.detach()
    weakref.finalize._registered_with_atexit = False  # type: ignore[attr-defined]
    if "logging" in sys.modules:  # as an interpreter that imported logging has it
        atexit.register(sys.modules["logging"].shutdown)


def _standard_streams(fds: list[int], pass_fds: tuple[int, ...]) -> None:
    """Put the child's streams on 0, 1, 2 and close every other descriptor but ``pass_fds``.

    Cyclic garbage is collected first: a file object of the parent's that becomes garbage
    later would close its descriptor number, by then perhaps one the child opened. What stays
    reachable lives in frames the child never returns to, so it is never closed."""
    gc.collect()
    # Above every descriptor involved, so that no dup2 below overwrites a source.
    low = max([*fds, *pass_fds, 2]) + 1
    moved = [os.dup2(fd, low + i, inheritable=False) for i, fd in enumerate(fds)]
    for target, fd in enumerate(moved):
        os.dup2(fd, target)
    keep = sorted({0, 1, 2, *pass_fds})
    start = 3
    for fd in [*keep[3:], _max_fd()]:
        if fd > start:
            os.closerange(start, fd)
        start = max(start, fd + 1)
    for fd in pass_fds:
        os.set_inheritable(fd, True)
    # A parent may have replaced sys.stdout (a test runner capturing it, the robot's host
    # pointing it at stderr): an interpreter's streams write to 0, 1 and 2.
    for name, fd, mode in (("stdin", 0, "r"), ("stdout", 1, "w"), ("stderr", 2, "w")):
        if _descriptor(getattr(sys, name)) != fd:
            stream = open(fd, mode, closefd=False, encoding="utf-8",  # noqa: SIM115
                          errors="backslashreplace" if fd == 2 else "strict",
                          buffering=1 if fd != 0 else -1)
            setattr(sys, name, stream)
            setattr(sys, f"__{name}__", stream)


def _descriptor(stream: object) -> int | None:
    try:
        return int(stream.fileno())  # type: ignore[attr-defined]
    except (AttributeError, OSError, ValueError):
        return None


def _max_fd() -> int:
    try:
        return int(os.sysconf("SC_OPEN_MAX"))
    except (OSError, ValueError):
        return 65536


def _default_signals() -> None:
    """The dispositions an interpreter starts with (a parent may have set its own)."""
    for number in (signal.SIGTERM, signal.SIGCHLD, signal.SIGHUP, signal.SIGUSR1,
                   signal.SIGUSR2, signal.SIGALRM):
        with contextlib.suppress(OSError, ValueError):
            signal.signal(number, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    with contextlib.suppress(ValueError):
        signal.set_wakeup_fd(-1)
    signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
