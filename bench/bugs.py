"""Bug-finding benchmark: does REI fail buggy navigation software and pass correct software?

Runs the campaign `rei demo` runs (a suite of ``--count`` generated ``--preset`` rooms, seed S,
every mission ``--repeat`` times with seeds derived from S, the default .vepl) once per
campaign seed with each navigator: the correct `reference` (the baseline, measured in the same
invocation) and every defective navigator of bench/defects (one realistic defect each). A run
fails as `rei campaign` counts it: it did not complete its mission (a failed task, a time-out,
a crash) or a requirement's verdict is not "pass". A navigator is *flagged* on a seed when any
run of that campaign fails.

Reported per navigator: seeds flagged, failed runs, and what caught them: each requirement whose
verdict was "fail" (counted over failed runs; names are read from the runs' summary.json, none
is assumed here), "inconclusive" verdicts apart, and the runs whose only failure is the task
outcome ("task:failed", "task:timeout", ...). Then: detection rate (defects flagged on every
seed / defects; and flagged seed-campaigns / defect seed-campaigns), the reference's
false-alarm rate (its campaigns with any failed run), which defects were caught only by task
outcomes, and each navigator's campaign wall time (noisy on a shared machine) and simulated seconds
(deterministic: longer missions, time-outs) relative to the reference's on the same seed.

Writes bench/out/bugs.json (every run's verdicts); ``--markdown`` prints the table for
bench/RESULTS.md. ``--quick`` is a smoke test: the first seed, 2 rooms, one run per mission.
``--examples`` adds the four bundled examples to every campaign: the small preset has no
humans and no goal headings or speed limits, so some defects cannot show in the demo suite.

Usage: python bench/bugs.py [--seeds S ...] [--workers N] [--only NAME ...] [--quick]
       [--count N] [--repeat K] [--preset small|medium|large] [--examples] [--markdown]
"""

from __future__ import annotations

import argparse
import io
import json
import os
import shutil
import sys
import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# The defects are `bench.defects.MODULE:Class`: importable here and in every run's process
# (a run imports its controller from its own working folder and PYTHONPATH).
sys.path.insert(0, str(REPO))
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)

from bench.defects import DEFECTS  # noqa: E402
from rei.runtime.campaign import LocalEngine, RunRecord, plan_campaign, run_campaign  # noqa: E402
from rei.runtime.robot import make_controller  # noqa: E402

REFERENCE = "reference"
TASK = "task:"
"""Prefix of a catcher that is a run's outcome (failed task, time-out, crash), not a verdict."""
INCONCLUSIVE = "inconclusive:"


@dataclass(frozen=True)
class Navigator:
    name: str
    kind: str
    spec: str
    expected: str
    """The docstring's "Expected catcher" (the defect's own claim, never used for scoring)."""


@dataclass(frozen=True)
class RunOutcome:
    run_id: str
    seed: int
    passed: bool
    outcome: str
    status: str
    reason: str
    simulated: float
    """Simulation seconds of the run (0 without a summary)."""
    failed: tuple[str, ...]
    """Requirements whose verdict was "fail"."""
    inconclusive: tuple[str, ...]
    reasons: dict[str, str] = field(default_factory=dict)
    """Each failed requirement's reason."""

    @property
    def catchers(self) -> list[str]:
        """What made this run fail: its failed requirements, else its outcome."""
        if self.passed:
            return []
        found = list(self.failed) + [INCONCLUSIVE + r for r in self.inconclusive]
        if self.status != "ran" or self.outcome != "completed":
            found.append(TASK + (self.outcome if self.status == "ran" else self.status))
        return found


@dataclass(frozen=True)
class CampaignOutcome:
    navigator: str
    seed: int
    wall: float
    runs: tuple[RunOutcome, ...]

    @property
    def flagged(self) -> bool:
        return any(not r.passed for r in self.runs)

    @property
    def simulated(self) -> float:
        return sum(r.simulated for r in self.runs)


def navigators(only: list[str] | None) -> list[Navigator]:
    found = [Navigator(REFERENCE, "correct", REFERENCE, "nothing (the correct navigator)")]
    for d in DEFECTS:
        doc = type(make_controller(d.spec)).__doc__ or ""
        expected = " ".join(doc.split("Expected catcher:", 1)[-1].split("\n\n")[0].split())
        found.append(Navigator(d.name, d.kind, d.spec, expected))
    if only:
        unknown = sorted(set(only) - {n.name for n in found})
        if unknown:
            raise SystemExit(f"--only: unknown navigator(s) {', '.join(unknown)}; expected "
                             f"among {', '.join(n.name for n in found)}")
        # The reference is the baseline of the time ratios and the false-alarm rate: always run.
        found = [n for n in found if n.name == REFERENCE or n.name in only]
    return found


def outcome_of(record: RunRecord) -> RunOutcome:
    s = record.summary
    verdicts = s.verdicts if s is not None else ()
    return RunOutcome(
        run_id=record.spec.run_id, seed=record.spec.seed, passed=record.passed,
        outcome=record.outcome, status=record.status, reason=record.reason,
        simulated=s.duration if s is not None else 0.0,
        failed=tuple(v.requirement for v in verdicts if v.status == "fail"),
        inconclusive=tuple(v.requirement for v in verdicts if v.status == "inconclusive"),
        reasons={v.requirement: v.reason for v in verdicts if v.status == "fail"})


def run_one(nav: Navigator, inputs: list[Path], seed: int, repeat: int, workers: int,
            root: Path) -> CampaignOutcome:
    plan = plan_campaign(inputs, repeat=repeat, seed=seed,
                         controller=None if nav.spec == REFERENCE else nav.spec)
    shutil.rmtree(root, ignore_errors=True)  # a fresh campaign: never resume older code's runs
    start = time.perf_counter()
    result = run_campaign(plan, root, LocalEngine(workers), {"command": ["bench/bugs.py"]},
                          stream=io.StringIO())
    wall = time.perf_counter() - start
    return CampaignOutcome(nav.name, seed, wall, tuple(outcome_of(r) for r in result.records))


def suite(out: Path, count: int, preset: str, seed: int, examples: bool) -> list[Path]:
    from rei.runtime.commands.demo import EXAMPLES, generate_suite  # noqa: PLC0415

    inputs = generate_suite(out / f"suite-{preset}-{count}-seed{seed}", count, preset, seed)
    return [*inputs, EXAMPLES] if examples and EXAMPLES not in inputs else inputs


def catchers(campaigns: list[CampaignOutcome]) -> Counter[str]:
    return Counter(c for camp in campaigns for r in camp.runs for c in r.catchers)


def summarise(navs: list[Navigator], results: dict[str, list[CampaignOutcome]],
              seeds: list[int]) -> dict[str, object]:
    ref_wall = {c.seed: c.wall for c in results[REFERENCE]}
    ref_sim = {c.seed: c.simulated for c in results[REFERENCE]}
    rows = []
    for nav in navs:
        camps = results[nav.name]
        caught = catchers([c for c in camps if c.flagged])
        named = sorted(k for k in caught if not k.startswith((TASK, INCONCLUSIVE)))
        ratios = [c.wall / ref_wall[c.seed] for c in camps if ref_wall.get(c.seed)]
        sim = [c.simulated / ref_sim[c.seed] for c in camps if ref_sim.get(c.seed)]
        rows.append({
            "navigator": nav.name, "kind": nav.kind, "spec": nav.spec,
            "expected_catcher": nav.expected,
            "seeds_flagged": sum(c.flagged for c in camps), "seeds": len(camps),
            "runs_failed": sum(not r.passed for c in camps for r in c.runs),
            "runs": sum(len(c.runs) for c in camps),
            "caught_by": dict(caught.most_common()),
            "caught_by_requirement": bool(named),
            "time_vs_reference": sum(ratios) / len(ratios) if ratios else None,
            "simulated_vs_reference": sum(sim) / len(sim) if sim else None,
        })
    defects = [r for r in rows if r["navigator"] != REFERENCE]
    ref = next(r for r in rows if r["navigator"] == REFERENCE)
    every = [r["navigator"] for r in defects if r["seeds_flagged"] == r["seeds"]]
    flagged_camps = sum(int(str(r["seeds_flagged"])) for r in defects)
    all_camps = sum(int(str(r["seeds"])) for r in defects)
    return {
        "seeds": seeds,
        "rows": rows,
        "detection_rate_every_seed": len(every) / len(defects) if defects else None,
        "defects_flagged_every_seed": every,
        "defects_never_flagged": [r["navigator"] for r in defects if r["seeds_flagged"] == 0],
        "detection_rate_per_seed_campaign": flagged_camps / all_camps if all_camps else None,
        "false_alarm_rate": (int(str(ref["seeds_flagged"])) / int(str(ref["seeds"]))
                             if ref["seeds"] else None),
        "flagged_only_by_task_outcome": [r["navigator"] for r in defects
                                         if r["seeds_flagged"] and not r["caught_by_requirement"]],
        "flagged_by_a_requirement": [r["navigator"] for r in defects
                                     if r["caught_by_requirement"]],
    }


def table(summary: dict[str, object], markdown: bool) -> str:
    rows = summary["rows"]
    assert isinstance(rows, list)
    lines = ["| navigator | kind | flagged seeds | failed runs | caught by (failed runs) "
             "| expected catcher | campaign time vs reference | simulated s vs reference |",
             "|---|---|---:|---:|---|---|---:|---:|"]
    for r in rows:
        caught = ", ".join(f"{k} × {n}" for k, n in r["caught_by"].items()) or "—"
        ratio, sim = r["time_vs_reference"], r["simulated_vs_reference"]
        expected = r["expected_catcher"] if markdown else r["expected_catcher"][:60]
        lines.append(f"| {r['navigator']} | {r['kind']} | {r['seeds_flagged']}/{r['seeds']} "
                     f"| {r['runs_failed']}/{r['runs']} | {caught} | {expected} | "
                     f"{'—' if ratio is None else f'{ratio:.2f}'} | "
                     f"{'—' if sim is None else f'{sim:.2f}'} |")

    def pct(key: str) -> str:
        value = summary[key]
        return "—" if value is None else f"{100 * float(str(value)):.0f} %"

    every = summary["defects_flagged_every_seed"]
    assert isinstance(every, list)
    n_defects = len(rows) - 1
    lines += [
        "",
        f"* Detection rate (defects flagged on every seed): {len(every)}/{n_defects} = "
        f"{pct('detection_rate_every_seed')}; per seed-campaign: "
        f"{pct('detection_rate_per_seed_campaign')}.",
        f"* False-alarm rate (reference campaigns with any failed run): "
        f"{pct('false_alarm_rate')}.",
        f"* Never flagged: {', '.join(summary['defects_never_flagged']) or 'none'}.",  # type: ignore[arg-type]
        f"* Flagged only by task outcomes (no requirement failed): "
        f"{', '.join(summary['flagged_only_by_task_outcome']) or 'none'}.",  # type: ignore[arg-type]
        f"* Flagged by a named requirement: "
        f"{', '.join(summary['flagged_by_a_requirement']) or 'none'}.",  # type: ignore[arg-type]
    ]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3], metavar="S",
                        help="campaign seeds (suite and run seeds; default 1 2 3)")
    parser.add_argument("--workers", type=int, default=2, help="runs at once (default 2)")
    parser.add_argument("--only", nargs="+", default=None, metavar="NAME",
                        help="only these defects (the reference always runs)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke test: first seed, 2 rooms, one run per mission")
    parser.add_argument("--count", type=int, default=6, help="rooms per suite (demo: 6)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per mission (demo: 2)")
    parser.add_argument("--preset", choices=("small", "medium", "large"), default="small",
                        help="room class of the suite (demo: small)")
    parser.add_argument("--examples", action="store_true",
                        help="add the bundled examples (humans, a goal heading) to every "
                             "campaign")
    parser.add_argument("--markdown", action="store_true",
                        help="print the table for bench/RESULTS.md (full expected catchers)")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "out",
                        help="folder for suites, campaigns and bugs.json (default bench/out)")
    args = parser.parse_args()
    seeds, count, repeat = args.seeds, args.count, args.repeat
    if args.quick:
        seeds, count, repeat = seeds[:1], 2, 1
    navs = navigators(args.only)
    out: Path = args.out
    results: dict[str, list[CampaignOutcome]] = {n.name: [] for n in navs}
    started = time.perf_counter()
    for seed in seeds:
        inputs = suite(out / "suites", count, args.preset, seed, args.examples)
        for nav in navs:
            camp = run_one(nav, inputs, seed, repeat, args.workers,
                           out / "bugs" / f"seed{seed}" / nav.name)
            results[nav.name].append(camp)
            failed = sum(not r.passed for r in camp.runs)
            print(f"seed {seed} {nav.name}: {failed}/{len(camp.runs)} runs failed "
                  f"({camp.wall:.0f} s)", file=sys.stderr)
    summary = summarise(navs, results, seeds)
    settings = {"seeds": seeds, "count": count, "repeat": repeat, "preset": args.preset,
                "examples": args.examples, "workers": args.workers, "quick": args.quick,
                "wall_seconds": time.perf_counter() - started}
    report = {"settings": settings, "summary": summary,
              "campaigns": [asdict(c) for camps in results.values() for c in camps]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "bugs.json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print(f"{len(seeds)} seed(s) x {count} {args.preset} room(s) x {repeat} run(s)"
          f"{' + examples' if args.examples else ''}; {out / 'bugs.json'}\n")
    print(table(summary, args.markdown))
    return 0


if __name__ == "__main__":
    sys.exit(main())
