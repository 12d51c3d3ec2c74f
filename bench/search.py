"""Search benchmark: how soon does `rei search` find bench/bugs.py's defects, per strategy,
against random sampling on the same budget of simulations?

For every defect chosen with ``--only``, every strategy (``--strategies``, random always
included: it is the baseline) and every seed, one search of at most ``--budget`` simulations
over the ``--preset`` rooms (layout searched, optionally ``--speed LOW:HIGH`` or other
``--factor`` levels; the default objective: the smallest margin of any requirement). A defect
is *found* when one of its candidates fails and the correct navigator passes that same
candidate (same files, same run seed: one extra run, made after each batch), so a candidate no
navigator could pass is never counted as a detection; the search *stops at its first
confirmed failure*, so a search that finds its defect early costs little. The reference's own
searches (``--reference-seeds``, ``--reference-strategies``, ``--reference-budget``) run their
whole budget: every failure in them is a false alarm.

Reported per strategy: defects found per seed (mean and spread), simulations to the first
confirmed failure (mean, spread, max), detections per 1,000 simulations *spent* (a found
search counts its simulations up to the detection, a missed one its whole budget), its ratio
to random's rate measured in the same invocation, the defects found on every seed, failing
candidates the reference failed too, and the reference's false alarms. With ``--shrink`` each
confirmed failure is shrunk with `rei shrink`'s engine (3 seeds, at most ``--shrink-runs``
runs) and "shrunk" gives the mean size reduction; without it, "n/a".

Each search is appended to OUT/outcomes.jsonl as it ends (``--resume`` keeps those of the
same settings and runs the rest); OUT/search.json has the summary; ``--markdown`` prints the
tables for bench/RESULTS.md. CPU seconds (this process and its children, this invocation
only) are reported with the load average, since the machine is shared.

Usage: python bench/search.py [--only NAME ...] [--strategies S ...] [--seeds S ...]
       [--reference-seeds S ...] [--reference-strategies S ...] [--reference-budget N]
       [--budget N] [--batch K] [--workers N] [--preset small] [--speed LOW:HIGH]
       [--factor NAME=LEVELS ...] [--scenario NAME=LOW:HIGH ...] [--shrink [--shrink-runs N]]
       [--resume] [--markdown] [--out DIR]
"""

from __future__ import annotations

import argparse
import io
import json
import os
import resource
import shutil
import statistics
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)

from bench.defects import DEFECTS  # noqa: E402
from rei.runtime.campaigns import LocalEngine, plan_campaign, run_campaign  # noqa: E402
from rei.runtime.campaigns.search import SearchConfig, run_search  # noqa: E402
from rei.runtime.campaigns.search.driver import CandidateResult  # noqa: E402
from rei.runtime.campaigns.shrink import size_reduction  # noqa: E402
from rei.runtime.campaigns.shrink.oracle import RunSettings  # noqa: E402

REFERENCE = "reference"


@dataclass(frozen=True)
class SearchOutcome:
    navigator: str
    strategy: str
    seed: int
    simulations: int
    failing: int
    confirmed: str
    """The first failing candidate the reference passes ('' when none)."""
    first_at: int | None
    """Simulations run up to and including the confirmed failure."""
    cells: int
    """Distinct (measure A, measure B) cells of 0.25 x 0.25 among failing candidates."""
    requirements: tuple[str, ...]
    shrunk: float | None
    confirmations: int = 0
    """Reference runs made to confirm failing candidates."""
    unconfirmed: int = 0
    """Failing candidates the reference failed too (not detections)."""


def shrink_reduction(mission: Path, spec: str, args: argparse.Namespace) -> float | None:
    """The size reduction (share of elements removed) of `rei shrink`'s minimal case for a
    confirmed failure, or None when shrinking was not asked for (``--shrink``) or the case
    did not fail the same requirement on every one of the three seeds."""
    if not args.shrink:
        return None
    out = mission.parent.parent / f"shrunk-{mission.stem}"
    shutil.rmtree(out, ignore_errors=True)
    settings = RunSettings(seeds=(0, 1, 2), controller=spec, workers=args.workers)
    return size_reduction(mission, out, settings, max_runs=args.shrink_runs)


def confirm(result: CandidateResult, root: Path, seed: int, workers: int) -> bool:
    """True when the reference passes the failing candidate (same files and run seed)."""
    pair = result.candidate.pair
    assert pair is not None
    mission = root / "candidates" / pair.mission_file
    plan = plan_campaign([mission], seed=seed)
    # plan_campaign derives the run seed from the mission's folder/name, as the search did.
    check = root.parent / f"{root.name}-confirm-{result.candidate.name}"
    shutil.rmtree(check, ignore_errors=True)
    done = run_campaign(plan, check, LocalEngine(workers), {"command": ["bench/search.py"]},
                        stream=io.StringIO())
    return all(r.passed for r in done.records)


def one_search(nav: str, spec: str, strategy: str, seed: int, args: argparse.Namespace,
               budget: int) -> SearchOutcome:
    """One search; a defect's search ends at its first *confirmed* failure (the reference
    passes that candidate), the reference's runs its whole budget (every failure a false
    alarm)."""
    root = args.out / nav / f"{strategy}-{seed}"
    shutil.rmtree(root, ignore_errors=True)
    levels = tuple(tuple(f.split("=", 1)) for f in args.factor)
    levels = (*levels, ("speed", args.speed)) if args.speed else levels
    scenario = tuple(tuple(f.split("=", 1)) for f in args.scenario)
    config = SearchConfig(preset=args.preset, levels=levels,  # type: ignore[arg-type]
                          scenario=scenario,  # type: ignore[arg-type]
                          strategy=strategy, seed=seed, budget=budget, batch=args.batch,
                          controller=None if spec == REFERENCE else spec)
    verdicts: dict[str, bool] = {}

    def confirmed_failure(results: Sequence[CandidateResult]) -> bool:
        for r in results:
            if r.failed and r.candidate.name not in verdicts:
                verdicts[r.candidate.name] = confirm(r, root, seed, args.workers)
        return any(verdicts.values())

    result = run_search(config, root, LocalEngine(args.workers),
                        {"command": ["bench/search.py"]}, stream=io.StringIO(),
                        until=None if nav == REFERENCE else confirmed_failure)
    if not result.complete:  # interrupted (Ctrl-C): record nothing of this search
        raise KeyboardInterrupt
    ran = [r for r in result.results if r.record is not None]
    failing = [r for r in ran if r.failed]
    confirmed, first_at = "", None
    for r in failing:
        if verdicts.get(r.candidate.name):
            confirmed = r.candidate.name
            first_at = ran.index(r) + 1
            break
    cells = {(int(r.candidate.descriptor(config.measures[0]) / 0.25),
              int(r.candidate.descriptor(config.measures[1]) / 0.25)) for r in failing}
    reqs = sorted({v.requirement for r in failing if r.record and r.record.summary
                   for v in r.record.summary.verdicts if v.status == "fail"})
    shrunk = None
    if confirmed:
        shrunk = shrink_reduction(root / "candidates" / f"{confirmed}_0001.mission", spec,
                                  args)
    return SearchOutcome(nav, strategy, seed, len(ran), len(failing), confirmed, first_at,
                         len(cells), tuple(reqs), shrunk, len(verdicts),
                         sum(not v for v in verdicts.values()))


def _mean_sd(values: Sequence[float]) -> tuple[float | None, float | None]:
    if not values:
        return None, None
    return statistics.mean(values), statistics.pstdev(values) if len(values) > 1 else 0.0


def summarise(outcomes: list[SearchOutcome], strategies: list[str], defects: list[str],
              seeds: list[int], budget: int) -> dict[str, Any]:
    """Per strategy over the defects' searches. A search that finds its defect stops there,
    so ``per_1000`` is detections per 1,000 simulations *spent* (a found search counts the
    simulations up to its confirmed failure, a missed one its whole budget): the rate of a
    searcher that moves on to the next defect when it has one."""
    rows: dict[str, Any] = {}
    for strategy in strategies:
        mine = [o for o in outcomes if o.strategy == strategy and o.navigator != REFERENCE]
        per_seed = [sum(bool(o.confirmed) for o in mine if o.seed == s) for s in seeds]
        sims = sum(o.simulations for o in mine)
        found = sum(bool(o.confirmed) for o in mine)
        firsts = [float(o.first_at) for o in mine if o.first_at is not None]
        first_mean, first_sd = _mean_sd(firsts)
        reference = [o for o in outcomes if o.strategy == strategy and o.navigator == REFERENCE]
        every_seed = [d for d in defects
                      if (ds := [o for o in mine if o.navigator == d]) and all(o.confirmed
                                                                                for o in ds)]
        rows[strategy] = {
            "searches": len(mine),
            "found_per_seed": per_seed,
            "mean": statistics.mean(per_seed) if per_seed else 0.0,
            "spread": statistics.pstdev(per_seed) if len(per_seed) > 1 else 0.0,
            "found": found,
            "simulations": sims,
            "per_1000": 1000.0 * found / sims if sims else 0.0,
            "first_failure_mean": first_mean,
            "first_failure_sd": first_sd,
            "first_failure_max": max(firsts) if firsts else None,
            "defects_found_every_seed": every_seed,
            "share_found_every_seed": len(every_seed) / len(defects) if defects else 0.0,
            "defects_found": sorted({o.navigator for o in mine if o.confirmed}),
            "unconfirmed": sum(o.unconfirmed for o in mine),
            "reference_simulations": sum(o.simulations for o in reference),
            "false_alarms": sum(o.failing for o in reference),
            "budget": budget,
        }
    base = rows.get("random", {}).get("per_1000") or 0.0
    for strategy in strategies:
        rows[strategy]["ratio_to_random"] = (rows[strategy]["per_1000"] / base
                                             if base else None)
    return rows


def _fmt(value: float | None, spec: str = ".1f") -> str:
    return "—" if value is None else format(value, spec)


def table(summary: dict[str, Any], outcomes: list[SearchOutcome], defects: list[str]) -> str:
    lines = ["| strategy | searches | defects found per seed (mean ± sd) | simulations spent | "
             "detections per 1,000 simulations spent | ratio to random | simulations to the "
             "first confirmed failure (mean ± sd, max) | defects found on every seed | "
             "failing candidates the reference also failed | reference: false alarms / "
             "simulations |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, row in summary.items():
        ratio = _fmt(row["ratio_to_random"], ".2f")
        first = (f"{_fmt(row['first_failure_mean'])} ± {_fmt(row['first_failure_sd'])}, "
                 f"{_fmt(row['first_failure_max'], '.0f')}")
        lines.append(f"| {name} | {row['searches']} | {row['found_per_seed']} "
                     f"({row['mean']:.2f} ± {row['spread']:.2f}) | {row['simulations']} | "
                     f"{row['per_1000']:.0f} | {ratio} | {first} | "
                     f"{len(row['defects_found_every_seed'])}/{len(defects)} | "
                     f"{row['unconfirmed']} | {row['false_alarms']} / "
                     f"{row['reference_simulations']} |")
    lines += ["", "| defect | " + " | ".join(f"{s}: found (simulations to it)" for s in summary)
              + " | failed requirements | shrunk |",
              "|---|" + "---|" * (len(summary) + 2)]
    for nav in defects:
        cells = []
        for strategy in summary:
            mine = sorted((o for o in outcomes if o.navigator == nav and o.strategy == strategy),
                          key=lambda o: o.seed)
            at = ", ".join(str(o.first_at) if o.first_at else "—" for o in mine)
            cells.append(f"{sum(bool(o.confirmed) for o in mine)}/{len(mine)} ({at})")
        reqs = sorted({q for o in outcomes if o.navigator == nav for q in o.requirements})
        shrunk = [o.shrunk for o in outcomes if o.navigator == nav and o.shrunk is not None]
        lines.append(f"| {nav} | " + " | ".join(cells) + f" | {', '.join(reqs) or '—'} | "
                     + (f"{statistics.mean(shrunk):.0%}" if shrunk else "n/a") + " |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="+", default=["stale-scans", "control-latency",
                                                      "blind-sector"], metavar="NAME",
                        help="defects to search for (default: the three the default "
                             "campaign misses); the reference always runs")
    parser.add_argument("--strategies", nargs="+", default=["random", "tpe", "map-elites"],
                        metavar="S", help="strategies (random is always added)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3], metavar="S")
    parser.add_argument("--reference-seeds", type=int, nargs="+", default=None, metavar="S",
                        help="seeds of the reference's whole-budget searches (default: "
                             "--seeds)")
    parser.add_argument("--budget", type=int, default=32,
                        help="simulations per search at most (a defect's search stops at its "
                             "first confirmed failure)")
    parser.add_argument("--reference-strategies", nargs="+", default=None, metavar="S",
                        help="strategies of the reference's searches (default: all)")
    parser.add_argument("--reference-budget", type=int, default=None, metavar="N",
                        help="simulations of each of the reference's searches (default: "
                             "--budget)")
    parser.add_argument("--batch", type=int, default=4, help="candidates per batch")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--preset", default="small")
    parser.add_argument("--speed", default=None, metavar="LOW:HIGH",
                        help="search the humans' walking speed in this range (default: the "
                             "preset's levels; 0.5:1.4 lets search find fast social humans "
                             "that walk into even the correct navigator)")
    parser.add_argument("--factor", action="append", default=[], metavar="NAME=LEVELS",
                        help="a factor's levels or LOW:HIGH range, as `rei search --NAME` "
                             "takes them (e.g. stressor=emerge)")
    parser.add_argument("--scenario", action="append", default=[], metavar="NAME=LOW:HIGH",
                        help="a scenario parameter searched too (rei search's --phase, "
                             "--object-shift, ...: phase, object_shift, goal_shift, "
                             "path_shift, stress_shift, KIND.PARAM), e.g. object_shift=0:0.3")
    parser.add_argument("--shrink", action="store_true",
                        help="shrink every confirmed failure with rei shrink (3 seeds)")
    parser.add_argument("--shrink-runs", type=int, default=120, metavar="N",
                        help="run budget of each shrink (default 120)")
    parser.add_argument("--resume", action="store_true",
                        help="keep the searches already in OUT/outcomes.jsonl (same settings) "
                             "and run only the missing ones")
    parser.add_argument("--summary-only", action="store_true",
                        help="run nothing: summarise the searches in OUT/outcomes.jsonl of "
                             "these settings (what an interrupted benchmark finished)")
    parser.add_argument("--markdown", action="store_true")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "out" / "search")
    args = parser.parse_args()
    strategies = ["random", *[s for s in args.strategies if s != "random"]]
    known = {d.name: d.spec for d in DEFECTS}
    unknown = sorted(set(args.only) - set(known))
    if unknown:
        raise SystemExit(f"--only: unknown defect(s) {', '.join(unknown)}")
    reference_seeds = args.reference_seeds if args.reference_seeds is not None else args.seeds
    # The reference's first seed, then the defects seed by seed, then its other seeds: an
    # interrupted benchmark has whole seeds and a false-alarm check. Each search is appended
    # to outcomes.jsonl as it ends, so --resume loses nothing but the search under way.
    defects = [(n, known[n]) for n in args.only]
    checked = [s for s in strategies if s in (args.reference_strategies or strategies)]
    jobs = [(seed, REFERENCE, REFERENCE, strategy) for seed in reference_seeds[:1]
            for strategy in checked[:1]]
    jobs += [(seed, nav, spec, strategy) for seed in args.seeds for nav, spec in defects
             for strategy in strategies]
    jobs += [(seed, REFERENCE, REFERENCE, strategy) for seed in reference_seeds
             for strategy in checked if (seed, strategy) != (reference_seeds[0], checked[0])]
    args.out.mkdir(parents=True, exist_ok=True)
    log = args.out / "outcomes.jsonl"
    reference_budget = args.reference_budget or args.budget

    def key_of(nav: str) -> dict[str, Any]:
        return {"budget": reference_budget if nav == REFERENCE else args.budget,
                "batch": args.batch, "preset": args.preset, "speed": args.speed,
                "factor": args.factor, **({"scenario": args.scenario} if args.scenario
                                           else {})}

    outcomes: list[SearchOutcome] = []
    if (args.resume or args.summary_only) and log.is_file():
        for line in log.read_text(encoding="utf-8").splitlines():
            data = json.loads(line)
            if data.pop("settings") == key_of(data["navigator"]):
                data["requirements"] = tuple(data["requirements"])
                outcomes.append(SearchOutcome(**data))
    else:
        log.write_text("", encoding="utf-8")
    done = {(o.seed, o.navigator, o.strategy) for o in outcomes}
    started, load = time.perf_counter(), os.getloadavg()
    for seed, nav, spec, strategy in jobs:
        if (seed, nav, strategy) in done or args.summary_only:
            continue
        o = one_search(nav, spec, strategy, seed, args,
                       reference_budget if nav == REFERENCE else args.budget)
        outcomes.append(o)
        with log.open("a", encoding="utf-8") as out:
            out.write(json.dumps({**o.__dict__, "settings": key_of(nav)}) + "\n")
        print(f"seed {seed} {nav} {strategy}: {o.failing}/{o.simulations} failing, "
              f"confirmed {o.confirmed or '-'} at {o.first_at or '-'} "
              f"({time.perf_counter() - started:.0f} s, load {os.getloadavg()[0]:.1f})",
              file=sys.stderr)
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    summary = summarise(outcomes, strategies, args.only, args.seeds, args.budget)
    settings = {**key_of(""), "reference_budget": reference_budget, "seeds": args.seeds,
                "reference_seeds": reference_seeds,
                "workers": args.workers, "defects": args.only, "strategies": strategies,
                "wall_seconds": time.perf_counter() - started,
                "cpu_seconds": own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime,
                "load_average_at_start": load, "load_average_at_end": os.getloadavg()}
    (args.out / "search.json").write_text(json.dumps(
        {"settings": settings, "summary": summary,
         "searches": [o.__dict__ for o in outcomes]}, indent=1) + "\n", encoding="utf-8")
    print(json.dumps(settings))
    print(table(summary, outcomes, args.only))
    return 0


if __name__ == "__main__":
    sys.exit(main())
