"""What a report reads from a campaign folder: its plan and records (each run's event log and
path are read by rei.runtime.observation.run_folder).

Event logs (events.csv, one row per signal: time, signal, utility, running total, objects) and
traces belong to `rei run`; they are read here leniently, because a crashed run may have left
none or half of them, and a report must still be written. This module must never write files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rei.runtime.campaigns.plan import CampaignPlan
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.store import CampaignStore


@dataclass(frozen=True)
class CampaignData:
    root: Path
    plan: CampaignPlan
    manifest: dict[str, Any]
    records: tuple[RunRecord, ...]

    def run_dir(self, record: RunRecord) -> Path:
        return self.root / "runs" / record.spec.run_id

    @property
    def provenance(self) -> dict[str, Any]:
        sessions = self.manifest.get("sessions") or [{}]
        first: dict[str, Any] = sessions[0]
        return first


def load_campaign(root: Path) -> CampaignData:
    plan, manifest, records = CampaignStore.read(root)
    return CampaignData(root, plan, manifest, tuple(records))
