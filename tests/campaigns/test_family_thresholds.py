"""bench/bugs.py --families: how a family's detection threshold is read off its campaigns (the
mildest severity caught on every seed), on made-up campaign outcomes, never a real campaign."""

from __future__ import annotations

import importlib
import os
import sys
from types import ModuleType

import pytest

from bench.knockouts import FAMILIES

RUNS = ("room_a.r00", "room_b.r00", "room_c.r00")
SEEDS = (1, 2)


@pytest.fixture
def bugs(monkeypatch: pytest.MonkeyPatch) -> ModuleType:
    """bench/bugs.py as a module (it puts the checkout on PYTHONPATH for its runs' processes
    when first imported: undone after the test)."""
    monkeypatch.setenv("PYTHONPATH", os.environ.get("PYTHONPATH", ""))
    monkeypatch.setattr(sys, "path", list(sys.path))
    return importlib.import_module("bench.bugs")


def campaign(bugs: ModuleType, name: str, seed: int, failing: dict[str, str],
             simulated: float = 10.0) -> object:
    """A campaign of ``RUNS`` on ``seed`` whose runs in ``failing`` fail that requirement
    (the baseline's room_c fails too: a failure it shares is no detection)."""
    runs = tuple(
        bugs.RunOutcome(run_id=run, seed=seed, passed=run not in failing, outcome="completed",
                        status="ran", reason="", simulated=simulated, task_failures=(),
                        failed=(failing[run],) if run in failing else (), inconclusive=())
        for run in RUNS)
    return bugs.CampaignOutcome(name, seed, 1.0, runs)


def test_the_threshold_is_the_mildest_severity_caught_on_every_seed(bugs: ModuleType) -> None:
    delay = next(f for f in FAMILIES if f.name == "delay")
    mild, second, third, severe = delay.severities
    shared = {"room_c.r00": "MISSION_SIMPLE"}
    caught = {seed: {**shared, "room_a.r00": "REACTION_TIME"} for seed in SEEDS}
    outcomes = {
        "reference": [campaign(bugs, "reference", s, shared) for s in SEEDS],
        # mild: fails only what the baseline fails too, in a different time: not caught
        f"delay_{mild}": [campaign(bugs, "m", s, shared, 11.0) for s in SEEDS],
        f"delay_{second}": [campaign(bugs, "2", s, caught[s]) for s in SEEDS],
        f"delay_{third}": [campaign(bugs, "3", 1, caught[1]), campaign(bugs, "3", 2, shared)],
        f"delay_{severe}": [campaign(bugs, "s", s, caught[s]) for s in SEEDS],
    }
    navs = [bugs.Navigator("reference", "baseline", "reference", "")] + [
        bugs.Navigator(name, "delay", f"bench.knockouts:{name}", "")
        for name in outcomes if name != "reference"]
    summary = bugs.summarise(navs, outcomes, list(SEEDS), "reference")
    (row,) = bugs.family_rows([delay], summary, outcomes, "reference")
    assert row["threshold"] == second  # third is missed on seed 2, second is not
    assert row["missed_beyond_threshold"] == [third]
    by = {e["severity"]: e for e in row["severities"]}
    assert [by[s]["seeds_caught"] for s in delay.severities] == [0, 2, 1, 2]
    assert by[third]["caught_seeds"] == [1]
    assert by[second]["caught_by"] == {"REACTION_TIME": 2}
    assert not by[mild]["same_as_baseline"]  # its runs took longer
    table = bugs.family_table([row], summary, "reference", False, markdown=True)
    assert f"| delay | commands N ms late | commands {second} ms late (yet missed on some " \
           f"seed at the more severe {third}) |" in table


def test_a_threshold_at_the_mildest_severity_says_the_limit_is_milder(bugs: ModuleType) -> None:
    tolerance = next(f for f in FAMILIES if f.name == "tolerance")
    outcomes = {"reference": [campaign(bugs, "reference", s, {}) for s in SEEDS]}
    outcomes |= {f"tolerance_{v}": [campaign(bugs, "t", s, {"room_a.r00": "GOALS"})
                                    for s in SEEDS] for v in tolerance.severities}
    navs = [bugs.Navigator(name, "", "", "") for name in outcomes]
    summary = bugs.summarise(navs, outcomes, list(SEEDS), "reference")
    (row,) = bugs.family_rows([tolerance], summary, outcomes, "reference")
    assert row["threshold"] == tolerance.severities[0]
    table = bugs.family_table([row], summary, "reference", False, markdown=True)
    assert "goal tolerance × 1.5 (the mildest tried: the suite's limit is milder still)" in table


def test_a_knockout_whose_runs_all_end_as_the_baselines_is_reported_so(bugs: ModuleType) -> None:
    base = [campaign(bugs, "reference", s, {}) for s in SEEDS]
    same = [campaign(bugs, "x", s, {}) for s in SEEDS]
    longer = [campaign(bugs, "x", s, {}, 10.5) for s in SEEDS]
    assert bugs.same_as_baseline(same, base)
    assert not bugs.same_as_baseline(longer, base)
    assert not bugs.caught_on(same[0], base[0])
    assert bugs.caught_on(campaign(bugs, "x", 1, {"room_b.r00": "SPEED_LIMIT"}), base[0])


def test_no_severity_caught_on_every_seed_is_no_threshold(bugs: ModuleType) -> None:
    footprint = next(f for f in FAMILIES if f.name == "footprint")
    outcomes = {"reference": [campaign(bugs, "reference", s, {}) for s in SEEDS]}
    outcomes |= {f"footprint_{s}": [campaign(bugs, "f", 1, {"room_a.r00": "NO_ROBOT_COLLISION"}),
                                    campaign(bugs, "f", 2, {})]
                 for s in footprint.severities[-1:]}  # only the most severe ran
    navs = [bugs.Navigator(name, "", "", "") for name in outcomes]
    summary = bugs.summarise(navs, outcomes, list(SEEDS), "reference")
    (row,) = bugs.family_rows([footprint], summary, outcomes, "reference")
    assert row["threshold"] is None
    assert [e["run"] for e in row["severities"]] == [False, False, False, True]
    plain = bugs.family_table([row], summary, "reference", True, markdown=False)
    assert "none (no severity caught on every seed)" in plain and "90: not run" in plain
