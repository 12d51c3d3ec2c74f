"""A `rei run` killed with SIGKILL leaves its scratch folder only until the next one starts.

The supervisor removes its children's scratch folder however they end, but nothing of it runs
when it is killed with SIGKILL itself. The folder's name says which process owns it
(rei.runtime.platform.scratch) and the next supervisor sweeps those whose owner is gone — never one
whose owner is alive, another user's, or anything that is not such a folder.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rei.runtime.platform.scratch import make_scratch, pid_namespace, start_ticks, sweep_stale
from rei.runtime.runs.supervisor import SCRATCH_PREFIX
from tests.conftest import EXAMPLES, REPO

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"
SAFETY_LIMIT = 600.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="owners are told apart by /proc/PID/stat (Linux)")


def owned_name(pid: int, start: int, space: int | None = None) -> str:
    """A folder's name as make_scratch gives it (in this pid namespace unless ``space``)."""
    return f"{SCRATCH_PREFIX}{pid}-{start}-{pid_namespace() if space is None else space}-ab_12"


def waiting_process() -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-c", "import signal; signal.pause()"])


def ended_process() -> tuple[int, int]:
    """The pid and start time of a process that has ended and been reaped."""
    child = waiting_process()
    start = start_ticks(child.pid)
    assert start is not None
    child.kill()
    child.wait()
    return child.pid, start


def test_the_folder_names_its_living_owner(tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    folder = Path(make_scratch(SCRATCH_PREFIX))
    assert folder.parent == tmp_path
    assert folder.name.startswith(f"{SCRATCH_PREFIX}{os.getpid()}-{start_ticks(os.getpid())}-"
                                  f"{pid_namespace()}-")
    assert sweep_stale(SCRATCH_PREFIX, str(tmp_path)) == []  # its owner (this test) runs
    assert folder.is_dir()


def test_folders_of_ended_owners_are_swept_and_no_other(tmp_path: Path) -> None:
    pid, start = ended_process()
    me = start_ticks(os.getpid())
    assert me is not None
    stale = tmp_path / owned_name(pid, start)
    reused = tmp_path / owned_name(os.getpid(), me + 1)  # this pid, started at another time
    live = tmp_path / owned_name(os.getpid(), me)
    unowned = tmp_path / f"{SCRATCH_PREFIX}k2j4_x9a"  # an older REI's: no owner to check
    space = pid_namespace()
    assert space is not None
    # A container sharing the folder: its pids are not this namespace's, its owner unseen.
    elsewhere = tmp_path / owned_name(pid, start, space + 1)
    other_prefix = tmp_path / f"rei-controller-{pid}-{start}-abcd_123"
    a_file = tmp_path / owned_name(pid, start + 1)
    target = tmp_path / "kept"
    link = tmp_path / owned_name(pid, start + 2)
    for folder in (stale, reused, live, unowned, elsewhere, other_prefix, target):
        folder.mkdir()
        (folder / "inside.txt").write_text("x")
    a_file.write_text("x")
    link.symlink_to(target)

    removed = sweep_stale(SCRATCH_PREFIX, str(tmp_path))

    assert sorted(removed) == sorted([stale, reused])
    assert not stale.exists() and not reused.exists()
    for kept in (live, unowned, elsewhere, other_prefix, target):
        assert (kept / "inside.txt").read_text() == "x"
    assert a_file.read_text() == "x" and link.is_symlink()


def test_a_zombie_owner_is_gone(tmp_path: Path) -> None:
    """Killed but not yet reaped by its parent: it runs nothing, its folder goes."""
    child = waiting_process()
    try:
        start = start_ticks(child.pid)
        assert start is not None
        folder = tmp_path / owned_name(child.pid, start)
        folder.mkdir()
        os.kill(child.pid, signal.SIGKILL)
        while start_ticks(child.pid) is not None:  # until the kernel has made it a zombie
            time.sleep(0.01)
        assert Path(f"/proc/{child.pid}").exists()  # not reaped: still in the process table
        assert sweep_stale(SCRATCH_PREFIX, str(tmp_path)) == [folder]
        assert not folder.exists()
    finally:
        child.kill()
        child.wait()


@pytest.mark.skipif(os.geteuid() != 0, reason="giving a folder to another user needs root")
def test_another_users_folder_is_never_swept(tmp_path: Path) -> None:
    pid, start = ended_process()
    theirs = tmp_path / owned_name(pid, start)
    theirs.mkdir()
    os.chown(theirs, 65534, 65534)
    assert sweep_stale(SCRATCH_PREFIX, str(tmp_path)) == []
    assert theirs.is_dir()


def rei_run(out: Path, temporary: Path, duration: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "rei.runtime.commands", "run", str(NAVIGATION), "-o", str(out),
         "--duration", duration, "--quiet"],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        env={**os.environ, "TMPDIR": str(temporary)})


@pytest.mark.slow
def test_the_next_run_sweeps_the_folder_of_a_run_killed_with_sigkill(tmp_path: Path) -> None:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    killed = rei_run(tmp_path / "killed", temporary, "30")
    try:
        deadline = time.monotonic() + SAFETY_LIMIT
        while not list(temporary.glob(f"{SCRATCH_PREFIX}*")):
            assert killed.poll() is None, "the run ended before making its scratch folder"
            assert time.monotonic() < deadline, "no scratch folder appeared"
            time.sleep(0.05)
    finally:
        killed.kill()  # SIGKILL: the supervisor removes nothing
        killed.communicate()
    [left] = temporary.glob(f"{SCRATCH_PREFIX}*")
    assert left.name.startswith(f"{SCRATCH_PREFIX}{killed.pid}-")
    assert left.is_dir()  # what the sweep is for: nothing else removes it
    me = start_ticks(os.getpid())
    assert me is not None
    live = temporary / owned_name(os.getpid(), me)
    live.mkdir()

    following = rei_run(tmp_path / "next", temporary, "0.5")
    _, stderr = following.communicate(timeout=SAFETY_LIMIT)
    assert following.returncode in (0, 1), stderr.decode()
    assert not left.exists()
    assert sorted(temporary.iterdir()) == [live]  # its own removed too, the live one kept
