"""Running one planned run in isolation: `rei run` in its own process, under a watchdog.

Both engines call ``execute_run``: the local engine in a thread of the campaign process, the
Dask engine on a cluster worker. The run's process may crash, hang or be killed; whatever
happens becomes a ``RunResult`` (never an exception), so one bad run never stops a campaign.
This module must never write outside the work folder it is given, and never touch the store.
The run's temporary files go into that folder too (``RUN_TEMPORARY``, the run's ``TMPDIR``),
removed however the run ended: a `rei run` the watchdog kills with SIGKILL cannot clean up.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Literal

from rei.generators.output import open_output
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.platform.processes import (
    Child,
    child_status,
    one_math_thread,
    start_child,
    stop_child,
)
from rei.runtime.platform.warm import warm_enabled
from rei.runtime.results import RunSummary
from rei.runtime.runs.cache import CACHE_VARIABLE
from rei.runtime.runs.fork_server import TEMPORARY_VARIABLE, WarmRun, WarmWorkers

RunStatus = Literal["ran", "crashed", "hung", "interrupted"]
"""ran: `rei run` ended by itself and wrote a summary; crashed: it died by a signal from
anyone but the campaign (SIGKILL from a user or the out-of-memory killer, SIGSEGV, ...) or
ended without a valid summary; hung: the watchdog killed it; interrupted: the campaign itself
stopped it (Ctrl-C of the campaign, or it is ending), so it is not recorded and runs again when
the campaign resumes. Only the campaign's own decision makes a run interrupted: anything else
is a finished run, recorded once, so a run that always dies never keeps a campaign open."""

DEFAULT_RUNNER: tuple[str, ...] = (sys.executable, "-m", "rei.runtime.commands")
"""The program that runs one mission; `run MISSION -o DIR ...` is appended."""

POLL_SECONDS = 0.1
"""How often the watchdog looks at a running run (and at the campaign's stop request)."""


@dataclass(frozen=True)
class RunResult:
    """What one attempt of a run produced, before the store records it."""

    run_id: str
    status: RunStatus
    exit_code: int | None
    wall_time: float
    summary: dict[str, Any] | None
    """summary.json as written by `rei run` (a RunSummary), when there is one."""
    message: str = ""
    """Why a run crashed or hung: the watchdog's note or the last lines of its error output."""
    files: dict[str, bytes] = field(default_factory=dict)
    """The run folder's files, when the run happened on another machine (Dask engine)."""


def default_timeout(spec: RunSpec) -> float:
    """Wall-clock seconds before the watchdog kills a run that has not ended."""
    if spec.duration is not None:
        return max(60.0, 10.0 * spec.duration + 30.0)
    return 1800.0


def _tail(path: Path, lines: int = 8) -> str:
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    return "\n".join(text.strip().splitlines()[-lines:])


def death_reason(code: int) -> str:
    """Words for a negative exit status: ``killed by signal 9 (SIGKILL; out of memory?)``."""
    number = -code
    try:
        name = signal.Signals(number).name
    except ValueError:
        name = "an unknown signal"
    # Nothing in a run sends itself SIGKILL: a user did, or the kernel's out-of-memory killer.
    hint = "; out of memory?" if number == signal.SIGKILL else ""
    return f"killed by signal {number} ({name}{hint})"


def _read_summary(path: Path) -> tuple[dict[str, Any] | None, str]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        RunSummary.from_json(data)  # the shape is checked here, not when the report is built
    except FileNotFoundError:
        return None, "no summary.json"
    except (OSError, ValueError, TypeError, KeyError) as exc:
        return None, f"summary.json is unreadable: {exc}"
    if not isinstance(data, dict):
        return None, "summary.json is not an object"
    return data, ""


def execute_run(spec: RunSpec, work_dir: Path, *, timeout: float | None = None,
                runner: Sequence[str] = DEFAULT_RUNNER,
                stop: threading.Event | None = None, cache: Path | None = None,
                warm: WarmWorkers | None = None, pages: str = "all") -> RunResult:
    """Run ``spec`` with its output in ``work_dir`` (created); kill it after ``timeout`` s.
    ``cache``: the run reuses generated worlds and automata from there (rei.runtime.runs.cache).
    ``warm``: the `rei run` process is forked by this thread's fork server, its imports done
    (rei.runtime.runs.fork_server), when the runner is REI's own and REI_WARM is not off; the
    same process otherwise, and watched, killed and judged the same way.
    ``pages``: `rei run --page` (rei.runtime.results.PAGE_POLICIES), "all" as `rei run`.

    Setting ``stop`` kills the run at once and reports it interrupted (the campaign is ending);
    nothing else makes a run interrupted. On Linux the run dies with the calling thread, so
    call this from a thread that lives until it returns (both engines do: the thread waits).
    """
    work_dir.mkdir(parents=True, exist_ok=True)
    temporary = work_dir / RUN_TEMPORARY
    temporary.mkdir(mode=0o700, exist_ok=True)
    try:
        return _execute(spec, work_dir, temporary, timeout, runner, stop, cache, warm, pages)
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


RUN_TEMPORARY = ".tmp"
"""The folder of a run's temporary files inside its work folder (its ``TMPDIR``)."""


def _execute(spec: RunSpec, work_dir: Path, temporary: Path, timeout: float | None,
             runner: Sequence[str], stop: threading.Event | None, cache: Path | None,
             warm: WarmWorkers | None, pages: str) -> RunResult:
    limit = default_timeout(spec) if timeout is None else timeout
    argv = [*runner, *spec.run_argv(str(work_dir)), *page_argv(pages)]
    with open_output(work_dir / "campaign-stdout.txt", binary=True) as out, \
            open_output(work_dir / "campaign-stderr.txt", binary=True) as err:
        # Its own process group and death with this thread (rei.runtime.platform.processes): Ctrl-C
        # reaches the campaign, which stops the runs; kill -9 of the campaign kills them too
        # (a warm run dies with its fork server, which dies with this thread).
        env = run_environment(cache)
        env[TEMPORARY_VARIABLE] = str(temporary.resolve())
        process = _start(argv, env, out, err, warm if tuple(runner) == DEFAULT_RUNNER
                         and warm_enabled(env) else None)
        # The watchdog counts from here: starting (or replacing) a worker's fork server is
        # the campaign's cost, not the run's, and must not make a run look hung.
        started = time.monotonic()
        try:
            code = process.status()
            while code is None:
                if stop is not None and stop.is_set():
                    process.stop()
                    return RunResult(spec.run_id, "interrupted", None,
                                     time.monotonic() - started, None,
                                     "stopped by the campaign")
                if time.monotonic() - started > limit:
                    process.stop()
                    return RunResult(spec.run_id, "hung", None, time.monotonic() - started,
                                     None, f"watchdog: no result after {limit:g} s wall-clock; "
                                           f"killed")
                if stop is not None:
                    stop.wait(POLL_SECONDS)
                else:
                    time.sleep(POLL_SECONDS)
                code = process.status()
        except BaseException:
            process.stop()  # the campaign is stopping: never leave a run behind
            raise
    wall = time.monotonic() - started
    if code < 0:
        # Whoever sent it, it was not the campaign (that case returned above): the run is over.
        detail = _tail(work_dir / "campaign-stderr.txt")
        lost = (" (its warm worker, the fork server, died, and the run with it)"
                if isinstance(process, WarmRun) and process.lost else "")
        return RunResult(spec.run_id, "crashed", code, wall, None,
                         death_reason(code) + lost + (f": {detail}" if detail else ""))
    summary, problem = _read_summary(work_dir / "summary.json")
    if summary is None:
        detail = _tail(work_dir / "campaign-stderr.txt")
        return RunResult(spec.run_id, "crashed", code, wall, None,
                         f"exit status {code}, {problem}" + (f": {detail}" if detail else ""))
    return RunResult(spec.run_id, "ran", code, wall, summary, "")


def page_argv(pages: str) -> list[str]:
    """The `rei run` option for ``pages``: none for "all" (its default, and the same command
    line campaigns gave before the option existed)."""
    return [] if pages == "all" else ["--page", pages]


class _ColdRun:
    """A run started as a fresh interpreter, with a ``WarmRun``'s two calls."""

    def __init__(self, process: Child) -> None:
        self.process = process

    def status(self) -> int | None:
        return child_status(self.process)

    def stop(self) -> int:
        return stop_child(self.process)


def _start(argv: list[str], env: dict[str, str], out: IO[bytes], err: IO[bytes],
           warm: WarmWorkers | None) -> WarmRun | _ColdRun:
    """The run's process: forked by this thread's fork server when ``warm`` (and it can),
    else a fresh interpreter; why it could not be warm goes to the run's error output."""
    if warm is not None:
        run, why = warm.start(argv[len(DEFAULT_RUNNER):], env, os.getcwd(), out.fileno(),
                              err.fileno())
        if run is not None:
            return run
        err.write(f"rei campaign: this run starts a fresh interpreter: {why}\n".encode())
        err.flush()
    return _ColdRun(start_child(argv, stdout=out, stderr=err, env=env))


def run_environment(cache: Path | None = None) -> dict[str, str]:
    """The environment of a run: one math-library thread per run unless the user chose
    otherwise (parallel runs each spawning a thread per core would fight over the cores), and
    the campaign's cache of generated artifacts, if any (a user's $REI_CACHE_DIR wins)."""
    env = dict(os.environ)
    one_math_thread(env)
    if cache is not None and not env.get(CACHE_VARIABLE):
        env[CACHE_VARIABLE] = os.path.abspath(cache)
    return env


WARM_ATTRIBUTE = "rei_warm_workers"
"""Where a Dask worker keeps the fork servers of its threads."""


def _dask_worker_warm() -> WarmWorkers | None:
    """The fork servers of the Dask worker running this task (one per worker thread, each
    dying with its thread, as the local engine's), or None outside a Dask worker."""
    try:
        from distributed import get_worker  # noqa: PLC0415
        worker: Any = get_worker()
    except (ImportError, ValueError):
        return None
    # setdefault: one object even when two of the worker's threads ask at once
    warm = vars(worker).setdefault(WARM_ATTRIBUTE, WarmWorkers())
    return warm if isinstance(warm, WarmWorkers) else None


def execute_run_remote(spec: RunSpec, work_dir: str, timeout: float | None = None,
                       runner: Sequence[str] | None = None, pages: str = "all") -> RunResult:
    """The Dask task: run in a private folder on the worker, then deliver the run's files.

    The campaign process creates ``work_dir`` (unique and fresh) before submitting. When this
    machine sees it (the same machine, or a shared file system) the files are moved into it;
    when it has gone meanwhile (the campaign was killed and resumed, which discards unfinished
    attempts) they are dropped; otherwise the result carries them back. Either way only the
    campaign process records runs, and a run orphaned by a killed campaign cannot write into
    a resumed one.
    """
    import shutil  # noqa: PLC0415
    import tempfile  # noqa: PLC0415

    program = runner if runner is not None else DEFAULT_RUNNER
    target = Path(work_dir)
    shared = target.is_dir()
    with tempfile.TemporaryDirectory(prefix="rei-run-") as tmp:
        work = Path(tmp) / spec.run_id
        result = execute_run(spec, work, timeout=timeout, runner=program,
                             warm=_dask_worker_warm(), pages=pages)
        if shared:
            if target.is_dir():
                for entry in sorted(work.iterdir()):
                    shutil.move(entry, target / entry.name)
            return result
        files = {p.relative_to(work).as_posix(): p.read_bytes()
                 for p in sorted(work.rglob("*")) if p.is_file() and not p.is_symlink()}
    return RunResult(result.run_id, result.status, result.exit_code, result.wall_time,
                     result.summary, result.message, files)
