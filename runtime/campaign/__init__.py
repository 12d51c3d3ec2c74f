"""Campaigns: many missions, many repeats, run in parallel, resumable, in one results store.

Planning (``plan``) turns missions, folders and suite indexes into runs with derived seeds; an
engine (``engines``: local worker processes, or a Dask cluster) executes each run in isolation
with `rei run` under a watchdog (``execute``); the store (``store``) records every run exactly
once, atomically, with its own folder; ``stats`` computes success rates with Wilson intervals.
Reports on a campaign folder are ``rei.runtime.report``'s job. This package never imports
pybullet: runs happen in other processes.
"""

from rei.runtime.campaign.engines import CampaignEngine, DaskEngine, LocalEngine, check_engine
from rei.runtime.campaign.errors import CampaignError
from rei.runtime.campaign.execute import RunResult, execute_run
from rei.runtime.campaign.plan import CampaignPlan, RunSpec, derive_seed, plan_campaign
from rei.runtime.campaign.run import CampaignResult, run_campaign
from rei.runtime.campaign.stats import SuccessRate, success_rates, wilson_interval
from rei.runtime.campaign.store import CampaignStore, RunRecord, record_row, write_tables

__all__ = [
    "CampaignEngine", "CampaignError", "CampaignPlan", "CampaignResult", "CampaignStore",
    "DaskEngine", "LocalEngine", "RunRecord", "RunResult", "RunSpec", "SuccessRate",
    "check_engine", "derive_seed", "execute_run", "plan_campaign", "record_row",
    "run_campaign", "success_rates", "wilson_interval", "write_tables",
]
