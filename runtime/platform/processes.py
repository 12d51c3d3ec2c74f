"""Child processes that never outlive the REI process that started them.

`rei campaign` runs each mission as a `rei run` process, and a program may start processes of
its own. When the parent dies — Ctrl-C, a crash, ``kill -9``, the out-of-memory killer — its
children must die too instead of computing (and writing into output folders) unseen. Two
mechanisms, both needed:

* the child asks the kernel to SIGKILL it when its parent dies (Linux ``PR_SET_PDEATHSIG``):
  the only thing that works when the parent is killed with SIGKILL and can clean up nothing.
  The kernel sends it when the *thread* that started the child ends, so ``start_child`` must
  be called from a thread that lives at least as long as the child — the thread that waits
  for it, as every caller here does;
* the child leads its own process group, so ``stop_child`` stops whatever it started too, and
  a terminal's Ctrl-C reaches only the parent, which decides what happens to its children.

``child_status`` tells that a child has ended without reaping it, so its process group id
cannot be reused before the group is swept. Given the function the child runs
(``start_child(..., warm=entry)``) the child is forked instead of executed when that is safe
(``rei.runtime.platform.warm``): the same guarantees, without a fresh interpreter's imports. This
module must never signal a process or a process group it did not start.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Mapping, MutableMapping, Sequence
from typing import IO, Any, Protocol

PR_SET_PDEATHSIG = 1
"""From <linux/prctl.h>."""

Stream = int | IO[bytes] | None


class Child(Protocol):
    """A child started by ``start_child``: a ``subprocess.Popen`` or a forked
    ``rei.runtime.platform.fork.ForkedChild``, both with this much of Popen's interface."""

    pid: int
    returncode: int | None
    stdin: IO[bytes] | None
    stdout: IO[bytes] | None

    def poll(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int: ...


PR_SET_DUMPABLE = 4
"""From <linux/prctl.h>."""


def _prctl() -> Any:
    """libc's prctl(2) with its argument types (Linux)."""
    prctl = ctypes.CDLL(None, use_errno=True).prctl
    prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong,
                      ctypes.c_ulong]
    prctl.restype = ctypes.c_int
    return prctl


THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""The math libraries' thread counts (read when numpy is first imported)."""


def one_math_thread(env: MutableMapping[str, str]) -> None:
    """One math-library thread unless the user chose otherwise: a run's arrays are small,
    parallel runs would each start a thread per core and fight over the cores, and a process
    with such threads alive cannot fork its children warm (rei.runtime.platform.warm)."""
    for name in THREAD_VARIABLES:
        env.setdefault(name, "1")


def keep_private() -> None:
    """Make this process non-dumpable (Linux): other processes of the same user — a robot
    under test among them — can then neither trace it nor open its descriptors through
    /proc/PID/fd (the supervisor's pipe), and it leaves no core file. Elsewhere nothing."""
    if not sys.platform.startswith("linux"):
        return
    _prctl()(PR_SET_DUMPABLE, 0, 0, 0, 0)


def die_with_parent() -> Callable[[], None] | None:
    """A ``preexec_fn`` that has the kernel SIGKILL the child when the thread that started it
    ends; None where there is no such request (not Linux: stop children yourself)."""
    if not sys.platform.startswith("linux"):
        return None
    # Resolved here, in the parent: between fork and exec the child may only call what is
    # ready (no imports, no locks another thread could have held at the fork).
    prctl = _prctl()
    parent = os.getpid()
    kill = int(signal.SIGKILL)

    def preexec() -> None:
        prctl(PR_SET_PDEATHSIG, kill, 0, 0, 0)
        if os.getppid() != parent:  # the parent died before the request took effect
            os.kill(os.getpid(), kill)

    return preexec


def start_child(argv: Sequence[str], *, stdin: Stream = subprocess.DEVNULL,
                stdout: Stream = None, stderr: Stream = None,
                env: Mapping[str, str] | None = None,
                cwd: str | os.PathLike[str] | None = None,
                pass_fds: Sequence[int] = (),
                warm: Callable[[], int | None] | None = None) -> Child:
    """Start ``argv`` as a child that dies with the calling thread (Linux) and leads its own
    process group; end it with ``stop_child``, or wait for it with ``child_status``.

    ``warm``: the function ``argv`` runs, in this process's environment (``env`` None);
    when given and ``rei.runtime.platform.fork.can_fork()`` (Linux, one thread, REI_WARM not
    off), the child is forked and runs it, its imports already done, instead of a fresh
    interpreter — the same child otherwise (``rei.runtime.platform.warm``)."""
    if warm is not None and env is None:
        from rei.runtime.platform.fork import can_fork, fork_child  # noqa: PLC0415

        if can_fork():
            return fork_child(warm, stdin=stdin, stdout=stdout, stderr=stderr, cwd=cwd,
                              pass_fds=pass_fds, die_with_parent=die_with_parent())
    return subprocess.Popen(argv, stdin=stdin, stdout=stdout, stderr=stderr, env=env, cwd=cwd,
                            process_group=0, preexec_fn=die_with_parent(), pass_fds=pass_fds)


def child_status(process: Child) -> int | None:
    """The child's exit status (negative: the signal that ended it) once it has ended, else
    None. Its whole process group is killed then: nothing it started outlives it."""
    if process.returncode is not None:
        return process.returncode
    try:
        # WNOWAIT: the ended child stays a zombie, so its pid (= the group id) is not reused
        # before the group is swept below.
        ended = os.waitid(os.P_PID, process.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT)
    except ChildProcessError:  # already reaped elsewhere: its group id may be reused
        return process.wait()
    if ended is None:
        return None
    _kill_group(process.pid)
    return process.wait()


def stop_child(process: Child) -> int:
    """SIGKILL the child and its process group; its exit status once reaped."""
    if process.returncode is None:
        _kill_group(process.pid)
    return process.wait()


def _kill_group(pgid: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, signal.SIGKILL)
