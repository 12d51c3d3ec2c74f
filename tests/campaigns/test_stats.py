"""Success rates with Wilson intervals, the flaky label, and mission verdicts against a
required pass rate."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rei.runtime.campaigns import (
    CampaignStore,
    SuccessRate,
    campaign_passed,
    mission_verdicts,
    success_rates,
    wilson_interval,
)
from rei.runtime.campaigns.stats import by_group, by_mission, judge_mission
from rei.runtime.campaigns.store import required_pass_rate
from rei.runtime.commands.cli import main
from tests.campaigns.records import EXAMPLES, example_plan, write_campaign


@pytest.mark.parametrize(("k", "n", "low", "high"), [
    # Reference values: Wilson score interval, z = 1.959964 (e.g. R's prop.test without
    # continuity correction, or statsmodels proportion_confint(method="wilson")).
    (0, 10, 0.0, 0.2775),
    (5, 10, 0.2366, 0.7634),
    (10, 10, 0.7225, 1.0),
    (1, 3, 0.0615, 0.7923),
    (81, 263, 0.2553, 0.3662),
])
def test_wilson_reference_values(k: int, n: int, low: float, high: float) -> None:
    assert wilson_interval(k, n) == pytest.approx((low, high), abs=5e-5)


@given(st.integers(1, 500).flatmap(lambda n: st.tuples(st.integers(0, n), st.just(n))))
def test_wilson_contains_the_observed_rate_and_stays_in_bounds(kn: tuple[int, int]) -> None:
    k, n = kn
    low, high = wilson_interval(k, n)
    assert 0.0 <= low <= k / n <= high <= 1.0
    wider = wilson_interval(k, n, confidence=0.99)
    assert wider[0] <= low + 1e-12 and wider[1] >= high - 1e-12


def test_rates_and_flaky_label_per_mission_and_group(tmp_path: Path) -> None:
    write_campaign(tmp_path)
    _, _, records = CampaignStore.read(tmp_path)
    rates = {r.key: r for r in success_rates(records, by_mission)}
    assert (rates["simple_wall"].passed, rates["simple_wall"].runs) == (3, 3)
    assert not rates["simple_wall"].flaky
    assert rates["navigation"].flaky and rates["small_dense"].flaky
    assert rates["medium_sparse"].passed == 0 and not rates["medium_sparse"].flaky
    assert rates["navigation"].rate == pytest.approx(2 / 3)
    (group,) = success_rates(records, by_group)
    assert (group.key, group.runs, group.passed) == ("examples", 12, 7)


# -- mission verdicts against a required pass rate ---------------------------------------


def _rate(passed: int, runs: int) -> SuccessRate:
    low, high = wilson_interval(passed, runs)
    return SuccessRate("m", runs, passed, passed / runs, low, high)


@pytest.mark.parametrize(("passed", "runs", "required", "verdict"), [
    (3, 3, 1.0, "pass"),     # the default: every run must pass
    (2, 3, 1.0, "fail"),     # one failure refutes a required rate of 1
    (3, 3, 0.9, "pass"),     # Wilson [0.44, 1] straddles 0.9, but no run contradicts it
    (29, 30, 0.9, "flaky"),  # [0.83, 0.99]: a failure, and 0.9 not yet confirmed nor refuted
    (2, 3, 0.5, "flaky"),
    (0, 3, 0.5, "fail"),     # straddles 0.5, but nothing ever passed
    (9, 10, 0.5, "pass"),    # [0.60, 0.98] lies above 0.5: confidently at or above
    (5, 10, 0.9, "fail"),    # [0.24, 0.76] lies below 0.9
    (0, 3, 0.0, "pass"),     # nothing required
])
def test_mission_verdict_rule(passed: int, runs: int, required: float, verdict: str) -> None:
    judged = judge_mission(_rate(passed, runs), required)
    assert judged.verdict == verdict, judged.reason
    assert f"{passed}/{runs} passed" in judged.reason


@given(st.integers(1, 60).flatmap(lambda n: st.tuples(st.integers(0, n), st.just(n))),
       st.floats(0.0, 1.0))
def test_verdicts_follow_the_wilson_interval(kn: tuple[int, int], required: float) -> None:
    k, n = kn
    rate = _rate(k, n)
    verdict = judge_mission(rate, required).verdict
    if rate.low >= required:
        assert verdict == "pass"
    elif rate.high < required:
        assert verdict == "fail"
    else:  # the interval straddles the required rate: flaky exactly when the runs disagree
        assert (verdict == "flaky") == rate.flaky
    # Requiring less never turns a passing mission into a failing or flaky one.
    if verdict == "pass":
        assert judge_mission(rate, required / 2).verdict == "pass"


def test_a_required_rate_outside_0_to_1_is_refused() -> None:
    with pytest.raises(ValueError, match="from 0 to 1, found 1.5"):
        judge_mission(_rate(1, 1), 1.5)


def test_mission_verdicts_of_a_campaign_and_the_rate_it_required(tmp_path: Path) -> None:
    write_campaign(tmp_path)
    _, manifest, records = CampaignStore.read(tmp_path)
    verdicts = {v.mission: v.verdict for v in mission_verdicts(records)}
    assert verdicts == {"medium_sparse": "fail", "navigation": "fail", "simple_wall": "pass",
                        "small_dense": "fail"}
    lenient = {v.mission: v.verdict for v in mission_verdicts(records, 0.5)}
    assert lenient == {"medium_sparse": "fail", "navigation": "flaky", "simple_wall": "pass",
                       "small_dense": "flaky"}
    assert not campaign_passed(mission_verdicts(records, 0.5))
    assert campaign_passed(mission_verdicts(records, 0.0))
    # `rei report DIR` judges as the last session did; folders from before --pass-rate: 1.0.
    assert required_pass_rate(manifest) == 1.0
    sessions = [{"pass_rate": 0.5}, {"pass_rate": 0.8}, {"command": ["rei"]}]
    assert required_pass_rate({"sessions": sessions}) == 0.8


def test_the_exit_status_follows_the_mission_verdicts(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    from rei.lang.cli_support import EXIT_FAILED, EXIT_OK, EXIT_RUN_ERROR
    from rei.runtime.commands.campaign import finish

    plan = example_plan()
    # Without small_dense (whose first repeat crashes): the verdicts alone decide.
    write_campaign(tmp_path / "ran", replace(plan, runs=tuple(
        r for r in plan.runs if not r.run_id.startswith("small_dense"))))
    assert finish(tmp_path / "ran", no_report=True) == EXIT_FAILED  # every run must pass
    assert "FAIL   medium_sparse: 0/3 passed" in capsys.readouterr().err
    assert finish(tmp_path / "ran", no_report=True, pass_rate=0.5) == EXIT_FAILED  # flaky
    assert "FLAKY  navigation: 2/3 passed" in capsys.readouterr().err
    assert finish(tmp_path / "ran", no_report=True, pass_rate=0.0) == EXIT_OK
    # A crashed run is a run error whatever the pass rate: nothing may hide it.
    write_campaign(tmp_path / "crash", plan)
    assert finish(tmp_path / "crash", no_report=True, pass_rate=0.0) == EXIT_RUN_ERROR
    assert "verdict: ERROR; 4 of 4 missions passed; 1 run(s) errored" in capsys.readouterr().out


@pytest.mark.parametrize("value", ["1.5", "-0.1", "nan", "ninety"])
def test_a_bad_pass_rate_on_the_command_line_is_a_located_input_error(
        value: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["campaign", str(EXAMPLES / "simple_wall"), "-o", str(tmp_path / "c"),
              "--pass-rate", value])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "argument --pass-rate: expected a rate from 0 to 1" in err
    assert f"found '{value}'" in err
    assert not (tmp_path / "c").exists()  # refused before anything is written
