"""Running a campaign: open (or resume) the store, run the missing runs, record each at once.

Every finished run is recorded the moment its result arrives, so an interrupted campaign loses
at most the runs that were in flight; running the same command again runs exactly those that
are missing. This module must never decide what a run's verdict is (that is `rei run`'s).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, TextIO

from rei.runtime.campaigns.engines import CampaignEngine, LocalEngine
from rei.runtime.campaigns.plan import CampaignPlan
from rei.runtime.campaigns.progress import Progress
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.static_pair import write_static_twins
from rei.runtime.campaigns.store import CampaignStore

CACHE_FOLDER = "cache"
"""``DIR/cache/``: the generated worlds and automata the campaign's runs share."""


@dataclass(frozen=True)
class CampaignResult:
    root: Path
    plan: CampaignPlan
    records: tuple[RunRecord, ...]
    ran_now: int
    """Runs executed in this session (the rest were recorded by earlier sessions)."""

    @property
    def complete(self) -> bool:
        return len(self.records) == len(self.plan.runs)

    @property
    def all_passed(self) -> bool:
        return self.complete and all(r.passed for r in self.records)


def run_campaign(plan: CampaignPlan, root: Path, engine: CampaignEngine,
                 provenance: dict[str, Any], *, stream: TextIO | None = None) -> CampaignResult:
    """Run what is missing of ``plan`` in ``root``; write results.csv / results.parquet."""
    out = stream if stream is not None else sys.stderr
    if isinstance(engine, LocalEngine) and engine.cache is None:
        # Every run of a mission generates the same world and automata: once is enough.
        engine = replace(engine, cache=root / CACHE_FOLDER)
    with CampaignStore.open(root, plan, provenance) as store:
        # Static twins are (re)written on every session before any run: they follow the
        # original files, and a run never reads a twin that is not complete.
        write_static_twins(plan)
        missing = store.missing()
        already = len(plan.runs) - len(missing)
        if already:
            print(f"resuming {root}: {already} of {len(plan.runs)} runs already recorded",
                  file=out)
        progress = Progress(len(plan.runs), already, out)
        ran = 0
        try:
            work_dir = lambda s: store.new_work_dir(s.run_id)  # noqa: E731
            for spec, work, result in engine.execute(missing, work_dir):
                record = store.record(spec, result, work)
                if record is not None:
                    ran += 1
                    progress.update(record.verdict)
        finally:
            progress.finish()
            # Tables always match the records, also after Ctrl-C (they are rebuilt on resume).
            store.write_tables()
        records = tuple(store.records())
        if len(records) < len(plan.runs):
            print(f"{len(plan.runs) - len(records)} of {len(plan.runs)} runs are not recorded "
                  f"(stopped by the campaign); run the same command again to run them",
                  file=out)
        return CampaignResult(root, plan, records, ran)
