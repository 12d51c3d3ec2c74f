"""Shared fixtures: the examples, temporary REI files, and real external tools; and how the
suite is spread over parallel workers (pytest-xdist, `bash scripts/test` runs `-n logical`).

A test that needs an external tool (Debian's `ign`, Chromium) is skipped on a developer's
machine that lacks it, but fails in CI (CI=true), where .ci/run installs it: a green CI
never hides a missing install step.

Parallel workers are separate processes, so tests share nothing but the file system and the
machine: write under ``tmp_path`` (each worker has its own), bind port 0 on 127.0.0.1, never a
fixed path or port. In CI (CI=true, or HYPOTHESIS_PROFILE=ci as .ci/run sets) Hypothesis's
property tests draw the same examples on every run (the `ci` profile, derandomized): a CI
landing cannot fail on a new random draw. A developer's run still draws afresh each time,
which is where new counterexamples come from.
A test file runs on one worker (`--dist loadfile`), so a module-scoped
fixture (an expensive run shared by the file's tests) is still made once. (xdist's finer
`--dist loadgroup` would split the files that share nothing, but pytest 9.2 ignores the group
suffix xdist 3.8 writes into node ids, so its groups are not kept together.)
"""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
from collections.abc import Callable, Generator
from pathlib import Path

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI") or os.environ.get("HYPOTHESIS_PROFILE") == "ci":
    settings.load_profile("ci")

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"


def example_files(suffix: str) -> list[Path]:
    return sorted(EXAMPLES.rglob(f"*{suffix}"))


def require_tool(name: str) -> str:
    """The path of an external program; skip (locally) or fail (in CI) when it is missing."""
    path = shutil.which(name)
    if path is None:
        message = f"'{name}' is not installed (.ci/run installs it)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path


CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update")


def chromium(page: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """Headless Chromium (a real browser) on a local page: ``--dump-dom``, ``--screenshot``."""
    program = require_tool("chromium")
    profile = tmp_path / "chromium-profile"
    shutil.rmtree(profile, ignore_errors=True)
    return subprocess.run([program, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args,
                           page.as_uri()], capture_output=True, text=True, timeout=180,
                          check=True)


def made_once(tmp_path_factory: pytest.TempPathFactory, name: str,
              make: Callable[[Path], None]) -> Path:
    """A folder ``make`` fills once per test session, whichever worker asks for it first, for
    expensive real runs that test files on several workers read (a session-scoped fixture alone
    is made once per worker). The workers' temporary folders share a parent: the first worker
    to take the lock there makes the folder, the others wait for it and read it. ``make`` writes
    only into the folder it is given; the tests only read it. If ``make`` fails, the next
    worker that asks tries again (and fails the same way: each reports it)."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    folder = root / f"made-once-{name}"
    with (root / f"made-once-{name}.lock").open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not (folder / ".made").is_file():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (folder / ".made").touch()
    return folder


def slow_tests(items: list[pytest.Item]) -> dict[str, int]:
    """How many tests marked ``slow`` each test file holds."""
    count: dict[str, int] = {}
    for item in items:
        module = item.nodeid.split("::")[0]
        count[module] = count.get(module, 0) + (item.get_closest_marker("slow") is not None)
    return count


@pytest.hookimpl(wrapper=True)  # before every plain hook, xdist's own too
def pytest_collection_modifyitems(config: pytest.Config,
                                  items: list[pytest.Item]) -> Generator[None, None, None]:
    """Under xdist (`bash scripts/test`: `--dist loadfile --no-loadscope-reorder`, each test
    file on one worker, files handed out in collection order): the files with the most slow
    tests come first, so no long file starts last while the other worker idles. Without xdist
    the order is pytest's own."""
    if getattr(config.option, "numprocesses", None) or hasattr(config, "workerinput"):
        slow = slow_tests(items)
        # A stable sort: equal files, and the tests within each file, keep their order.
        items.sort(key=lambda item: -slow[item.nodeid.split("::")[0]])
    return (yield)


@pytest.fixture
def examples_dir() -> Path:
    return EXAMPLES


@pytest.fixture
def write(tmp_path: Path):  # type: ignore[no-untyped-def]
    """Write a file under tmp_path and return its path: write('a.room', text)."""

    def _write(name: str, text: str | bytes) -> Path:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8")
        return path

    return _write

