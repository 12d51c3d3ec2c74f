"""Campaign folders written through the real store from RunSummary records made in the test.

The summaries are REI's own file format (rei.runtime.results), written here instead of running
pybullet so store, statistics, report and JUnit can be tested fast and exactly.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from rei.runtime.campaigns import CampaignPlan, CampaignStore, RunResult, plan_campaign
from rei.runtime.results import RunSummary, Verdict

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

SIGNALS = (("SIG_MISSION_BEGIN", 20.0), ("SIG_MISSION_TASK_START", 5.0),
           ("SIG_GEOM_FAR_TRANSIT_CLOSE", -2.0), ("SIG_GEOM_CLOSE_TRANSIT_FAR", 1.0),
           ("SIG_MISSION_TASK_SUCCESS", 10.0), ("SIG_MISSION_END", 20.0))


def summary_for(mission: str, room: str, seed: int, passed: bool, duration: float
                ) -> RunSummary:
    counts: dict[str, int] = {}
    total = 0.0
    for name, utility in SIGNALS:
        counts[name] = counts.get(name, 0) + 1
        total += utility
    if not passed:
        counts["SIG_MISSION_TASK_FAIL"] = 1
        total -= 100.0
    verdicts = (Verdict("no_collision", "pass", None, "no collision"),
                Verdict("all_tasks_succeed", "pass" if passed else "fail",
                        None if passed else duration, "" if passed else "task 2 timed out"))
    return RunSummary(version=1, mission=mission, room=room, seed=seed, controller="navigator",
                      outcome="completed" if passed else "failed",
                      reason="" if passed else "task 2 timed out", duration=duration,
                      total_utility=total, signal_counts=counts, verdicts=verdicts)


def events_csv(summary: RunSummary) -> bytes:
    lines = ["time,signal,utility,total,objects"]
    total = 0.0
    step = summary.duration / (len(SIGNALS) + 1)
    for i, (name, utility) in enumerate(SIGNALS, start=1):
        total += utility
        lines.append(f"{i * step:.3f},{name},{utility},{total},waffle")
    return ("\n".join(lines) + "\n").encode()


def example_plan(repeat: int = 3, seed: int = 7, duration: float = 2.0) -> CampaignPlan:
    """The examples' campaign these records are shaped on: the four thesis rooms (the fault
    studies of examples/faults/ left out, so the records keep their shape)."""
    plan = plan_campaign([EXAMPLES], repeat=repeat, seed=seed, duration=duration)
    return replace(plan, runs=tuple(r for r in plan.runs
                                    if Path(r.mission_file).parent.name != "faults"))


def outcome_of(run_id: str, repeat: int) -> str:
    """A fixed pattern: simple_wall always passes, navigation is flaky, small_dense crashes once."""
    if run_id.startswith("small_dense") and repeat == 0:
        return "crashed"
    if run_id.startswith("navigation") and repeat == 1:
        return "fail"
    if run_id.startswith("medium_sparse"):
        return "fail"
    return "pass"


def result_for(spec_run_id: str, repeat: int, seed: int, mission_file: str) -> RunResult:
    kind = outcome_of(spec_run_id, repeat)
    if kind == "crashed":
        return RunResult(spec_run_id, "crashed", 3, 0.5, None, "exit status 3, no summary.json")
    stem = Path(mission_file).stem
    summary = summary_for(stem, f"{stem}_room", seed, kind == "pass", 10.0 + repeat)
    return RunResult(spec_run_id, "ran", 0 if kind == "pass" else 1, 1.0 + repeat,
                     summary.to_json(), "", {"events.csv": events_csv(summary)})


def write_campaign(root: Path, plan: CampaignPlan | None = None,
                   only: int | None = None) -> CampaignPlan:
    """Record the runs of ``plan`` (the first ``only`` of them) as a campaign would."""
    plan = plan or example_plan()
    with CampaignStore.open(root, plan, {"command": ["rei", "campaign", "test"]}) as store:
        for spec in plan.runs[:only]:
            work = store.new_work_dir(spec.run_id)
            store.record(spec, result_for(spec.run_id, spec.repeat, spec.seed,
                                          spec.mission_file), work)
        store.write_tables()
    return plan
