"""Statistics over recorded runs that users can trust: success rates with Wilson intervals.

A rate from 3 repeats is not a rate from 300: every rate carries its Wilson score interval
(95 % by default), which stays inside [0, 1] and is sensible at 0 and at n successes, unlike
the normal approximation. A mission whose repeats disagree (some pass, some fail) is labelled
flaky. Against a required pass rate each mission gets one verdict (``mission_verdicts``), and
with ``--pair-static`` each failing mission is told apart by whether its runs in the same room
without people fail too (``classify_pairs``). The campaign's status and exit code
(``campaign_outcome``: the one rule behind `rei campaign`, `rei demo` and `rei report`),
junit.xml and the report all take the verdicts from here, so they cannot disagree. This module
must never read files.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from statistics import NormalDist
from typing import Literal

from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_ERROR
from rei.runtime.campaigns.run_records import RunRecord


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


# -- mission verdicts against a required pass rate ---------------------------------------

DEFAULT_PASS_RATE = 1.0
"""Every run must pass: without --pass-rate a campaign is as strict as its runs (exit status 0
only when every run passed), which is what a CI job that never asked for a rate expects."""

MissionVerdictKind = Literal["pass", "fail", "flaky", "inconclusive"]

FAILING_RUNS = frozenset({"fail", "error"})
"""Run verdicts that show something wrong; the others that do not pass (inconclusive,
unjudged, interrupted) only leave the question open."""


@dataclass(frozen=True)
class MissionVerdict:
    """One mission judged against the required pass rate, on the Wilson interval of its rate."""

    rate: SuccessRate
    required: float
    verdict: MissionVerdictKind
    reason: str

    @property
    def mission(self) -> str:
        return self.rate.key


def check_pass_rate(required: float) -> float:
    """The required pass rate, checked (a number from 0 to 1)."""
    if not (math.isfinite(required) and 0.0 <= required <= 1.0):
        raise ValueError(f"expected a required pass rate from 0 to 1, found {required}")
    return required


def judge_mission(rate: SuccessRate, required: float) -> MissionVerdict:
    """The verdict of one mission; the rule of docs/campaign.md ("Mission verdicts").

    pass:  the interval lies at or above the required rate (low >= P), or it straddles P and
           every run passed (no run contradicts P; a handful of repeats cannot prove more);
    fail:  the interval lies below it (high < P), or it straddles P and no run passed;
    flaky: the interval straddles P (low < P <= high) and the repeats disagree: the runs so far
           neither confirm nor refute P — repeat more, or find why some runs fail.
    """
    check_pass_rate(required)
    where = (f"{rate.passed}/{rate.runs} passed, rate {rate.rate:.2f}, "
             f"Wilson [{rate.low:.2f}, {rate.high:.2f}], required {required:g}")
    if rate.runs == 0:
        return MissionVerdict(rate, required, "fail", "no run recorded")
    if rate.low >= required:
        return MissionVerdict(rate, required, "pass", f"{where}: interval at or above")
    if rate.high < required:
        return MissionVerdict(rate, required, "fail", f"{where}: interval below")
    if rate.passed == rate.runs:
        return MissionVerdict(rate, required, "pass",
                              f"{where}: every run passed (the interval is wide only because "
                              f"the runs are few)")
    if rate.passed == 0:
        return MissionVerdict(rate, required, "fail", f"{where}: no run passed")
    return MissionVerdict(rate, required, "flaky",
                          f"{where}: the runs disagree and the interval includes the "
                          f"required rate; repeat more")


def mission_verdicts(records: Iterable[RunRecord], required: float = DEFAULT_PASS_RATE,
                     confidence: float = 0.95) -> list[MissionVerdict]:
    """One verdict per mission in first-seen order. Paired static runs (``--pair-static``) are
    a diagnosis, not the mission under test: they never count towards its verdict."""
    check_pass_rate(required)
    tested = [r for r in records if not r.spec.static_pair]
    failing = {by_mission(r) for r in tested if r.verdict in FAILING_RUNS}
    out = []
    for rate in success_rates(tested, by_mission, confidence):
        verdict = judge_mission(rate, required)
        if verdict.verdict != "pass" and rate.key not in failing:
            # Nothing failed, something was not decided: the mission is an open question, not
            # a failure (a smoke test cut short by --duration is the common case).
            verdict = MissionVerdict(rate, required, "inconclusive",
                                     f"{verdict.reason}; no run failed, "
                                     f"{rate.runs - rate.passed} inconclusive")
        out.append(verdict)
    return out


def campaign_passed(verdicts: Iterable[MissionVerdict]) -> bool:
    """Every mission passed; a flaky or inconclusive one does not (CI must not go green on an
    open question)."""
    return all(v.verdict == "pass" for v in verdicts)


# -- the campaign's one status and exit code ---------------------------------------------

CampaignStatus = Literal["pass", "fail", "inconclusive", "error", "interrupted", "incomplete"]


@dataclass(frozen=True)
class CampaignOutcome:
    """What a campaign folder says as a whole: its status word and the exit code of every
    command that reports on it (`rei campaign`, `rei demo`, `rei report`)."""

    status: CampaignStatus
    exit_code: int
    missions: int
    missions_passed: int
    run_errors: int
    """Runs (static twins included) that crashed, hung or ended in a run error."""
    missing: int
    """Planned runs with no record."""

    def line(self) -> str:
        """The final line the commands print (before the report's location)."""
        more = [f"{self.run_errors} run(s) errored"] if self.run_errors else []
        if self.missing:
            more.append(f"{self.missing} planned run(s) not recorded")
        return (f"verdict: {self.status.upper()}; {self.missions_passed} of {self.missions} "
                f"missions passed" + "".join(f"; {m}" for m in more))


def campaign_outcome(records: Iterable[RunRecord], verdicts: Iterable[MissionVerdict], *,
                     planned: int, interrupted: bool = False) -> CampaignOutcome:
    """The exit rule of a campaign, in order of precedence:

    130 interrupted (the session stopped before its runs were done; resume it);
    3   a run errored (crashed, hung, the controller raised, a bad mission file): the campaign
        could not judge that run, which no pass rate may hide;
    1   a mission failed or is flaky (status "fail"), or none failed but one is inconclusive
        (status "inconclusive"), or planned runs have no record (status "incomplete");
    0   every mission passed and every planned run is recorded.
    """
    runs = list(records)
    judged = list(verdicts)
    errors = sum(r.verdict == "error" for r in runs)
    kinds = {v.verdict for v in judged}
    missing = max(0, planned - len(runs))
    status: CampaignStatus
    if interrupted:
        status, code = "interrupted", EXIT_INTERRUPTED
    elif errors:
        status, code = "error", EXIT_RUN_ERROR
    elif kinds & {"fail", "flaky"}:
        status, code = "fail", EXIT_FAILED
    elif "inconclusive" in kinds:
        status, code = "inconclusive", EXIT_FAILED
    elif missing or not judged:
        status, code = "incomplete", EXIT_FAILED
    else:
        status, code = "pass", EXIT_OK
    return CampaignOutcome(status, code, len(judged), sum(v.verdict == "pass" for v in judged),
                           errors, missing)


# -- paired static runs: the people or the room? ----------------------------------------

PairCause = Literal["passes", "fails with people only", "fails in the static room too",
                    "inconclusive with people only", "inconclusive in the static room too"]


@dataclass(frozen=True)
class PairedMission:
    """A mission's runs next to their twins in the same room without humans and dynamic
    objects (same seed, so the same start pose and laser noise)."""

    mission: str
    with_people: SuccessRate
    static: SuccessRate
    failed_pairs: int
    """Pairs whose run with people failed."""
    failed_static_too: int
    """Of those, pairs whose static twin failed as well."""
    cause: PairCause


def classify_pairs(records: Iterable[RunRecord], confidence: float = 0.95
                   ) -> list[PairedMission]:
    """Per paired mission: "passes" when every run with people passed; "fails in the static
    room too" when some failing run's static twin failed as well (the room, the navigator or
    the mission is the problem, people or not); else "fails with people only". A mission whose
    runs with people did not pass but none failed (inconclusive, as in a smoke test cut short)
    is "inconclusive in the static room too" or "inconclusive with people only" alike: an
    open question is never labelled a failure. "Failed" is a run verdict of fail or error."""
    all_records = list(records)
    static = {r.spec.pair: r for r in all_records if r.spec.static_pair}
    people = [r for r in all_records if not r.spec.static_pair and r.spec.pair in static]
    rates = {rate.key: rate for rate in success_rates(people, by_mission, confidence)}
    static_rates = {rate.key: rate for rate in success_rates(
        [static[r.spec.pair] for r in people], lambda r: by_mission_of_pair(r), confidence)}
    failed: dict[str, int] = {}
    both: dict[str, int] = {}
    really: set[str] = set()
    """Missions with a run with people that failed (not only inconclusive ones)."""
    static_fails: set[str] = set()
    for record in people:
        key = by_mission(record)
        if not record.passed:
            failed[key] = failed.get(key, 0) + 1
            twin = static[record.spec.pair]
            if not twin.passed:
                both[key] = both.get(key, 0) + 1
            if record.verdict in FAILING_RUNS:
                really.add(key)
                if twin.verdict in FAILING_RUNS:
                    static_fails.add(key)
    out = []
    for key, rate in rates.items():
        cause: PairCause
        if not failed.get(key):
            cause = "passes"
        elif key in really:
            cause = ("fails in the static room too" if key in static_fails
                     else "fails with people only")
        else:
            cause = ("inconclusive in the static room too" if both.get(key)
                     else "inconclusive with people only")
        out.append(PairedMission(key, rate, static_rates[key], failed.get(key, 0),
                                 both.get(key, 0), cause))
    return out


def by_mission_of_pair(record: RunRecord) -> str:
    """The mission a run belongs to, its static twin included (grouped with the original)."""
    return record.spec.pair.rsplit(".r", 1)[0] if record.spec.pair else by_mission(record)
