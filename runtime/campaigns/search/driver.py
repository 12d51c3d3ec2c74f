"""Running a search: propose a batch, build its candidates, run them as a campaign, learn.

The search folder *is* a campaign folder (campaign.json, runs/, results.csv/.parquet, so
`rei report` reads it) plus ``search.json`` (the options, checked on resume), ``candidates/``
(every built .room/.mission and their index.csv) and ``search.csv`` (one row per candidate:
its levels, margin and verdict). Each batch grows the campaign's plan by its candidates'
runs (``extend_plan``) and runs them on the campaign engine given (local workers, Dask).

Determinism and resuming: a strategy's proposals depend only on its seed and what it was told
before, batches have a fixed size whatever the worker count, and the runs' seeds derive from
the search seed and the candidate's file; so a resumed search replays the recorded batches
(rebuilding the same files, running nothing) and continues exactly where it stopped, and its
final files equal an uninterrupted search's. This module never decides a run's verdict.
"""

from __future__ import annotations

import csv
import io
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, TextIO

from rei.catalogue import default_catalogue
from rei.generators.output import write_atomic
from rei.generators.rooms.design import (
    LAYOUT_SEEDS,
    SearchDimension,
    decode_point,
    search_dimensions,
)
from rei.generators.rooms.scenario import check_faults, parse_scenario
from rei.generators.rooms.space import (
    FACTOR_NAMES,
    Interval,
    ParameterSpace,
    check_level,
    is_interval,
    parse_interval,
    preset_space,
)
from rei.runtime.campaigns.engines import CampaignEngine
from rei.runtime.campaigns.orchestration import run_campaign
from rei.runtime.campaigns.plan import CampaignPlan, plan_campaign
from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.search.candidates import (
    CANDIDATES,
    Candidate,
    build_candidate,
    write_candidates,
)
from rei.runtime.campaigns.search.errors import SearchError
from rei.runtime.campaigns.search.strategies import Told, make_strategy, refuse_unusable
from rei.runtime.campaigns.store import MANIFEST, CampaignStore, extend_plan
from rei.runtime.observation.evaluator.margins import smallest_margin

SEARCH_FILE = "search.json"
SEARCH_TABLE = "search.csv"
FORMAT = "rei-search"
VERSION = 1

NO_EVIDENCE = 10.0
"""The objective of a candidate that tells nothing about failing: it was not built, its run
errored, or its run has no margin for the requirement and did not fail it. Above every real
margin of the default requirements, so a strategy moves away from such points."""
FAILED_WITHOUT_MARGIN = -1.0
"""The objective of a run that failed the requirement without a margin for it."""
MARGIN_BOUND = 10.0


@dataclass(frozen=True)
class SearchConfig:
    """Everything that decides a search's candidates and runs (search.json)."""

    preset: str = "small"
    levels: tuple[tuple[str, str], ...] = ()
    """Factor options as given (``max_speed`` -> ``0.05:2``): levels, or a LOW:HIGH range."""
    scenario: tuple[tuple[str, str], ...] = ()
    """Scenario parameters' ranges as given (``phase`` -> ``0:20``, ``laser_noise.sigma``
    -> ``0.01:0.1``): generators/rooms/scenario.py."""
    layout: int | None = None
    """A fixed construction seed (the layout is then not searched)."""
    strategy: str = "tpe"
    seed: int = 0
    budget: int = 100
    batch: int = 8
    requirement: str | None = None
    """The requirement whose margin is minimised; None: the smallest margin of any."""
    measures: tuple[str, str] = ("closest_obstacle_m", "tortuosity")
    controller: str | None = None
    vepl: str | None = None
    duration: float | None = None
    stop_on_failure: bool = False
    version: str = "0"
    vepl_parameters: tuple[tuple[str, float], ...] = ()
    """`--param`: the specification's parameter values passed to every run, sorted by name."""

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["levels"] = [list(p) for p in self.levels]
        data["scenario"] = [list(p) for p in self.scenario]
        data["measures"] = list(self.measures)
        if self.vepl_parameters:  # a search without them keeps the shape it always had
            data["vepl_parameters"] = dict(self.vepl_parameters)
        else:
            del data["vepl_parameters"]
        return {"format": FORMAT, "version": VERSION, "config": data}

    @staticmethod
    def from_json(data: dict[str, Any]) -> SearchConfig:
        config = dict(data["config"])
        config["levels"] = tuple(tuple(p) for p in config["levels"])
        # A search.json from before scenario parameters existed searched none.
        config["scenario"] = tuple(tuple(p) for p in config.get("scenario", ()))
        config["measures"] = tuple(config["measures"])
        if "vepl_parameters" in config:
            config["vepl_parameters"] = tuple(sorted(
                (str(n), float(v)) for n, v in dict(config["vepl_parameters"]).items()))
        return SearchConfig(**config)

    def space(self) -> tuple[ParameterSpace, dict[str, Interval]]:
        """The parameter space (a range's factor keeps a placeholder level) and the ranges."""
        overrides: dict[str, tuple[str, ...]] = {}
        intervals: dict[str, Interval] = {}
        for name, text in self.levels:
            if is_interval(text):
                interval = parse_interval(name, text)
                intervals[name] = interval
                overrides[name] = (interval.level(0.0),)
            else:
                overrides[name] = tuple(v.strip() for v in text.split(",") if v.strip())
        return preset_space(self.preset).replaced(overrides), intervals

    def scenario_ranges(self) -> tuple[Interval, ...]:
        return tuple(parse_scenario(name, text) for name, text in self.scenario)

    def dimensions(self) -> tuple[ParameterSpace, tuple[SearchDimension, ...]]:
        space, intervals = self.space()
        return space, search_dimensions(space, intervals, self.layout,
                                        self.scenario_ranges())


def check_config(config: SearchConfig) -> tuple[ParameterSpace, tuple[SearchDimension, ...]]:
    """Refuse options no search can use, before anything is written."""
    from rei.generators.rooms.space import ParameterError  # noqa: PLC0415
    from rei.runtime.campaigns.search.strategies import MEASURE_RANGES  # noqa: PLC0415
    from rei.runtime.observation.evaluator.margins import RULES  # noqa: PLC0415

    if config.budget < 1:
        raise SearchError(f"--budget: expected a number of simulations of at least 1, found "
                          f"{config.budget}")
    if config.batch < 1:
        raise SearchError(f"--batch: expected at least 1, found {config.batch}")
    if config.strategy == "map-elites" and config.batch < 2:
        raise SearchError("--batch: map-elites needs batches of at least 2 candidates")
    if config.requirement is not None and config.requirement not in RULES:
        from rei.lang.suggest import did_you_mean  # noqa: PLC0415

        raise SearchError(f"--requirement: expected a requirement with a margin "
                          f"({', '.join(RULES)}), found '{config.requirement}'"
                          + did_you_mean(config.requirement, tuple(RULES)))
    for name in config.measures:
        if name not in MEASURE_RANGES:
            raise SearchError(f"--measures: expected two of {', '.join(MEASURE_RANGES)}, "
                              f"found '{name}'")
    for name, _ in config.levels:
        if name not in FACTOR_NAMES:
            raise ParameterError(name, f"a factor ({', '.join(FACTOR_NAMES)})", f"'{name}'")
    names = [name for name, _ in config.scenario]
    if len(set(names)) != len(names):
        twice = sorted({n for n in names if names.count(n) > 1})
        raise ParameterError("fault-range", "each scenario parameter once",
                             f"{', '.join(twice)} more than once")
    check_faults(config.scenario_ranges())
    if config.layout is not None and not 0 <= config.layout < LAYOUT_SEEDS:
        raise SearchError(f"--layout: expected a construction seed from 0 to "
                          f"{LAYOUT_SEEDS - 1}, found {config.layout}")
    space, dims = config.dimensions()
    # Every level given is checked with the generator's own parser now, so a bad one stops
    # the search before any run (an impossible combination is still a candidate 'not built').
    static_names = tuple(default_catalogue().names("static"))
    reference = {f.name: f.levels[0] for f in space.factors}
    for name, text in config.levels:
        if not is_interval(text):
            for level in text.split(","):
                check_level(name, level, reference, static_names)
    if not dims:
        raise SearchError("nothing to search: every factor has one level and --layout fixes "
                          "the room's construction; give a factor several levels or a "
                          "LOW:HIGH range, or drop --layout")
    refuse_unusable(config.strategy, len(dims))
    return space, dims


# -- the objective -----------------------------------------------------------------------


def objective(record: RunRecord | None, requirement: str | None) -> float:
    """The value a strategy minimises for one run: the requirement's margin (the smallest of
    any, without a requirement), bounded; a failed run (failed requirement) is never above
    FAILED_WITHOUT_MARGIN; a run that tells nothing is NO_EVIDENCE."""
    if record is None or record.summary is None or record.verdict == "error":
        return NO_EVIDENCE
    verdicts = record.summary.verdicts
    if requirement is None:
        margin = smallest_margin(verdicts)
        failed = record.verdict == "fail"
    else:
        chosen = [v for v in verdicts if v.requirement == requirement]
        margin = chosen[0].margin if chosen else None
        failed = bool(chosen) and chosen[0].status == "fail"
    if margin is not None and not math.isfinite(margin):
        margin = None
    if failed and (margin is None or margin >= 0):
        # Failed by a verdict without a margin (a task, an event pattern) while others
        # passed with room to spare: a failure must never rank as a near pass.
        return FAILED_WITHOUT_MARGIN
    if margin is None:
        return NO_EVIDENCE
    return min(max(margin, -MARGIN_BOUND), MARGIN_BOUND)


@dataclass(frozen=True)
class CandidateResult:
    candidate: Candidate
    record: RunRecord | None
    objective: float

    @property
    def failed(self) -> bool:
        return self.record is not None and self.record.verdict == "fail"


def fail_line(result: CandidateResult, requirement: str | None) -> str:
    """What a failing candidate's line says after its file: the requirements it failed, then
    the margin the search minimised, labelled with its requirement (the smallest of any
    without --requirement). A candidate fails by any requirement, so the margin shown may be
    another requirement's and positive: the names say why it failed."""
    summary = result.record.summary if result.record is not None else None
    failed = sorted({v.requirement for v in summary.verdicts if v.status == "fail"}
                    ) if summary is not None else []
    which = f"{requirement} margin" if requirement is not None else "smallest margin"
    names = ", ".join(failed) if failed else "a verdict without a requirement"
    return f"failed {names}; {which} {result.objective:.3g}"


@dataclass
class SearchProgress:
    """The progress line of a search: simulations of the budget, failing runs and the best
    (lowest) margin so far with its candidate. It never influences the search."""

    budget: int
    stream: TextIO = field(default_factory=lambda: sys.stderr)
    width: int = 28
    started: float = field(default_factory=time.monotonic)

    def update(self, results: Sequence[CandidateResult]) -> None:
        done = len(results)
        ran = [r for r in results if r.record is not None]
        failing = sum(r.failed for r in results)
        best = min(ran, key=lambda r: r.objective, default=None)
        filled = int(self.width * done / self.budget) if self.budget else self.width
        bar = "#" * filled + "." * (self.width - filled)
        margin = (f"best margin {best.objective:.3g} ({best.candidate.name})"
                  if best is not None and best.objective < NO_EVIDENCE else "best margin -")
        line = (f"[{bar}] {done}/{self.budget} candidates  {len(ran)} simulated  "
                f"failing {failing}  {margin}")
        tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.stream.write(("\r" + line) if tty else line + "\n")
        self.stream.flush()

    def finish(self) -> None:
        if hasattr(self.stream, "isatty") and self.stream.isatty():
            self.stream.write("\n")


@dataclass(frozen=True)
class SearchResult:
    root: Path
    results: tuple[CandidateResult, ...]
    complete: bool
    """False when the session was stopped before the search ended (run it again)."""

    @property
    def failing(self) -> tuple[CandidateResult, ...]:
        return tuple(r for r in self.results if r.failed)


def _open_folder(root: Path, config: SearchConfig) -> None:
    path = root / SEARCH_FILE
    if root.exists() and not root.is_dir():
        raise SearchError(f"{root}: expected a search folder, found a file")
    if path.is_file():
        try:
            stored = SearchConfig.from_json(json.loads(path.read_text(encoding="utf-8")))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise SearchError(f"{path}: the search's options are corrupt ({exc}); refusing "
                              f"this folder — move it away or choose another -o") from exc
        if stored != config:
            old, new = asdict(stored), asdict(config)
            differ = [k for k in old if old[k] != new[k]]
            raise SearchError(f"{root}: this folder holds a different search (it differs in "
                              f"{', '.join(differ)}); resume it with the command that started "
                              f"it, or choose another -o folder")
        return
    if root.exists() and any(root.iterdir()):
        raise SearchError(f"{root}: not a REI search folder (it has files but no "
                          f"{SEARCH_FILE}); choose an empty or new -o folder")
    root.mkdir(parents=True, exist_ok=True)
    write_atomic(path, (json.dumps(config.to_json(), indent=1, sort_keys=True) + "\n")
                 .encode("utf-8"))


def run_search(config: SearchConfig, root: Path, engine: CampaignEngine,
               provenance: dict[str, Any], *, stream: TextIO | None = None,
               until: Callable[[Sequence[CandidateResult]], bool] | None = None
               ) -> SearchResult:
    """Run (or resume) the search in ``root``; SearchError for options it cannot use.
    KeyboardInterrupt passes through with every finished run recorded. ``until(results)``,
    asked after every batch with all results so far, ends the search early when True (a
    benchmark's stop at its first *confirmed* failure); it must depend only on the results,
    so a resumed search stops where an uninterrupted one did."""
    space, dims = check_config(config)
    _open_folder(root, config)
    strategy = make_strategy(config.strategy, dims, config.seed % 2**32, config.batch,
                             config.measures)
    folder = root / CANDIDATES
    out = stream if stream is not None else sys.stderr
    if (root / MANIFEST).is_file():
        recorded = len(CampaignStore.read(root)[2])
        print(f"resuming {root}: {recorded} simulation(s) already recorded; replaying them",
              file=out)
    progress = SearchProgress(config.budget, out)
    candidates: list[Candidate] = []
    results: list[CandidateResult] = []
    complete = True
    batch = 0
    try:
        while len(candidates) < config.budget:
            batch += 1
            points = strategy.ask(min(config.batch, config.budget - len(candidates)))
            fresh = [build_candidate(decode_point(space, dims, p, config.layout),
                                     len(candidates) + k + 1, batch, p, folder, config.version)
                     for k, p in enumerate(points)]
            candidates.extend(fresh)
            index = write_candidates(candidates, folder, config.strategy, config.preset)
            records: dict[str, RunRecord] = {}
            if any(c.pair is not None for c in fresh):
                plan = plan_campaign([index], seed=config.seed, controller=config.controller,
                                     vepl=Path(config.vepl) if config.vepl else None,
                                     duration=config.duration,
                                     vepl_parameters=config.vepl_parameters)
                replayed = _recorded_batch(root, plan)
                if replayed is None:
                    extend_plan(root, plan)
                    ran = run_campaign(plan, root, engine, provenance, stream=io.StringIO())
                    if not ran.complete:
                        complete = False
                        break
                    replayed = list(ran.records)
                records = {Path(r.spec.mission_file).name: r for r in replayed}
            for candidate in fresh:
                pair = candidate.pair
                record = records.get(pair.mission_file) if pair is not None else None
                results.append(CandidateResult(candidate, record,
                                               objective(record, config.requirement)))
            strategy.tell(points, [Told(r.objective, (r.candidate.descriptor(config.measures[0]),
                                                      r.candidate.descriptor(config.measures[1])),
                                        built=r.candidate.pair is not None)
                                   for r in results[-len(fresh):]])
            progress.update(results)
            if config.stop_on_failure and any(r.failed for r in results):
                break
            if until is not None and until(results):
                break
    finally:
        progress.finish()
        write_atomic(root / SEARCH_TABLE, search_table(results, dims).encode("utf-8"))
    if not any(r.record is not None for r in results) and complete:
        problem = next((r.candidate.problem for r in results if r.candidate.problem), "")
        raise SearchError(f"no candidate could be built, so nothing ran; the generator "
                          f"said: {problem}")
    return SearchResult(root, tuple(results), complete)


def _recorded_batch(root: Path, plan: CampaignPlan) -> list[RunRecord] | None:
    """When resuming: the records of a batch that an earlier session finished (the folder's
    plan already goes beyond ``plan``), else None (the batch runs now)."""
    if not (root / MANIFEST).is_file():
        return None
    stored, _, records = CampaignStore.read(root)
    if len(stored.runs) <= len(plan.runs):
        return None
    head = CampaignPlan(stored.version, stored.seed, stored.repeat,
                        stored.runs[:len(plan.runs)])
    if head != plan:
        raise SearchError(f"{root}: the recorded runs do not match this search's candidates "
                          f"(was it made by another version of REI?); choose another -o folder")
    wanted = {s.run_id for s in plan.runs}
    mine = [r for r in records if r.spec.run_id in wanted]
    if len(mine) != len(wanted):
        raise SearchError(f"{root}: runs of a finished batch are missing from runs/; "
                          f"refusing to guess their results — choose another -o folder")
    return mine


def search_table(results: Sequence[CandidateResult], dims: Sequence[SearchDimension]) -> str:
    """search.csv: per candidate, its searched levels, margin, verdict and why it did not
    run; no wall-clock figures, so the same search gives the same bytes."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    names = [d.name for d in dims]
    writer.writerow(["candidate", "batch", "run_id", "verdict", "objective",
                     "failed_requirements", *names, "problem"])
    for r in results:
        c = r.candidate
        levels = dict(c.row.levels) | dict(c.row.scenario)
        levels["layout"] = str(c.row.layout)
        record = r.record
        failed = ""
        if record is not None and record.summary is not None:
            failed = " ".join(v.requirement for v in record.summary.verdicts
                              if v.status == "fail")
        writer.writerow([c.name, c.batch, record.spec.run_id if record else "",
                         record.verdict if record else "not built",
                         f"{r.objective:.6g}", failed, *(levels[n] for n in names),
                         c.problem])
    return out.getvalue()
