"""Where runs execute: the local engine (worker processes on this machine, nothing to install)
and the Dask engine (a Dask distributed cluster, imported only when asked for).

An engine takes planned runs and hands back one ``RunResult`` per run as each finishes, in the
campaign process, which alone writes the store. Engines must never write the store, and never
raise because one run failed: a crash or a hang is a result.
"""

from __future__ import annotations

import concurrent.futures
import threading
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Protocol, runtime_checkable

from rei.runtime.campaign.errors import CampaignError
from rei.runtime.campaign.execute import (
    DEFAULT_RUNNER,
    RunResult,
    execute_run,
    execute_run_remote,
)
from rei.runtime.campaign.plan import RunSpec
from rei.runtime.warm.server import WarmWorkers

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


@dataclass(frozen=True)
class LocalEngine:
    """Runs at most ``workers`` runs at once, each in its own `rei run` process."""

    workers: int = 1
    timeout: float | None = None
    runner: tuple[str, ...] = DEFAULT_RUNNER
    cache: Path | None = None
    """Where the runs share generated worlds and automata (rei.runtime.cache); run_campaign
    gives the campaign's own ``DIR/cache`` when this is None."""
    name: str = field(default="local", init=False)

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise CampaignError(f"--workers: expected at least 1, found {self.workers}")

    def describe(self) -> dict[str, object]:
        return {"engine": self.name, "workers": self.workers}

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]:
        stop = threading.Event()
        # Threads only wait on the run processes; the isolation is the process per run.
        pool = concurrent.futures.ThreadPoolExecutor(self.workers, thread_name_prefix="rei-run")
        # A fork server per thread, imports done once per worker (rei.runtime.warm.server).
        warm = WarmWorkers()
        try:
            pending: dict[concurrent.futures.Future[RunResult], tuple[RunSpec, Path]] = {}
            queue = list(specs)
            queue.reverse()

            def submit() -> None:
                spec = queue.pop()
                folder = work_dir(spec)
                future = pool.submit(execute_run, spec, folder, timeout=self.timeout,
                                     runner=self.runner, stop=stop, cache=self.cache,
                                     warm=warm)
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
            pool.shutdown(wait=True, cancel_futures=True)
            warm.close()


@dataclass(frozen=True)
class DaskEngine:
    """Sends each run to a Dask distributed cluster; a worker runs it with `rei run`."""

    scheduler: str
    timeout: float | None = None
    connect_timeout: float = 30.0
    name: str = field(default="dask", init=False)

    def describe(self) -> dict[str, object]:
        return {"engine": self.name, "scheduler": self.scheduler}

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
                                       pure=False,
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


def _import_distributed() -> ModuleType:
    try:
        import distributed  # noqa: PLC0415
    except ImportError as exc:
        raise CampaignError(DASK_INSTALL_HINT) from exc
    return distributed
