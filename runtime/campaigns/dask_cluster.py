"""A real Dask cluster on this machine's loopback: `dask scheduler` and `dask worker` processes.

For trying the Dask engine, its tests and its benchmark without a cluster: the same programs a
user starts on real machines, bound to 127.0.0.1, stopped when the context ends. This module
must never leave a process running after its context, nor listen on another interface.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from rei.runtime.campaigns.engines import DASK_INSTALL_HINT
from rei.runtime.campaigns.errors import CampaignError


def _dask_program() -> list[str]:
    script = Path(sys.executable).with_name("dask")
    if script.is_file():
        return [str(script)]
    try:
        import distributed  # noqa: F401, PLC0415
    except ImportError as exc:
        raise CampaignError(DASK_INSTALL_HINT) from exc
    return [sys.executable, "-m", "dask"]


def _stop(process: subprocess.Popen[bytes], grace: float) -> None:
    if process.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()


@contextlib.contextmanager
def loopback_cluster(workers: int = 2, threads: int = 1, start_timeout: float = 90.0,
                     nanny: bool = True) -> Iterator[str]:
    """Start a scheduler and ``workers`` worker processes of ``threads`` threads each on
    127.0.0.1; yield the scheduler's address. Without ``nanny`` (one worker only) the worker
    runs tasks in its own process: fewer processes to share the cores with the runs."""
    if not nanny and workers != 1:
        raise CampaignError("a cluster without nannies has exactly one worker process")
    dask = _dask_program()
    processes: list[subprocess.Popen[bytes]] = []
    with tempfile.TemporaryDirectory(prefix="rei-dask-") as tmp:
        info = Path(tmp) / "scheduler.json"
        logs = [open(Path(tmp) / name, "wb") for name in ("scheduler.log", "worker.log")]  # noqa: SIM115
        try:
            # Own process groups: stopping the cluster also stops the workers' nannies' children.
            processes.append(subprocess.Popen(
                [*dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                 "--scheduler-file", str(info)], stdout=logs[0], stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL, process_group=0, cwd=tmp))
            address = _wait_for_address(info, processes[0], start_timeout, Path(tmp))
            processes.append(subprocess.Popen(
                [*dask, "worker", address, "--host", "127.0.0.1", "--nworkers", str(workers),
                 "--nthreads", str(threads), "--no-dashboard", "--memory-limit", "0",
                 "--nanny" if nanny else "--no-nanny"],
                stdout=logs[1], stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                process_group=0, cwd=tmp))
            _wait_for_workers(address, workers, start_timeout, processes[1], Path(tmp))
            yield address
        finally:
            for process in reversed(processes):
                _stop(process, grace=20.0)
            for log in logs:
                log.close()


def _wait_for_address(info: Path, scheduler: subprocess.Popen[bytes], limit: float,
                      tmp: Path) -> str:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        if scheduler.poll() is not None:
            raise CampaignError("dask scheduler exited: "
                                + (tmp / "scheduler.log").read_text(errors="replace")[-2000:])
        try:
            return str(json.loads(info.read_text())["address"])
        except (OSError, ValueError, KeyError):
            time.sleep(0.1)
    raise CampaignError(f"dask scheduler did not start within {limit:g} s")


def _wait_for_workers(address: str, count: int, limit: float,
                      worker: subprocess.Popen[bytes], tmp: Path) -> None:
    import distributed  # noqa: PLC0415

    with distributed.Client(address, timeout=limit, set_as_default=False) as client:
        try:
            client.wait_for_workers(count, timeout=limit)
        except TimeoutError as exc:
            log = (tmp / "worker.log").read_text(errors="replace")[-2000:]
            raise CampaignError(f"{count} dask workers did not start within {limit:g} s "
                                f"(worker {'exited' if worker.poll() is not None else 'running'}"
                                f"): {log}") from exc
