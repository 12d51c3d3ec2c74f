"""Failure clusters (issue 25.4): a campaign's failed runs as a few distinct failures, each
with its smallest reproducer and replay command, first in report.html and in clusters.json.
Campaign folders are written through the real store with REI's own summary format
(tests/campaigns/records.py); tests/shrink/test_shrink_command.py links a real shrink."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from lxml import etree

from rei.runtime.campaigns import CampaignStore, RunResult
from rei.runtime.presentation.campaign_report import build_report
from rei.runtime.presentation.campaign_report.build import rerun_command
from rei.runtime.results import Verdict
from tests.campaigns.records import EXAMPLES, example_plan, summary_for

SPEEDING = ("SIG_MISSION_BEGIN", "SIG_MISSION_TASK_START", "SIG_OVER_SPEED_COMMANDED")
BUMPING = ("SIG_MISSION_TASK_START", "SIG_GEOM_FAR_TRANSIT_CLOSE", "SIG_ROBOT_COLLISION")


def _events(signals: tuple[str, ...]) -> bytes:
    rows = ["time,signal,utility,total_utility,objects"]
    rows += [f"{0.5 * (i + 1):.1f},{name},-1,{-(i + 1)}," for i, name in enumerate(signals)]
    rows.append("9.0,SIG_MISSION_END,20,17,")  # after the failure: not part of its story
    return ("\n".join(rows) + "\n").encode()


def _failing(mission: str) -> tuple[str, tuple[str, ...]] | None:
    """Which requirement each example mission fails in this campaign, after which signals."""
    return {"simple_wall": ("SPEED_LIMIT", SPEEDING), "navigation": ("SPEED_LIMIT", SPEEDING),
            "small_dense": ("NO_ROBOT_COLLISION", BUMPING),
            "medium_sparse": ("NO_ROBOT_COLLISION", BUMPING)}.get(mission)


def _campaign(root: Path, passing: bool = False, undecided: frozenset[str] = frozenset()
              ) -> None:
    """``undecided``: runs whose requirement is inconclusive instead of failed."""
    plan = example_plan(repeat=2)
    with CampaignStore.open(root, plan, {"command": ["rei", "campaign", "examples"]}) as store:
        for spec in plan.runs:
            stem = Path(spec.mission_file).stem
            failing = None if passing else _failing(stem)
            summary = summary_for(stem, f"{stem}_room", spec.seed, True, 10.0 + spec.repeat)
            if failing is not None:
                requirement, signals = failing
                summary = replace(summary, outcome="completed", verdicts=(
                    Verdict(requirement,
                            "inconclusive" if spec.run_id in undecided else "fail",
                            0.5 * len(signals), f"{requirement} broken"),
                    Verdict("MISSION_GOALS_REACHED", "pass", None, "")))
            result = RunResult(spec.run_id, "ran", 1 if failing else 0, 1.0, summary.to_json(),
                               "", {"events.csv": _events(failing[1] if failing else ())})
            store.record(spec, result, store.new_work_dir(spec.run_id))
        store.write_tables()


def _clusters(root: Path) -> list[dict[str, object]]:
    data = json.loads((root / "clusters.json").read_text(encoding="utf-8"))
    found: list[dict[str, object]] = data["clusters"]
    return found


def test_two_kinds_of_failure_are_two_clusters_each_with_its_smallest_reproducer(
        tmp_path: Path) -> None:
    root = tmp_path / "campaign"
    _campaign(root)
    build_report(root)
    found = _clusters(root)
    assert [(c["requirement"], len(c["runs"])) for c in found] == [  # type: ignore[arg-type]
        ("NO_ROBOT_COLLISION", 4), ("SPEED_LIMIT", 4)]
    collision, speed = found
    assert collision["lead"] == list(BUMPING) and speed["lead"] == list(SPEEDING)
    # the smallest case of each cluster: simple_wall (5 elements) before navigation (48),
    # small_dense (42) before medium_sparse (129); the shorter run of the two repeats
    assert speed["reproducer"] == {
        "run": "simple_wall.r00", "mission": "simple_wall/simple_wall.mission", "shrunk": False,
        "elements": 5, "time": 1.5, "reason": "SPEED_LIMIT broken",
        "replay": rerun_command(next(r.spec for r in CampaignStore.read(root)[2]
                                     if r.spec.run_id == "simple_wall.r00"))}
    assert collision["reproducer"]["run"] == "small_dense.r00"  # type: ignore[index]
    assert collision["reproducer"]["elements"] == 42  # type: ignore[index]
    # first in the report, one row per cluster, with the replay command
    page = etree.HTML((root / "report.html").read_text(encoding="utf-8"))
    assert page.xpath("//h2/@id")[0] == "clusters"
    rows = page.xpath("//table[@id='failure-clusters']/tbody/tr")
    assert len(rows) == 2
    cells = [td.xpath("string(.)") for td in rows[1].xpath("./td")]
    assert cells[0] == "SPEED_LIMIT" and cells[5].startswith("simple_wall.r00 at 1.5 s")
    assert "(5 elements)" in cells[5] and cells[7] == speed["reproducer"]["replay"]  # type: ignore[index]
    # the same folder gives the same bytes
    first = (root / "clusters.json").read_bytes(), (root / "report.html").read_bytes()
    build_report(root)
    assert ((root / "clusters.json").read_bytes(), (root / "report.html").read_bytes()) == first


def test_the_same_requirement_after_other_signals_is_another_cluster(tmp_path: Path) -> None:
    root = tmp_path / "campaign"
    _campaign(root)
    # navigation's speeding now follows other signals: a failure of its own kind
    (run,) = [p for p in (root / "runs").iterdir() if p.name == "navigation.r01"]
    (run / "events.csv").write_bytes(_events(("SIG_MISSION_BEGIN", "SIG_HUMAN_NEAR",
                                              "SIG_OVER_SPEED_COMMANDED")))
    build_report(root, html=False)
    found = _clusters(root)
    assert sorted((c["requirement"], len(c["runs"])) for c in found) == [  # type: ignore[arg-type]
        ("NO_ROBOT_COLLISION", 4), ("SPEED_LIMIT", 1), ("SPEED_LIMIT", 3)]


def test_a_shrunk_case_is_the_reproducer_of_its_cluster(tmp_path: Path) -> None:
    root = tmp_path / "campaign"
    _campaign(root)
    shrunk = root / "shrunk" / "navigation"
    shrunk.mkdir(parents=True)
    replay = "rei run shrunk/navigation/navigation.mission -o replay --seed 0"
    (shrunk / "shrink.json").write_text(json.dumps({
        "result": "shrunk", "requirement": "SPEED_LIMIT",
        "mission_file": str((EXAMPLES / "navigation" / "navigation.mission").resolve()),
        "files": {"mission": "navigation.mission"}, "sizes": {"after": {"elements": 3}},
        "replay": replay}), encoding="utf-8")
    # a shrink of another requirement, or one that found nothing, is not used
    other = root / "shrunk" / "other"
    other.mkdir()
    (other / "shrink.json").write_text(json.dumps({"result": "passes"}), encoding="utf-8")
    build_report(root, html=False)
    speed = next(c for c in _clusters(root) if c["requirement"] == "SPEED_LIMIT")
    assert speed["reproducer"] == {
        "run": "navigation.r00", "mission": "shrunk/navigation/navigation.mission",
        "shrunk": True, "elements": 3, "time": 1.5, "reason": "SPEED_LIMIT broken",
        "replay": replay}
    collision = next(c for c in _clusters(root) if c["requirement"] != "SPEED_LIMIT")
    assert collision["reproducer"]["shrunk"] is False  # type: ignore[index]


def test_a_passing_campaign_has_no_clusters(tmp_path: Path) -> None:
    root = tmp_path / "campaign"
    _campaign(root, passing=True)
    build_report(root)
    assert _clusters(root) == []
    page = etree.HTML((root / "report.html").read_text(encoding="utf-8"))
    assert not page.xpath("//table[@id='failure-clusters']")
    assert page.xpath("string(//p[@id='no-failures'])").startswith("No failures")


def test_an_inconclusive_requirement_is_not_clustered_with_its_failures(tmp_path: Path) -> None:
    root = tmp_path / "campaign"
    _campaign(root, undecided=frozenset({"simple_wall.r00"}))
    # a shrink of simple_wall for SPEED_LIMIT reproduces its failure, not the undecided run
    shrunk = root / "shrunk" / "simple_wall"
    shrunk.mkdir(parents=True)
    (shrunk / "shrink.json").write_text(json.dumps({
        "result": "shrunk", "requirement": "SPEED_LIMIT",
        "mission_file": str((EXAMPLES / "simple_wall" / "simple_wall.mission").resolve()),
        "files": {"mission": "simple_wall.mission"}, "sizes": {"after": {"elements": 2}},
        "replay": "rei run shrunk/simple_wall/simple_wall.mission -o replay"}),
        encoding="utf-8")
    build_report(root, html=False)
    found = _clusters(root)
    assert [(c["requirement"], c["status"], c["runs"]) for c in found] == [
        ("NO_ROBOT_COLLISION", "fail",
         ["medium_sparse.r00", "medium_sparse.r01", "small_dense.r00", "small_dense.r01"]),
        ("SPEED_LIMIT", "fail", ["navigation.r00", "navigation.r01", "simple_wall.r01"]),
        ("SPEED_LIMIT", "inconclusive", ["simple_wall.r00"])]
    failed, undecided = found[1]["reproducer"], found[2]["reproducer"]
    assert failed["run"] == "simple_wall.r01" and failed["shrunk"] is True  # type: ignore[index]
    assert undecided["run"] == "simple_wall.r00" and undecided["shrunk"] is False  # type: ignore[index]
