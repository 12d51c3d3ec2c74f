"""A search's campaign grows batch by batch: ``extend_plan`` accepts a plan only when the
folder's plan is its beginning, unchanged; anything else is refused as `rei campaign` refuses
another campaign's folder, and ``CampaignStore.open`` then accepts the grown plan."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from rei.runtime.campaigns import CampaignError, CampaignStore
from rei.runtime.campaigns.store import extend_plan
from tests.campaigns.records import example_plan


def test_a_plan_may_only_grow_at_its_end(tmp_path: Path) -> None:
    full = example_plan(repeat=2)
    first = replace(full, runs=full.runs[:2])
    extend_plan(tmp_path, first)
    with CampaignStore.open(tmp_path, first, {}) as store:
        assert [s.run_id for s in store.plan.runs] == [s.run_id for s in first.runs]
    extend_plan(tmp_path, full)
    extend_plan(tmp_path, full)  # the same plan again: nothing to do
    CampaignStore.open(tmp_path, full, {}).close()
    with pytest.raises(CampaignError, match="different campaign"):
        CampaignStore.open(tmp_path, first, {})  # open itself never shrinks a plan
    changed = replace(full, runs=(replace(full.runs[0], seed=1), *full.runs[1:], ))
    with pytest.raises(CampaignError, match="differs in seed"):
        extend_plan(tmp_path, changed)
    reordered = replace(full, runs=(full.runs[1], full.runs[0], *full.runs[2:]))
    with pytest.raises(CampaignError, match="different campaign"):
        extend_plan(tmp_path, reordered)
    assert CampaignStore.read(tmp_path)[0] == full  # nothing refused was written
