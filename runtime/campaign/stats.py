"""Statistics over recorded runs that users can trust: success rates with Wilson intervals.

A rate from 3 repeats is not a rate from 300: every rate carries its Wilson score interval
(95 % by default), which stays inside [0, 1] and is sensible at 0 and at n successes, unlike
the normal approximation. A mission whose repeats disagree (some pass, some fail) is labelled
flaky. This module must never read files.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from statistics import NormalDist

from rei.runtime.campaign.store import RunRecord


@dataclass(frozen=True)
class SuccessRate:
    key: str
    runs: int
    passed: int
    rate: float
    low: float
    high: float
    """Wilson score interval of the success probability at the chosen confidence."""

    @property
    def flaky(self) -> bool:
        """Repeats disagree: at least one passed and at least one did not."""
        return 0 < self.passed < self.runs


def wilson_interval(successes: int, trials: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (Wilson 1927)."""
    if trials <= 0:
        return 0.0, 1.0
    if not 0 <= successes <= trials:
        raise ValueError(f"successes must be within 0..{trials}, found {successes}")
    z = NormalDist().inv_cdf(0.5 + confidence / 2)
    p = successes / trials
    z2n = z * z / trials
    centre = (p + z2n / 2) / (1 + z2n)
    half = z * math.sqrt(p * (1 - p) / trials + z2n / (4 * trials)) / (1 + z2n)
    # Exact bounds at the extremes: rounding must not exclude the observed all-or-nothing rate.
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == trials else min(1.0, centre + half)
    return low, high


def success_rates(records: Iterable[RunRecord], key: Callable[[RunRecord], str],
                  confidence: float = 0.95) -> list[SuccessRate]:
    """One rate per key (mission, group, ...), keys in first-seen order."""
    counts: dict[str, list[int]] = {}
    for record in records:
        entry = counts.setdefault(key(record), [0, 0])
        entry[0] += 1
        entry[1] += int(record.passed)
    out = []
    for name, (runs, passed) in counts.items():
        low, high = wilson_interval(passed, runs, confidence)
        out.append(SuccessRate(name, runs, passed, passed / runs, low, high))
    return out


def by_mission(record: RunRecord) -> str:
    return record.spec.run_id.rsplit(".r", 1)[0]


def by_group(record: RunRecord) -> str:
    return record.spec.group
