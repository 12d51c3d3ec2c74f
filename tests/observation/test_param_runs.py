"""`--param` on real pybullet runs: a correct navigator whose forward protective field is
0.7 m (the reference's 1.05 m narrowed) fails REACTION_TIME against the default .vepl's
react_zone = 1.05 m whatever its latency, and passes with `--param react_zone=0.7` — the
documented way to judge such a robot (docs/vepl.md, "Reaction time"). In the emerging-person
stress room of `rei demo`'s suite (seed 1, as tests/observation/test_reaction_runs.py). The run
records the value (summary.json, run.log, its page), the same scenario, seed and value write
the same bytes, replaying the failing run's trace with the value passes it (and without it
fails it again), and `rei run` itself (the supervised child) takes the option and refuses an
undeclared name with exit 2."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from rei.runtime.commands.cli import main as rei
from rei.runtime.commands.demo import generate_suite
from rei.runtime.commands.replay import replay
from rei.runtime.results import RunSummary, Verdict
from rei.runtime.robot.navigator.reference import ReferenceNavigator
from rei.runtime.runs.session import run_into

REPO = Path(__file__).resolve().parents[2]
SEED = 1
HERE = "tests.observation.test_param_runs"
FIELD = (("react_zone", 0.7),)


class Field07(ReferenceNavigator):
    """The reference navigator with a 0.7 m protective field: it slows to its cap only when
    an unmapped laser point is within 0.7 m of its footprint (not 1.05 m)."""

    slow_zone_reach = 0.7


def _verdicts(summary: RunSummary) -> dict[str, Verdict]:
    return {v.requirement: v for v in summary.verdicts}


@pytest.mark.slow
def test_a_narrower_protective_field_is_judged_with_the_matching_react_zone(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capfd: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p))
    generate_suite(tmp_path / "suite", 6, "small", SEED)
    mission = tmp_path / "suite" / "stress" / "stress_0001.mission"
    assert "stressor: kind=emerge" in mission.with_suffix(".room").read_text(encoding="utf-8")
    controller = f"{HERE}:Field07"

    default, _ = run_into(mission, tmp_path / "default", controller=controller, seed=SEED)
    tuned, _ = run_into(mission, tmp_path / "tuned", controller=controller, seed=SEED,
                        parameters=FIELD)
    # the verdict really changes with the value, and only REACTION_TIME does
    assert _verdicts(default)["REACTION_TIME"].status == "fail"
    assert _verdicts(tuned)["REACTION_TIME"].status == "pass"
    assert default.verdict == "fail" and tuned.verdict == "pass"
    assert {k: v.status for k, v in _verdicts(default).items() if k != "REACTION_TIME"} == \
        {k: v.status for k, v in _verdicts(tuned).items() if k != "REACTION_TIME"}
    # the value is part of the record
    assert default.parameters == {} and tuned.parameters == {"react_zone": 0.7}
    written = json.loads((tmp_path / "tuned" / "summary.json").read_text(encoding="utf-8"))
    assert written["parameters"] == {"react_zone": 0.7}
    assert "parameters" not in json.loads(
        (tmp_path / "default" / "summary.json").read_text(encoding="utf-8"))
    assert "specification parameters set by --param: react_zone=0.7" in \
        (tmp_path / "tuned" / "run.log").read_text(encoding="utf-8")
    automata = (tmp_path / "tuned" / "automata" / "automata.py").read_text(encoding="utf-8")
    assert "w.hazard_clearance < 0.7" in automata

    # same scenario + seed + value: the same bytes
    run_into(mission, tmp_path / "again", controller=controller, seed=SEED, parameters=FIELD)
    for name in ("summary.json", "events.csv", "trace.jsonl"):
        assert (tmp_path / "again" / name).read_bytes() == \
            (tmp_path / "tuned" / name).read_bytes()

    # the failing run's trace, judged again with the value, passes; without it, fails
    judged = replay(tmp_path / "default" / "trace.jsonl", None, tmp_path / "replayed",
                    parameters=FIELD)
    assert _verdicts(judged)["REACTION_TIME"].status == "pass"
    assert judged.parameters == {"react_zone": 0.7}
    assert judged.verdicts == tuned.verdicts
    plain = replay(tmp_path / "default" / "trace.jsonl", None, tmp_path / "replayed-plain")
    assert plain.verdicts == default.verdicts

    # `rei run` (its supervised child) takes the option, and shows it on the run's page
    capfd.readouterr()
    assert rei(["run", str(mission), "-o", str(tmp_path / "cli"), "--seed", str(SEED),
                "--controller", controller, "--param", "react_zone=0.7", "-q"]) == 0
    assert (tmp_path / "cli" / "summary.json").read_bytes() == \
        (tmp_path / "tuned" / "summary.json").read_bytes()
    page = (tmp_path / "cli" / "report.html").read_text(encoding="utf-8")
    assert '<dd id="parameters">react_zone=0.7</dd>' in page
    capfd.readouterr()
    assert rei(["run", str(mission), "-o", str(tmp_path / "bad"), "--seed", str(SEED),
                "--param", "react_zon=0.7", "-q"]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did you mean 'react_zone'?" in err[0], err
    assert not (tmp_path / "bad" / "summary.json").exists()


@pytest.mark.slow
def test_a_campaign_passes_records_and_keeps_its_values(tmp_path: Path) -> None:
    """A real campaign (its runs are `rei run` processes) with --param: each run's summary,
    the plan, the re-run command, junit.xml and the report carry the value; resuming with
    another value is refused (exit 2) and leaves the folder as it was."""
    from lxml import etree  # noqa: PLC0415

    out = tmp_path / "campaign"
    mission = str(REPO / "examples" / "simple_wall" / "simple_wall.mission")
    common = ["campaign", mission, "-o", str(out), "--duration", "2", "--workers", "1",
              "--seed", "4"]
    status = rei([*common, "--param", "react_zone=0.7", "--param", "slow_speed=0.2", "-q"])
    assert status in (0, 1)  # 2 s of a mission: the verdict is not what this test is about
    [summary] = list((out / "runs").glob("*/summary.json"))
    written = json.loads(summary.read_text(encoding="utf-8"))
    assert written["parameters"] == {"react_zone": 0.7, "slow_speed": 0.2}
    manifest = json.loads((out / "campaign.json").read_text(encoding="utf-8"))
    [run] = manifest["plan"]["runs"]
    assert run["vepl_parameters"] == {"react_zone": 0.7, "slow_speed": 0.2}
    junit = etree.parse(str(out / "junit.xml"))
    values = {p.get("name"): p.get("value") for p in junit.iter("property")}
    assert values["param.react_zone"] == "0.7" and values["param.slow_speed"] == "0.2"
    assert "--param react_zone=0.7 --param slow_speed=0.2" in values["rerun"]
    report = (out / "report.html").read_text(encoding="utf-8")
    assert '<p id="parameters">' in report and "<code>react_zone=0.7</code>" in report

    before = (out / "campaign.json").read_bytes()
    assert rei([*common, "--param", "react_zone=0.8", "--param", "slow_speed=0.2", "-q"]) == 2
    assert rei([*common, "-q"]) == 2
    assert (out / "campaign.json").read_bytes() == before
    # the same values resume it (nothing left to run)
    assert rei([*common, "--param", "slow_speed=0.2", "--param", "react_zone=0.7", "-q"]) \
        == status
