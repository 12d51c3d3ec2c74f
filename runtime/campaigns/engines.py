"""Where runs execute: the local engine (worker processes on this machine, nothing to install)
and the Dask engine (a Dask distributed cluster, imported only when asked for).

An engine takes planned runs and hands back one ``RunResult`` per run as each finishes, in the
campaign process, which alone writes the store. Engines must never write the store, and never
raise because one run failed: a crash or a hang is a result.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import threading
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import ModuleType
from typing import Protocol, TypeVar, runtime_checkable

from rei.runtime.campaigns.errors import CampaignError
from rei.runtime.campaigns.execute import DEFAULT_RUNNER, RunResult, execute_run, execute_run_remote
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.results import PAGE_POLICIES
from rei.runtime.runs.fork_server import WarmWorkers

WorkDirFactory = Callable[[RunSpec], Path]

DASK_INSTALL_HINT = ("the Dask engine needs Dask distributed: "
                     "pip install 'rei-testbed[cluster]' (or pip install 'dask[distributed]')")


@runtime_checkable
class CampaignEngine(Protocol):
    """Runs planned runs; yields (spec, work folder, result) as each run ends."""

    @property
    def name(self) -> str: ...

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]: ...

    def describe(self) -> dict[str, object]: ...


def check_engine(engine: object) -> list[str]:
    """Problems that keep ``engine`` from being a campaign engine (empty: conforms)."""
    problems = []
    if not isinstance(getattr(engine, "name", None), str):
        problems.append("expected a 'name' attribute of type str")
    for method in ("execute", "describe"):
        if not callable(getattr(engine, method, None)):
            problems.append(f"expected a method '{method}'")
    return problems


class WorkerPool:
    """The local engine's worker threads, each with its fork server (rei.runtime.runs.fork_server),
    kept from one ``execute`` to the next until ``close``: a search's batches and a shrink's
    candidates then pay the servers' imports once, not once per batch or candidate.

    A thread lives until ``close`` (a fork server dies with the thread that started it, so
    closing ends the servers too, and a killed campaign takes them along). Runs stay a
    process each: nothing of one run is kept for the next but imported code, which the
    servers check for staleness before every fork.
    """

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise CampaignError(f"--workers: expected at least 1, found {workers}")
        self.workers = workers
        # Threads only wait on the run processes; the isolation is the process per run.
        self._threads = concurrent.futures.ThreadPoolExecutor(
            workers, thread_name_prefix="rei-run")
        self.warm = WarmWorkers()
        self._closed = False

    @property
    def closed(self) -> bool:
        return self._closed

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory, *,
                timeout: float | None = None, runner: tuple[str, ...] = DEFAULT_RUNNER,
                cache: Path | None = None, pages: str = "all"
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]:
        """Run ``specs`` on these workers, at most ``workers`` at once; when the caller
        stops (Ctrl-C, an error, a closed iterator) the runs in flight are stopped and
        waited for, and the workers stay for the next call."""
        if self._closed:
            raise CampaignError("the engine's workers were closed")
        stop = threading.Event()
        pending: dict[concurrent.futures.Future[RunResult], tuple[RunSpec, Path]] = {}
        try:
            queue = list(specs)
            queue.reverse()

            def submit() -> None:
                spec = queue.pop()
                folder = work_dir(spec)
                future = self._threads.submit(execute_run, spec, folder, timeout=timeout,
                                              runner=runner, stop=stop, cache=cache,
                                              warm=self.warm, pages=pages)
                pending[future] = (spec, folder)

            # Submitting only as workers free up keeps partial folders to the running ones.
            while queue and len(pending) < self.workers:
                submit()
            while pending:
                done, _ = concurrent.futures.wait(
                    pending, return_when=concurrent.futures.FIRST_COMPLETED)
                for future in done:
                    spec, folder = pending.pop(future)
                    if queue:
                        submit()
                    yield spec, folder, future.result()
        finally:
            stop.set()
            for future in pending:
                future.cancel()
            # the runs in flight end at once (interrupted); none outlives this call
            concurrent.futures.wait(pending)

    def close(self) -> None:
        """Stop the threads and their fork servers (idempotent)."""
        self._closed = True
        self._threads.shutdown(wait=True, cancel_futures=True)
        self.warm.close()

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()


@dataclass(frozen=True)
class LocalEngine:
    """Runs at most ``workers`` runs at once, each in its own `rei run` process."""

    workers: int = 1
    timeout: float | None = None
    runner: tuple[str, ...] = DEFAULT_RUNNER
    cache: Path | None = None
    """Where the runs share generated worlds and automata (rei.runtime.runs.cache); run_campaign
    gives the campaign's own ``DIR/cache`` when this is None."""
    pages: str = "all"
    """Which runs get their page: `rei run --page` (rei.runtime.results.PAGE_POLICIES)."""
    pool: WorkerPool | None = field(default=None, compare=False, repr=False)
    """Workers kept across ``execute`` calls (``kept_workers``); None: each call starts its
    own and ends them when it returns."""
    name: str = field(default="local", init=False)

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise CampaignError(f"--workers: expected at least 1, found {self.workers}")
        check_pages(self.pages)

    def describe(self) -> dict[str, object]:
        return {"engine": self.name, "workers": self.workers, "pages": self.pages}

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]:
        pool = self.pool if self.pool is not None else WorkerPool(self.workers)
        try:
            yield from pool.execute(specs, work_dir, timeout=self.timeout,
                                    runner=self.runner, cache=self.cache, pages=self.pages)
        finally:
            if self.pool is None:
                pool.close()


EngineT = TypeVar("EngineT", bound=CampaignEngine)


@contextlib.contextmanager
def kept_workers(engine: EngineT) -> Iterator[EngineT]:
    """``engine`` with one pool of workers (and fork servers) for the whole block, closed
    when it ends however it ends (Ctrl-C, an error): for commands that call ``execute``
    more than once (search's batches, shrink's candidates). Engines without local workers
    (Dask keeps its own per worker) come back as they are."""
    if not isinstance(engine, LocalEngine) or engine.pool is not None:
        yield engine
        return
    with WorkerPool(engine.workers) as pool:
        kept: EngineT = replace(engine, pool=pool)
        yield kept


@dataclass(frozen=True)
class DaskEngine:
    """Sends each run to a Dask distributed cluster; a worker runs it with `rei run`."""

    scheduler: str
    timeout: float | None = None
    connect_timeout: float = 30.0
    pages: str = "all"
    """Which runs get their page: `rei run --page` (rei.runtime.results.PAGE_POLICIES)."""
    name: str = field(default="dask", init=False)

    def __post_init__(self) -> None:
        check_pages(self.pages)

    def describe(self) -> dict[str, object]:
        return {"engine": self.name, "scheduler": self.scheduler, "pages": self.pages}

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]:
        distributed = _import_distributed()
        try:
            client = distributed.Client(self.scheduler, timeout=self.connect_timeout,
                                        set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise CampaignError(f"--scheduler {self.scheduler}: cannot reach the Dask "
                                f"scheduler ({exc})") from exc
        try:
            futures = []
            by_key: dict[str, tuple[RunSpec, Path]] = {}
            for spec in specs:
                folder = work_dir(spec)
                # pure=False: a repeat is a new experiment even with equal arguments;
                # retries=0: a run that killed its worker is a result, not something to hide.
                future = client.submit(execute_run_remote, spec, str(folder), self.timeout,
                                       None, self.pages, pure=False,
                                       key=f"rei-run-{spec.run_id}-{uuid.uuid4().hex[:8]}")
                futures.append(future)
                by_key[future.key] = (spec, folder)
            for future in distributed.as_completed(futures, loop=client.loop):
                spec, folder = by_key[future.key]
                try:
                    result: RunResult = future.result()
                except Exception as exc:  # noqa: BLE001  (a lost worker is one run's outcome)
                    result = RunResult(spec.run_id, "crashed", None, 0.0, None,
                                       f"the Dask worker failed: {type(exc).__name__}: {exc}")
                yield spec, folder, result
        finally:
            client.close()


def check_pages(pages: str) -> None:
    if pages not in PAGE_POLICIES:
        raise CampaignError(f"--pages: expected one of {', '.join(PAGE_POLICIES)}, found "
                            f"{pages!r}")


def _import_distributed() -> ModuleType:
    try:
        import distributed  # noqa: PLC0415
    except ImportError as exc:
        raise CampaignError(DASK_INSTALL_HINT) from exc
    return distributed
