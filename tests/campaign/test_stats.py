"""Success rates with Wilson intervals, and the flaky label."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rei.runtime.campaign import CampaignStore, success_rates, wilson_interval
from rei.runtime.campaign.stats import by_group, by_mission

from .records import write_campaign


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
