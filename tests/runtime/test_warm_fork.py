"""A forked child (rei.runtime.warm.fork) is set up as an executed child would be.

Each test forks a real child from the test process (single-threaded under ``-n 0`` and in an
xdist worker alike; the tests skip when a thread is alive, since forking is then refused)."""

from __future__ import annotations

import atexit
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rei.runtime.processes import child_status, start_child, stop_child
from rei.runtime.warm import WARM_VARIABLE, warm_enabled
from rei.runtime.warm.fork import ForkedChild, can_fork

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux only")


def forkable() -> None:
    if not can_fork():
        pytest.skip("a thread is alive in the test process: forking is refused here")


def test_the_child_runs_the_function_and_exits_with_its_status(tmp_path: Path) -> None:
    forkable()
    out = tmp_path / "out.txt"
    with out.open("wb") as stream:
        child = start_child(["false"], stdout=stream,
                            warm=lambda: print(f"forked {os.getpid()}") or 7)
    assert isinstance(child, ForkedChild)  # not the argv
    assert child.wait(timeout=SAFETY_LIMIT) == 7
    assert out.read_text() == f"forked {child.pid}\n"


@pytest.mark.parametrize(("entry", "status"), [
    ("raise SystemExit(3)", 3),
    ("raise SystemExit('bad')", 1),
    ("raise ValueError('boom')", 1),
    ("os._exit(5)", 5),
    ("os.kill(os.getpid(), signal.SIGKILL)", -signal.SIGKILL),
    ("raise KeyboardInterrupt", -signal.SIGINT),
])
def test_the_status_is_the_one_an_interpreter_would_give(entry: str, status: int) -> None:
    forkable()

    def run() -> int:
        exec(entry, {"os": os, "signal": signal})  # noqa: S102
        return 0

    child = start_child(["false"], stderr=subprocess.DEVNULL, warm=run)
    assert child.wait(timeout=SAFETY_LIMIT) == status
    # executed the same way, the same status
    cold = subprocess.run([sys.executable, "-c", f"import os, signal\n{entry}"],
                          stderr=subprocess.DEVNULL, check=False)
    assert cold.returncode == status


def test_the_child_holds_only_its_streams_and_pass_fds(tmp_path: Path) -> None:
    forkable()
    secret_read, secret_write = os.pipe()  # e.g. the supervisor's pipe: not for the child
    given_read, given_write = os.pipe()
    report = tmp_path / "fds.txt"
    try:
        def run() -> int:
            report.write_text(" ".join(sorted(os.listdir("/proc/self/fd"), key=int)))
            return 0

        child = start_child(["false"], pass_fds=(given_write,), warm=run)
        assert child.wait(timeout=SAFETY_LIMIT) == 0
    finally:
        for fd in (secret_read, secret_write, given_read, given_write):
            os.close(fd)
    # 0-2, the one passed, and the descriptor listing /proc/self/fd itself
    held = [int(fd) for fd in report.read_text().split()]
    assert secret_read not in held and secret_write not in held
    assert given_write in held
    assert len(set(held) - {0, 1, 2, given_write}) <= 1, held  # the listing's own


def test_the_child_leads_its_own_group_and_runs_its_own_exit_handlers_only(
        tmp_path: Path) -> None:
    forkable()
    parents = tmp_path / "parent-handler-ran"
    mine = tmp_path / "child-handler-ran"
    groups = tmp_path / "groups.txt"

    def parent_handler() -> None:
        parents.write_text("the parent's exit handler ran in the child")

    atexit.register(parent_handler)
    try:
        def run() -> int:
            atexit.register(lambda: mine.write_text("ran"))
            groups.write_text(f"{os.getpgid(0)} {os.getpid()}")
            return 0

        child = start_child(["false"], warm=run)
        assert child.wait(timeout=SAFETY_LIMIT) == 0
    finally:
        atexit.unregister(parent_handler)
    group, pid = groups.read_text().split()
    assert group == pid  # its own process group
    assert mine.read_text() == "ran"
    assert not parents.exists()


def test_stop_child_kills_what_the_forked_child_started(tmp_path: Path) -> None:
    forkable()
    pid_file = tmp_path / "grandchild.pid"

    def run() -> int:
        sleeper = subprocess.Popen(["sleep", "600"])
        pid_file.write_text(str(sleeper.pid))
        sleeper.wait()
        return 0

    child = start_child(["false"], warm=run)
    while not pid_file.exists() or not pid_file.read_text():
        assert child_status(child) is None
    grandchild = int(pid_file.read_text())
    assert stop_child(child) == -signal.SIGKILL
    deadline = time.monotonic() + SAFETY_LIMIT
    while running(grandchild, b"sleep\0600\0"):  # the group was killed with the child
        assert time.monotonic() < deadline, "the forked child's own child still runs"
        time.sleep(0.05)


def running(pid: int, cmdline: bytes) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        return state != "Z" and Path(f"/proc/{pid}/cmdline").read_bytes() == cmdline
    except (OSError, IndexError):
        return False


def test_with_a_thread_alive_or_warm_off_the_child_is_executed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    forkable()
    release = threading.Event()
    thread = threading.Thread(target=release.wait)
    thread.start()
    try:
        child = start_child([sys.executable, "-c", "raise SystemExit(4)"], warm=lambda: 9)
    finally:
        release.set()
        thread.join()
    assert isinstance(child, subprocess.Popen)
    assert child.wait(timeout=SAFETY_LIMIT) == 4
    monkeypatch.setenv(WARM_VARIABLE, "off")
    assert not warm_enabled() and not can_fork()
    child = start_child([sys.executable, "-c", "raise SystemExit(4)"], warm=lambda: 9)
    assert isinstance(child, subprocess.Popen)
    assert child.wait(timeout=SAFETY_LIMIT) == 4
