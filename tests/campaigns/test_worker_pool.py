"""One pool of workers for an engine's lifetime (rei.runtime.campaigns.engines.WorkerPool,
``kept_workers``): every ``execute`` call of a search's batches or a shrink's candidates is
served by the same fork servers, the runs are the bytes they would be otherwise, and closing
the block (normally, on an error, on Ctrl-C) leaves no server and no run behind.

Real runs of the bundled examples (pybullet, the reference navigator), real fork servers."""

from __future__ import annotations

import io
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

from rei.runtime.campaigns import LocalEngine, RunResult, plan_campaign
from rei.runtime.campaigns.engines import WorkDirFactory, WorkerPool, kept_workers
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.campaigns.search import run_search
from rei.runtime.campaigns.search.driver import SearchConfig
from rei.runtime.campaigns.shrink.case import load_case
from rei.runtime.campaigns.shrink.oracle import FailureOracle, RunSettings
from rei.runtime.platform.warm import WARM_VARIABLE

from .records import EXAMPLES
from .test_process_death import rei_runs
from .test_warm_runs import OUTPUTS, plugins, servers_of

__all__ = ["plugins"]  # the fixture, shared with the warm-run tests

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux only")]


def spec(example: str, duration: float, controller: str | None = None) -> RunSpec:
    return plan_campaign([EXAMPLES / example], duration=duration, controller=controller).runs[0]


def batch(engine: LocalEngine, specs: list[RunSpec], folder: Path) -> list[set[int]]:
    """Run ``specs`` into ``folder``; the fork servers alive as each result arrived."""
    seen = []
    for _, _, result in engine.execute(specs, lambda s: folder / s.run_id):
        assert result.status == "ran", result.message
        seen.append(servers_of(os.getpid()))
    return seen


def test_kept_workers_serve_every_call_from_the_same_servers_and_end_them(
        plugins: Path, tmp_path: Path) -> None:
    run = spec("simple_wall", 1.0)
    with kept_workers(LocalEngine(1)) as engine:
        first = batch(engine, [run], tmp_path / "first")
        second = batch(engine, [run], tmp_path / "second")
        assert engine.pool is not None and not engine.pool.closed
    assert len(first[0]) == 1 and first == second  # one server, kept from call to call
    assert not servers_of(os.getpid())  # and gone with the block
    # The second run got nothing from the first but imported code: the same bytes.
    for name in OUTPUTS:
        assert (tmp_path / "first" / run.run_id / name).read_bytes() == \
               (tmp_path / "second" / run.run_id / name).read_bytes(), name


def test_without_kept_workers_each_call_starts_and_ends_its_own(
        plugins: Path, tmp_path: Path) -> None:
    # What the pool saves: the engine alone pays a new server per call (the "before").
    engine = LocalEngine(1)
    run = spec("simple_wall", 0.5)
    first = batch(engine, [run], tmp_path / "first")
    assert not servers_of(os.getpid())
    second = batch(engine, [run], tmp_path / "second")
    assert not servers_of(os.getpid())
    assert first[0] and second[0] and first[0] != second[0]


@pytest.mark.parametrize("stop", [RuntimeError, KeyboardInterrupt])
def test_an_error_or_ctrl_c_in_the_block_stops_its_runs_and_servers(
        plugins: Path, tmp_path: Path, stop: type[BaseException]) -> None:
    quick = spec("simple_wall", 0.5)
    slow = spec("small_dense", 600.0, "slow_controllers:Dawdling")
    with pytest.raises(stop), kept_workers(LocalEngine(2)) as engine:
        for _, _, result in engine.execute([slow, quick], lambda s: tmp_path / s.run_id):
            assert result.run_id == quick.run_id, result.message  # the slow one still runs
            assert rei_runs(os.getpid()), "the slow run should be running"
            raise stop
    assert not rei_runs(os.getpid())
    assert not servers_of(os.getpid())


def test_a_closed_pool_refuses_work_and_a_cold_campaign_keeps_working(
        plugins: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pool = WorkerPool(1)
    pool.close()
    pool.close()  # twice is harmless
    with pytest.raises(Exception, match="the engine's workers were closed"):
        list(LocalEngine(1, pool=pool).execute([spec("simple_wall", 0.5)],
                                               lambda s: tmp_path / s.run_id))
    # REI_WARM=off: the kept threads start fresh interpreters, and no server at all
    monkeypatch.setenv(WARM_VARIABLE, "off")
    with kept_workers(LocalEngine(1)) as engine:
        assert batch(engine, [spec("simple_wall", 0.5)], tmp_path / "cold") == [set()]


class Watching:
    """An engine that runs on ``inner`` and notes the fork servers alive at each result."""

    name = "local"

    def __init__(self, inner: LocalEngine) -> None:
        self.inner = inner
        self.seen: list[frozenset[int]] = []

    def describe(self) -> dict[str, object]:
        return self.inner.describe()

    def execute(self, specs: Sequence[RunSpec], work_dir: WorkDirFactory
                ) -> Iterator[tuple[RunSpec, Path, RunResult]]:
        for item in self.inner.execute(specs, work_dir):
            self.seen.append(frozenset(servers_of(os.getpid())))
            yield item


def test_a_search_runs_every_batch_on_the_same_servers(plugins: Path, tmp_path: Path) -> None:
    config = SearchConfig(preset="small", strategy="random", seed=0, budget=4, batch=2,
                          duration=1.0)
    with kept_workers(LocalEngine(1, pages="none")) as engine:
        watching = Watching(engine)
        result = run_search(config, tmp_path / "search", watching, {}, stream=io.StringIO())
    simulated = sum(r.record is not None for r in result.results)
    assert simulated >= 3 and len(watching.seen) == simulated  # more than one batch ran
    assert len(set(watching.seen)) == 1 and len(watching.seen[0]) == 1
    assert not servers_of(os.getpid())


def test_a_shrinks_oracle_judges_every_candidate_on_the_same_servers(
        plugins: Path, tmp_path: Path) -> None:
    settings = RunSettings(seeds=(0,), duration=0.5, workers=1)
    case = load_case(EXAMPLES / "simple_wall" / "simple_wall.mission")
    seen = []
    with WorkerPool(1) as pool:
        oracle = FailureOracle(settings, tmp_path / "work", tmp_path / "journal.jsonl",
                               pool=pool)
        for _ in range(2):
            oracle.known.clear()  # judged again, as a new candidate is
            assert oracle.outcomes(case)[0].verdict not in ("error", "invalid")
            seen.append(servers_of(os.getpid()))
    assert oracle.started == 2
    assert len(seen[0]) == 1 and seen[0] == seen[1]
    assert not servers_of(os.getpid())
