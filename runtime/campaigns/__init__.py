"""Campaigns: many missions, many repeats, run in parallel, resumable, in one results store.

Planning (``plan``) turns missions, folders and suite indexes into runs with derived seeds; an
engine (``engines``: local worker processes, or a Dask cluster) executes each run in isolation
with `rei run` under a watchdog (``execute``); the store (``store``) records every run exactly
once, atomically, with its own folder; ``stats`` computes success rates with Wilson intervals,
mission verdicts against a required pass rate and, for ``--pair-static`` campaigns (whose static
twins ``static_pair`` writes), whether failures come from the people or the room.
``search/`` looks for failing scenarios, ``shrink/`` reduces a failing case, and
``failure_clusters`` groups a campaign's failures. Reports on a campaign folder are
``rei.runtime.presentation.campaign_report``'s job.

It may import runs, observation, the platform and the contracts; it never imports pybullet or
the simulation loop: runs happen in other processes (`rei run`).
"""

from rei.runtime.campaigns.engines import CampaignEngine, DaskEngine, LocalEngine, check_engine
from rei.runtime.campaigns.errors import CampaignError
from rei.runtime.campaigns.execute import RunResult, execute_run
from rei.runtime.campaigns.orchestration import CampaignResult, run_campaign
from rei.runtime.campaigns.plan import CampaignPlan, RunSpec, derive_seed, plan_campaign
from rei.runtime.campaigns.results_table import record_row, write_tables
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.static_pair import static_twin, write_static_twins
from rei.runtime.campaigns.stats import (
    MissionVerdict,
    PairedMission,
    SuccessRate,
    campaign_passed,
    classify_pairs,
    mission_verdicts,
    success_rates,
    wilson_interval,
)
from rei.runtime.campaigns.store import CampaignStore

__all__ = [
    "CampaignEngine", "CampaignError", "CampaignPlan", "CampaignResult", "CampaignStore",
    "DaskEngine", "LocalEngine", "MissionVerdict", "PairedMission", "RunRecord", "RunResult",
    "RunSpec", "SuccessRate", "campaign_passed", "check_engine", "classify_pairs",
    "derive_seed", "execute_run", "mission_verdicts", "plan_campaign", "record_row",
    "run_campaign", "static_twin", "success_rates", "wilson_interval", "write_static_twins",
    "write_tables",
]
