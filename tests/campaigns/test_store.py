"""The results store: atomic records, exactly-once resume, refusal of foreign or corrupt folders,
and the Parquet / CSV tables."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rei.runtime.campaigns import CampaignError, CampaignStore, RunRecord, RunResult, plan_campaign
from rei.runtime.campaigns.results_table import rows_table

from .records import EXAMPLES, example_plan, result_for, write_campaign


def test_resume_runs_only_the_missing_and_keeps_every_run_once(tmp_path: Path) -> None:
    plan = example_plan()
    write_campaign(tmp_path, plan, only=5)
    with CampaignStore.open(tmp_path, plan, {"command": ["again"]}) as store:
        missing = store.missing()
        assert [s.run_id for s in missing] == [s.run_id for s in plan.runs[5:]]
        for spec in missing:
            store.record(spec, result_for(spec.run_id, spec.repeat, spec.seed,
                                          spec.mission_file), store.new_work_dir(spec.run_id))
        assert store.missing() == []
        ids = [r.spec.run_id for r in store.records()]
    assert ids == [s.run_id for s in plan.runs]
    manifest = json.loads((tmp_path / "campaign.json").read_text())
    assert [s["command"] for s in manifest["sessions"]] == [["rei", "campaign", "test"],
                                                             ["again"]]


def test_an_unfinished_attempt_is_discarded_and_runs_again(tmp_path: Path) -> None:
    plan = example_plan()
    with CampaignStore.open(tmp_path, plan, {}) as store:
        work = store.new_work_dir(plan.runs[0].run_id)
        (work / "summary.json").write_text("{half")
    with CampaignStore.open(tmp_path, plan, {}) as store:
        assert not work.exists()
        assert len(store.missing()) == len(plan.runs)


def test_an_interrupted_run_is_not_recorded(tmp_path: Path) -> None:
    plan = example_plan()
    spec = plan.runs[0]
    with CampaignStore.open(tmp_path, plan, {}) as store:
        work = store.new_work_dir(spec.run_id)
        assert store.record(spec, RunResult(spec.run_id, "interrupted", 130, 1.0, None),
                            work) is None
        assert len(store.missing()) == len(plan.runs)


def test_record_json_roundtrip(tmp_path: Path) -> None:
    write_campaign(tmp_path)
    folders = sorted(p for p in (tmp_path / "runs").iterdir() if not p.name.startswith("."))
    assert len(folders) == 12
    for folder in folders:
        data = json.loads((folder / "record.json").read_text())
        assert RunRecord.from_json(data).to_json() == data


def test_a_foreign_folder_is_refused(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(CampaignError, match="not a REI campaign folder"):
        CampaignStore.open(tmp_path, example_plan(), {})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


@pytest.mark.parametrize(("content", "expected"), [
    ("{not json", "corrupt"),
    ('{"format": "something-else", "version": 1}', "not a REI campaign manifest"),
    ('{"format": "rei-campaign", "version": 99, "plan": {}}', "format version 99"),
    ('{"format": "rei-campaign", "version": 1, "plan": {"runs": 3}}', "plan is corrupt"),
])
def test_a_corrupt_manifest_is_refused(tmp_path: Path, content: str, expected: str) -> None:
    write_campaign(tmp_path, only=2)
    (tmp_path / "campaign.json").write_text(content)
    with pytest.raises(CampaignError, match=expected):
        CampaignStore.open(tmp_path, example_plan(), {})
    with pytest.raises(CampaignError, match=expected):
        CampaignStore.read(tmp_path)


def test_a_corrupt_or_stray_run_folder_is_refused(tmp_path: Path) -> None:
    plan = write_campaign(tmp_path, only=2)
    record = tmp_path / "runs" / plan.runs[0].run_id / "record.json"
    record.write_text('{"format": "rei-run-record", "spec": ')
    with pytest.raises(CampaignError, match=f"{record}: the run record is corrupt"):
        CampaignStore.open(tmp_path, plan, {})
    record.unlink()
    with pytest.raises(CampaignError, match="without record.json"):
        CampaignStore.open(tmp_path, plan, {})
    (tmp_path / "runs" / plan.runs[0].run_id).rename(tmp_path / "runs" / "other.r00")
    with pytest.raises(CampaignError, match="not in this campaign's plan"):
        CampaignStore.read(tmp_path)


def test_a_different_command_is_refused(tmp_path: Path) -> None:
    write_campaign(tmp_path, only=1)
    with pytest.raises(CampaignError, match="--seed 7 --repeat 3, found --seed 8 --repeat 3"):
        CampaignStore.open(tmp_path, example_plan(seed=8), {})
    with pytest.raises(CampaignError, match=r"only in the folder: \['medium_sparse.r00'"):
        CampaignStore.open(tmp_path, plan_campaign([EXAMPLES / "navigation"], repeat=3,
                                                   seed=7, duration=2.0), {})
    with pytest.raises(CampaignError, match="Run medium_sparse.r00 differs in duration"):
        CampaignStore.open(tmp_path, example_plan(duration=3.0), {})


def test_two_campaigns_cannot_write_one_folder(tmp_path: Path) -> None:
    plan = example_plan()
    with CampaignStore.open(tmp_path, plan, {}):
        with pytest.raises(CampaignError, match="another `rei campaign`"):
            CampaignStore.open(tmp_path, plan, {})


def test_tables_have_one_row_per_run_in_csv_and_parquet(tmp_path: Path) -> None:
    plan = write_campaign(tmp_path)
    with (tmp_path / "results.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    table = pq.read_table(tmp_path / "results.parquet").to_pylist()
    assert [r["run_id"] for r in rows] == [r["run_id"] for r in table] == \
        [s.run_id for s in plan.runs]
    crashed = next(r for r in table if r["run_id"] == "small_dense.r00")
    assert crashed["status"] == "crashed" and crashed["passed"] is False
    assert crashed["total_utility"] is None and crashed["signal:SIG_MISSION_BEGIN"] == 0
    passed = next(r for r in table if r["run_id"] == "simple_wall.r00")
    assert passed["req:all_tasks_succeed"] == "pass" and passed["passed"] is True
    assert passed["total_utility"] == 54.0 and passed["signal:SIG_MISSION_BEGIN"] == 1
    for key in ("mission", "room", "seed", "repeat", "controller", "outcome", "duration",
                "group"):
        assert key in rows[0]
    columns, _ = rows_table(CampaignStore.read(tmp_path)[2])
    assert list(rows[0]) == columns == pq.read_table(tmp_path / "results.parquet").column_names


def test_tables_are_deterministic(tmp_path: Path) -> None:
    write_campaign(tmp_path / "a")
    write_campaign(tmp_path / "b")
    assert (tmp_path / "a" / "results.csv").read_bytes() == \
        (tmp_path / "b" / "results.csv").read_bytes()
    assert pq.read_table(tmp_path / "a" / "results.parquet").equals(
        pq.read_table(tmp_path / "b" / "results.parquet"))
