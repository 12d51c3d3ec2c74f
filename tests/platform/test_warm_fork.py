"""A forked child (rei.runtime.platform.fork) is set up as an executed child would be.

Each test forks from a fresh single-threaded interpreter (a test runner's process may hold
threads — xdist's channel, numpy's — and then forking is rightly refused): the test's code
runs there and reports what it saw as JSON on its stdout."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import pytest

from rei.runtime.platform.warm import WARM_VARIABLE

SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux only")

PRELUDE = """
import atexit, json, os, signal, subprocess, sys, threading, time
from pathlib import Path
from rei.runtime.platform.processes import child_status, start_child, stop_child
from rei.runtime.platform.fork import ForkedChild, can_fork
assert can_fork() or os.environ.get("REI_WARM") == "off", "a fresh interpreter may fork"
result = {}
"""


def in_fresh_process(code: str, tmp: Path, **env: str) -> dict[str, Any]:
    """Run ``code`` (after PRELUDE, with ``tmp`` as ``tmp``) in a fresh interpreter; the
    ``result`` it fills in."""
    program = PRELUDE + f"tmp = Path({str(tmp)!r})\n" + textwrap.dedent(code) + \
        "\nprint(json.dumps(result))\n"
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          env={**os.environ, **env}, timeout=SAFETY_LIMIT, check=False)
    assert done.returncode == 0, done.stderr
    answer: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return answer


def test_the_child_runs_the_function_and_exits_with_its_status(tmp_path: Path) -> None:
    result = in_fresh_process("""
        with (tmp / "out.txt").open("wb") as stream:
            child = start_child(["false"], stdout=stream,
                                warm=lambda: print(f"forked {os.getpid()}") or 7)
        result["forked"] = isinstance(child, ForkedChild)  # not the argv
        result["status"] = child.wait(timeout=600)
        result["pid"] = child.pid
    """, tmp_path)
    assert result["forked"] and result["status"] == 7
    assert (tmp_path / "out.txt").read_text() == f"forked {result['pid']}\n"


@pytest.mark.parametrize(("entry", "status"), [
    ("raise SystemExit(3)", 3),
    ("raise SystemExit('bad')", 1),
    ("raise ValueError('boom')", 1),
    ("os._exit(5)", 5),
    ("os.kill(os.getpid(), signal.SIGKILL)", -signal.SIGKILL),
    ("raise KeyboardInterrupt", -signal.SIGINT),
])
def test_the_status_is_the_one_an_interpreter_would_give(tmp_path: Path, entry: str,
                                                         status: int) -> None:
    result = in_fresh_process(f"""
        def run():
            {entry}
        child = start_child(["false"], stderr=subprocess.DEVNULL, warm=run)
        result["status"] = child.wait(timeout=600)
    """, tmp_path)
    assert result["status"] == status
    # executed the same way, the same status
    cold = subprocess.run([sys.executable, "-c", f"import os, signal\n{entry}"],
                          stderr=subprocess.DEVNULL, check=False)
    assert cold.returncode == status


def test_the_child_holds_only_its_streams_and_pass_fds(tmp_path: Path) -> None:
    result = in_fresh_process("""
        # e.g. the supervisor's pipe, not for the child; numbered apart from what the child
        # opens itself (the listing below takes the lowest free number)
        secret_read, secret_write = (os.dup2(fd, 40 + i) for i, fd in enumerate(os.pipe()))
        given_read, given_write = os.pipe()
        def run():
            (tmp / "fds.txt").write_text(" ".join(os.listdir("/proc/self/fd")))
            return 0
        child = start_child(["false"], pass_fds=(given_write,), warm=run)
        assert child.wait(timeout=600) == 0
        result.update(secret=[secret_read, secret_write], given=given_write)
    """, tmp_path)
    held = {int(fd) for fd in (tmp_path / "fds.txt").read_text().split()}
    assert not held & set(result["secret"])
    assert result["given"] in held
    assert len(held - {0, 1, 2, result["given"]}) <= 1, held  # the listing's own


def test_the_child_leads_its_own_group_and_runs_its_own_exit_handlers_only(
        tmp_path: Path) -> None:
    in_fresh_process("""
        atexit.register(lambda: (tmp / "parent-handler-ran").write_text("in the child"))
        def run():
            atexit.register(lambda: (tmp / "child-handler-ran").write_text("ran"))
            (tmp / "groups.txt").write_text(f"{os.getpgid(0)} {os.getpid()}")
            return 0
        child = start_child(["false"], warm=run)
        assert child.wait(timeout=600) == 0
        assert not (tmp / "parent-handler-ran").exists()
    """, tmp_path)
    group, pid = (tmp_path / "groups.txt").read_text().split()
    assert group == pid  # its own process group
    assert (tmp_path / "child-handler-ran").read_text() == "ran"
    # written by the parent at its own exit, after the check above that the child had not
    assert (tmp_path / "parent-handler-ran").read_text() == "in the child"


def test_stop_child_kills_what_the_forked_child_started(tmp_path: Path) -> None:
    result = in_fresh_process("""
        pid_file = tmp / "grandchild.pid"
        def run():
            sleeper = subprocess.Popen(["sleep", "600"])
            pid_file.write_text(str(sleeper.pid))
            sleeper.wait()
            return 0
        child = start_child(["false"], warm=run)
        while not pid_file.exists() or not pid_file.read_text():
            assert child_status(child) is None
            time.sleep(0.01)
        result["status"] = stop_child(child)
        result["grandchild"] = int(pid_file.read_text())
    """, tmp_path)
    assert result["status"] == -signal.SIGKILL
    grandchild = result["grandchild"]
    deadline = time.monotonic() + SAFETY_LIMIT
    while running(grandchild, b"sleep\0600\0"):  # the group was killed with the child
        assert time.monotonic() < deadline, "the forked child's child still runs"
        time.sleep(0.05)


def running(pid: int, cmdline: bytes) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        return state != "Z" and Path(f"/proc/{pid}/cmdline").read_bytes() == cmdline
    except (OSError, IndexError):
        return False


def test_with_a_thread_alive_or_warm_off_the_child_is_executed(tmp_path: Path) -> None:
    code = """
        release = threading.Event()
        thread = threading.Thread(target=release.wait)
        if os.environ.get("REI_WARM") != "off":
            thread.start()
        child = start_child([sys.executable, "-c", "raise SystemExit(4)"], warm=lambda: 9)
        release.set()
        result["executed"] = isinstance(child, subprocess.Popen)
        result["status"] = child.wait(timeout=600)
    """
    with_thread = in_fresh_process(code, tmp_path)
    assert with_thread == {"executed": True, "status": 4}
    warm_off = in_fresh_process(code, tmp_path,
                                **{WARM_VARIABLE: "off"})
    assert warm_off == {"executed": True, "status": 4}


def test_a_child_stopped_at_once_after_the_fork_is_killed_not_waited_for(tmp_path: Path) -> None:
    # The child sets its own process group when it first runs; until then a killpg by the
    # parent found no group (ESRCH, ignored) and stop_child waited for the child's whole life,
    # then reported its normal exit. The parent now sets the group as well, before returning.
    result = in_fresh_process("""
        statuses = []
        for _ in range(10):
            child = start_child(["false"], stderr=subprocess.DEVNULL,
                                warm=lambda: time.sleep(30) or 0)
            stop_child(child)
            statuses.append(child.returncode)
        result["statuses"] = statuses
    """, tmp_path)
    assert result["statuses"] == [-signal.SIGKILL] * 10, result["statuses"]


def test_stderr_pipe_is_refused_rather_than_broken() -> None:
    from rei.runtime.platform.fork import fork_child

    with pytest.raises(ValueError, match="stderr=PIPE"):
        fork_child(lambda: 0, stderr=subprocess.PIPE)
