"""``run_search(until=...)``: a caller (bench/search.py, stopping at its first *confirmed*
failure) ends a search after any batch; what ran is recorded as in a search that ended
there, and running it again with the same ``until`` replays it without a run."""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import pytest

from rei.runtime.campaigns import CampaignStore, LocalEngine
from rei.runtime.campaigns.search import SearchConfig, run_search
from rei.runtime.campaigns.search.driver import CandidateResult

ROOM = (("shape", "rect"), ("size", "5x3"), ("objects", "0"), ("mix", "furniture"),
        ("humans", "0"), ("goals", "2"), ("spacing", "2"), ("cycles", "1"),
        ("behaviour", "yielding"), ("heading", "no"), ("max_speed", "0.05:0.3"))


@pytest.mark.slow
def test_until_ends_the_search_after_the_batch_it_says(tmp_path: Path) -> None:
    config = SearchConfig(levels=ROOM, layout=1, strategy="random", budget=6, batch=2,
                          requirement="SPEED_LIMIT")
    asked: list[int] = []

    def two_batches(results: Sequence[CandidateResult]) -> bool:
        asked.append(len(results))
        return len(results) >= 4

    out = tmp_path / "search"
    result = run_search(config, out, LocalEngine(1), {}, stream=io.StringIO(),
                        until=two_batches)
    assert asked == [2, 4]  # asked after every batch, with every result so far
    assert result.complete and len(result.results) == 4  # not the budget of 6
    assert len(CampaignStore.read(out)[2]) == 4
    assert len((out / "search.csv").read_text().splitlines()) == 1 + 4
    again = run_search(config, out, LocalEngine(1), {}, stream=io.StringIO(),
                       until=two_batches)
    assert [r.objective for r in again.results] == [r.objective for r in result.results]
    assert len(CampaignStore.read(out)[2]) == 4  # replayed, nothing ran again
