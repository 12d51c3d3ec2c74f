"""Fixtures of the campaign tests: the real `rei run` (skipped until it exists) and a real Dask
cluster (scheduler and workers as processes on 127.0.0.1)."""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator

import pytest


def require_rei_run() -> None:
    """Campaign integration tests need the real `rei run` (runtime/commands/run.py)."""
    if importlib.util.find_spec("rei.runtime.commands.run") is None:
        pytest.skip("`rei run` is missing (runtime/commands/run.py has not landed yet)")


@pytest.fixture(scope="module")
def dask_scheduler() -> Iterator[str]:
    pytest.importorskip("distributed", reason="pip install 'dask[distributed]'")
    from rei.runtime.campaigns.dask_cluster import loopback_cluster  # noqa: PLC0415

    with loopback_cluster(workers=2, threads=1) as address:
        yield address
