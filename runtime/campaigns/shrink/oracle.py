"""Does a candidate case still fail? Its K seeded runs through the campaign's local engine.

Every candidate runs as `rei run` processes (rei.runtime.campaigns.engines.LocalEngine: each in
its own supervised process, ``workers`` at once, on workers kept for the whole shrink), one per
seed, and its outcome is kept by the
case's digest, in memory and in a JSON-lines file, so an identical candidate never runs twice
and a shrink started again over the same output folder resumes without rerunning anything.
This module must never edit a case; it only judges one.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rei.runtime.campaigns.engines import LocalEngine, WorkerPool
from rei.runtime.campaigns.plan import RunSpec
from rei.runtime.campaigns.shrink.case import ScenarioCase
from rei.runtime.results import RunSummary, failed_verdicts


@dataclass(frozen=True)
class SeedOutcome:
    """One run of a candidate: its seed, the run's verdict (``judge``; ``invalid`` when
    `rei run` refused its input), the requirements that failed in it (earliest first; none
    when the run broke: a run error is no failure of a requirement) and every requirement
    it judged."""

    seed: int
    verdict: str
    failed: tuple[str, ...]
    message: str = ""
    """Why the run broke (run error, crash, hang); empty when it ran."""
    judged: tuple[str, ...] = ()
    """The requirements the run has verdicts for (empty: unknown, e.g. journaled by an older
    REI or a run that broke before judging)."""

    def to_json(self) -> dict[str, Any]:
        return {"seed": self.seed, "verdict": self.verdict, "failed": list(self.failed),
                **({"message": self.message} if self.message else {}),
                **({"judged": list(self.judged)} if self.judged else {})}

    @staticmethod
    def from_json(data: dict[str, Any]) -> SeedOutcome:
        return SeedOutcome(int(data["seed"]), str(data["verdict"]),
                           tuple(str(r) for r in data["failed"]), str(data.get("message", "")),
                           tuple(str(r) for r in data.get("judged", ())))


@dataclass(frozen=True)
class RunSettings:
    """How every candidate runs: what `rei run` gets besides the mission and the seed."""

    seeds: tuple[int, ...]
    controller: str | None = None
    vepl: str | None = None
    functions: str | None = None
    duration: float | None = None
    variation: bool = True
    workers: int = 1
    timeout: float | None = None
    vepl_parameters: tuple[tuple[str, float], ...] = ()
    """`rei run --param`: the specification's parameter values, sorted by name."""

    def spec(self, mission: Path, seed: int, run_id: str) -> RunSpec:
        return RunSpec(run_id=run_id, mission_file=str(mission.resolve()),
                       mission_key=f"{mission.parent.name}/{mission.name}", group="shrink",
                       repeat=self.seeds.index(seed), seed=seed, controller=self.controller,
                       vepl=self.vepl, duration=self.duration, variation=self.variation,
                       functions=self.functions, vepl_parameters=self.vepl_parameters)

    def describe(self) -> dict[str, Any]:
        described: dict[str, Any] = {
            "seeds": list(self.seeds), "controller": self.controller or "reference",
            "vepl": self.vepl, "functions": self.functions, "duration": self.duration,
            "variation": self.variation}
        if self.vepl_parameters:  # part of what a journal entry was judged with
            described["vepl_parameters"] = dict(self.vepl_parameters)
        return described


@dataclass
class FailureOracle:
    """Runs candidates on every seed; remembers each digest's outcomes."""

    settings: RunSettings
    work: Path
    """Scratch folder: candidates' files and runs (each run's folder goes once read)."""
    journal: Path
    """JSON lines {digest, settings, outcomes}: what earlier sessions found."""
    runs: int = 0
    """Runs judged: every distinct candidate's seeds once per session, whether they ran now
    or came from the journal (so a resumed shrink reports and budgets exactly as an
    uninterrupted one)."""
    started: int = 0
    """Runs this session actually started."""
    known: dict[str, tuple[SeedOutcome, ...]] = field(default_factory=dict)
    charged: set[str] = field(default_factory=set)
    """Digests already counted in ``runs`` this session: judging one again costs nothing."""
    pool: WorkerPool | None = None
    """The workers every candidate runs on (kept for the shrink: their fork servers' imports
    are paid once, not per candidate); None: each candidate starts its own."""

    def __post_init__(self) -> None:
        self.work.mkdir(parents=True, exist_ok=True)
        try:
            lines = self.journal.read_text(encoding="utf-8").splitlines()
        except OSError:
            return
        settings = self.settings.describe()
        for line in lines:
            try:
                entry = json.loads(line)
                if entry.get("settings") == settings:
                    self.known[str(entry["digest"])] = tuple(
                        SeedOutcome.from_json(o) for o in entry["outcomes"])
            except (ValueError, KeyError, TypeError, AttributeError):
                continue  # a line cut short by an interruption: that candidate runs again

    def cost(self, case: ScenarioCase) -> int:
        """The runs judging ``case`` adds to ``runs``: none when this session judged it."""
        return 0 if case.digest() in self.charged else len(self.settings.seeds)

    def outcomes(self, case: ScenarioCase) -> tuple[SeedOutcome, ...]:
        """The candidate's outcome on every seed (from the journal when known)."""
        digest = case.digest()
        if digest not in self.charged:
            self.charged.add(digest)
            self.runs += len(self.settings.seeds)
        if digest in self.known:
            return self.known[digest]
        folder = self.work / digest[:16]
        mission = case.write(folder / "case")
        specs = [self.settings.spec(mission, seed, f"s{seed}") for seed in self.settings.seeds]
        engine = LocalEngine(self.settings.workers, timeout=self.settings.timeout,
                             cache=self.work / "cache", pages="none", pool=self.pool)
        by_seed: dict[int, SeedOutcome] = {}
        for spec, run_dir, result in engine.execute(specs, lambda s: folder / "runs" / s.run_id):
            self.started += 1
            by_seed[spec.seed] = _outcome(spec.seed, result.status, result.summary,
                                          result.message, result.exit_code)
            shutil.rmtree(run_dir, ignore_errors=True)
        outcomes = tuple(by_seed[s] for s in self.settings.seeds)
        if any(o.verdict == "interrupted" for o in outcomes):
            raise KeyboardInterrupt  # the user stopped the runs: nothing to remember
        shutil.rmtree(folder, ignore_errors=True)
        self.known[digest] = outcomes
        if any(o.verdict in ("error", "invalid") for o in outcomes):
            return outcomes  # not remembered: a broken run may not break again
        with self.journal.open("a", encoding="utf-8") as journal:
            journal.write(json.dumps({"digest": digest, "settings": self.settings.describe(),
                                      "outcomes": [o.to_json() for o in outcomes]},
                                     sort_keys=True) + "\n")
        return outcomes


def _outcome(seed: int, status: str, summary: dict[str, Any] | None, message: str,
             exit_code: int | None = None) -> SeedOutcome:
    if status == "interrupted":
        return SeedOutcome(seed, "interrupted", (), message)
    if status != "ran" or summary is None:
        if exit_code == 2:  # `rei run` refused its input (a controller it cannot import, ...)
            return SeedOutcome(seed, "invalid", (), message)
        return SeedOutcome(seed, "error", (), message or f"the run {status}")
    run = RunSummary.from_json(summary)
    judged = tuple(dict.fromkeys(v.requirement for v in run.verdicts))
    if run.verdict in ("error", "interrupted"):  # verdicts of an abandoned mission: no failure
        return SeedOutcome(seed, run.verdict, (), run.reason, judged)
    failed = tuple(v.requirement for v in failed_verdicts(run) if v.status == "fail")
    return SeedOutcome(seed, run.verdict, failed, "", judged)


BROKEN = ("error", "interrupted", "invalid")
"""Verdicts of a run that broke: whatever it says of a requirement, it did not fail it."""


def fails_everywhere(outcomes: Sequence[SeedOutcome], requirement: str) -> bool:
    """The acceptance rule of a shrinking step: ``requirement`` failed on every seed, each
    of them a run that did not break."""
    return bool(outcomes) and all(o.verdict not in BROKEN and requirement in o.failed
                                  for o in outcomes)
