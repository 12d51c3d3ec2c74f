"""Bug-finding benchmark: does REI fail buggy navigation software and pass correct software?

Runs the campaign `rei demo` runs (a suite of ``--count`` generated ``--preset`` rooms, seed S,
every mission ``--repeat`` times with seeds derived from S, the default .vepl) once per
campaign seed with each navigator: the correct `reference` (the baseline, measured in the same
invocation) and every defective navigator of bench/defects (one realistic defect each). A run
fails as `rei campaign` counts it: it did not complete its mission (a failed task, a time-out,
a crash) or a requirement's verdict is not "pass". A navigator is *flagged* on a seed when any
run of that campaign fails; it is *caught* on a seed when it fails a run (same mission, repeat
and seed) that the reference passed: failures both share are the suite's (a mission the
correct navigator cannot complete either), not detections.

Reported per navigator: seeds caught (and flagged), failed runs, and what caught them: each
requirement whose verdict was "fail" (counted over the failed runs the reference passed; names
are read from the runs' summary.json, none is assumed here), "inconclusive" verdicts apart, and
the runs whose only failure is the task outcome ("task:failed (timeout)", "task:crashed", ...).
A second table names, per defect and seed, the requirements that caught it (the target: a
named requirement on every seed). Then: detection rate (defects caught on every seed / defects;
and caught seed-campaigns /
defect seed-campaigns), the reference's false-alarm rate (its campaigns with any failed run),
which defects were caught only by task outcomes, and each navigator's campaign wall time (noisy
on a shared machine) and simulated seconds (deterministic: longer missions, time-outs) relative
to the reference's on the same seed.

Writes bench/out/bugs.json (every run's verdicts); ``--markdown`` prints the table for
bench/RESULTS.md. ``--quick`` is a smoke test: the first seed, 2 rooms, one run per mission.
``--examples`` adds the four bundled examples to every campaign: the small preset has no
humans and no goal headings or speed limits, so some defects cannot show in the demo suite.

Usage: python bench/bugs.py [--seeds S ...] [--workers N] [--only NAME ...] [--quick]
       [--count N] [--repeat K] [--preset small|medium|large] [--examples] [--resume]
       [--markdown] [--out DIR]
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
from typing import Any

REPO = Path(__file__).resolve().parent.parent
# The defects are `bench.defects.MODULE:Class`: importable here and in every run's process
# (a run imports its controller from its own working folder and PYTHONPATH).
sys.path.insert(0, str(REPO))
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)

from bench.defects import DEFECTS  # noqa: E402
from rei.runtime.campaigns import LocalEngine, RunRecord, plan_campaign, run_campaign  # noqa: E402
from rei.runtime.robot import load_controller  # noqa: E402

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
    task_failures: tuple[str, ...]
    """Why tasks failed, by kind ("timeout", "aborted", "outside tolerance", ...)."""
    failed: tuple[str, ...]
    """Requirements whose verdict was "fail"."""
    inconclusive: tuple[str, ...]
    reasons: dict[str, str] = field(default_factory=dict)
    """Each failed requirement's reason."""

    @property
    def catchers(self) -> list[str]:
        """What made this run fail: its failed (and inconclusive) requirements, and its outcome
        when it did not complete its mission."""
        if self.passed:
            return []
        found = list(self.failed) + [INCONCLUSIVE + r for r in self.inconclusive]
        if self.status != "ran" or self.outcome != "completed":
            kinds = "/".join(self.task_failures)
            found.append(TASK + (self.outcome if self.status == "ran" else self.status)
                         + (f" ({kinds})" if kinds else ""))
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
        doc = type(load_controller(d.spec)).__doc__ or ""
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


def failure_kind(reason: str) -> str:
    """A task's failure reason without its figures: "timeout after 30 s" -> "timeout"."""
    kind = reason.split(":")[0].strip()
    return "timeout" if kind.startswith("timeout") else kind


def outcome_of(record: RunRecord) -> RunOutcome:
    s = record.summary
    verdicts = s.verdicts if s is not None else ()
    tasks = s.measurements.get("tasks", []) if s is not None else []
    kinds = sorted({failure_kind(str(t.get("reason", ""))) for t in tasks
                    if isinstance(t, dict) and not t.get("succeeded", True)})
    return RunOutcome(
        run_id=record.spec.run_id, seed=record.spec.seed, passed=record.passed,
        outcome=record.outcome, status=record.status, reason=record.reason,
        simulated=s.duration if s is not None else 0.0,
        task_failures=tuple(kinds),
        failed=tuple(v.requirement for v in verdicts if v.status == "fail"),
        inconclusive=tuple(v.requirement for v in verdicts if v.status == "inconclusive"),
        reasons={v.requirement: v.reason for v in verdicts if v.status == "fail"})


def run_one(nav: Navigator, inputs: list[Path], seed: int, repeat: int, workers: int,
            root: Path, resume: bool) -> CampaignOutcome:
    plan = plan_campaign(inputs, repeat=repeat, seed=seed,
                         controller=None if nav.spec == REFERENCE else nav.spec)
    if not resume:  # a fresh campaign: never mix in runs of older code
        shutil.rmtree(root, ignore_errors=True)
    start = time.perf_counter()
    result = run_campaign(plan, root, LocalEngine(workers), {"command": ["bench/bugs.py"]},
                          stream=io.StringIO())
    wall = time.perf_counter() - start
    return CampaignOutcome(nav.name, seed, wall, tuple(outcome_of(r) for r in result.records))


def suite(out: Path, count: int, preset: str, seed: int, examples: bool,
          stressor: str | None = None) -> list[Path]:
    """The demo's suite; with ``stressor``, ``count`` stress rooms of that one stressor
    instead (their movers' sides alternate over the suite, as in every suite)."""
    from rei.runtime.commands.demo import EXAMPLES, generate_suite  # noqa: PLC0415

    if stressor is None:
        inputs = generate_suite(out / f"suite-{preset}-{count}-seed{seed}", count, preset, seed)
    else:
        from rei.lang.cli import main as rei_gen  # noqa: PLC0415

        folder = out / f"suite-stress-{stressor}-{count}-seed{seed}"
        if not (folder / "index.csv").is_file():
            status = rei_gen(["rooms", "-o", str(folder), "--preset", "stress", "--stressor",
                              stressor, "--count", str(count), "--seed", str(seed)])
            if status != 0:
                raise SystemExit(status)
        inputs = [folder / "index.csv"]
    return [*inputs, EXAMPLES] if examples and EXAMPLES not in inputs else inputs


def catchers(campaigns: list[CampaignOutcome]) -> Counter[str]:
    return Counter(c for camp in campaigns for r in camp.runs for c in r.catchers)


def summarise(navs: list[Navigator], results: dict[str, list[CampaignOutcome]],
              seeds: list[int]) -> dict[str, Any]:
    """Per navigator and overall figures. Runs are paired with the reference's run of the same
    mission, repeat and seed: a defect is *caught* on a seed when it fails a run the reference
    passed (a failure both share, such as a mission the reference cannot complete either, is
    the suite's, not a detection)."""
    ref_camps = results[REFERENCE]
    ref_wall = {c.seed: c.wall for c in ref_camps}
    ref_sim = {c.seed: c.simulated for c in ref_camps}
    ref_passed = {(c.seed, r.run_id) for c in ref_camps for r in c.runs if r.passed}
    rows: list[dict[str, Any]] = []
    for nav in navs:
        camps = results[nav.name]
        new = [[r for r in c.runs if not r.passed and (c.seed, r.run_id) in ref_passed]
               for c in camps]
        caught = Counter(k for runs in new for r in runs for k in r.catchers)
        named = sorted(k for k in caught if not k.startswith((TASK, INCONCLUSIVE)))
        ratios = [c.wall / ref_wall[c.seed] for c in camps if ref_wall.get(c.seed)]
        sim = [c.simulated / ref_sim[c.seed] for c in camps if ref_sim.get(c.seed)]
        rows.append({
            "navigator": nav.name, "kind": nav.kind, "spec": nav.spec,
            "expected_catcher": nav.expected,
            "seeds": len(camps),
            "seeds_flagged": sum(c.flagged for c in camps),
            "seeds_caught": sum(bool(runs) for runs in new),
            "runs": sum(len(c.runs) for c in camps),
            "runs_failed": sum(not r.passed for c in camps for r in c.runs),
            "runs_failed_reference_passed": sum(len(runs) for runs in new),
            "caught_by": dict(caught.most_common()),
            "caught_by_all_failed_runs": dict(catchers(camps).most_common()),
            "caught_by_requirement": bool(named),
            "per_seed": {str(c.seed): dict(Counter(k for r in runs for k in r.catchers)
                                           .most_common())
                         for c, runs in zip(camps, new, strict=True)},
            "time_vs_reference": sum(ratios) / len(ratios) if ratios else None,
            "simulated_vs_reference": sum(sim) / len(sim) if sim else None,
        })
    defects = [r for r in rows if r["navigator"] != REFERENCE]
    ref = rows[0]

    def rate(key: str, every: bool) -> float | None:
        if not defects:
            return None
        if every:
            return sum(r[key] == r["seeds"] for r in defects) / len(defects)
        return sum(r[key] for r in defects) / sum(r["seeds"] for r in defects)

    return {
        "seeds": seeds,
        "rows": rows,
        "detection_rate_every_seed": rate("seeds_caught", True),
        "detection_rate_per_seed_campaign": rate("seeds_caught", False),
        "flagged_rate_every_seed": rate("seeds_flagged", True),
        "flagged_rate_per_seed_campaign": rate("seeds_flagged", False),
        "false_alarm_rate": ref["seeds_flagged"] / ref["seeds"] if ref["seeds"] else None,
        "reference_failed_runs": ref["runs_failed"],
        "defects_caught_every_seed": [r["navigator"] for r in defects
                                      if r["seeds_caught"] == r["seeds"]],
        "defects_never_caught": [r["navigator"] for r in defects if r["seeds_caught"] == 0],
        "caught_only_by_task_outcome": [r["navigator"] for r in defects
                                        if r["seeds_caught"] and not r["caught_by_requirement"]],
        "caught_by_a_requirement": [r["navigator"] for r in defects
                                    if r["caught_by_requirement"]],
        "caught_by_a_requirement_every_seed": [
            r["navigator"] for r in defects if r["per_seed"] and all(
                any(not k.startswith((TASK, INCONCLUSIVE)) for k in found)
                for found in r["per_seed"].values())],
    }


def named_catchers(found: dict[str, int]) -> str:
    """The requirements that failed in the runs the reference passed, most runs first; the
    task outcome or inconclusive verdicts only when no requirement failed."""
    named = [f"{k} ({n})" for k, n in found.items() if not k.startswith((TASK, INCONCLUSIVE))]
    if named:
        return ", ".join(named)
    other = [f"{k} ({n})" for k, n in found.items()]
    return ("only " + ", ".join(other)) if other else "not caught"


def seed_table(summary: dict[str, Any]) -> str:
    """Per defect and seed: which requirement caught it (runs the reference passed)."""
    seeds = [str(s) for s in summary["seeds"]]
    lines = ["| navigator | " + " | ".join(f"seed {s}" for s in seeds) + " |",
             "|---|" + "---|" * len(seeds)]
    for r in summary["rows"]:
        if r["navigator"] == REFERENCE:
            continue
        cells = [named_catchers(r["per_seed"].get(s, {})) for s in seeds]
        lines.append(f"| {r['navigator']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table(summary: dict[str, Any], markdown: bool) -> str:
    lines = ["| navigator | kind | seeds caught (flagged) | failed runs the reference passed "
             "(all failed) | caught by (runs the reference passed) | expected catcher "
             "| campaign time vs reference | simulated s vs reference |",
             "|---|---|---:|---:|---|---|---:|---:|"]
    for r in summary["rows"]:
        caught = ", ".join(f"{k} × {n}" for k, n in r["caught_by"].items()) or "—"
        ratio, sim = r["time_vs_reference"], r["simulated_vs_reference"]
        expected = r["expected_catcher"] if markdown else r["expected_catcher"][:50] + "…"
        lines.append(
            f"| {r['navigator']} | {r['kind']} | {r['seeds_caught']}/{r['seeds']} "
            f"({r['seeds_flagged']}) | {r['runs_failed_reference_passed']}/{r['runs']} "
            f"({r['runs_failed']}) | {caught} | {expected} | "
            f"{'—' if ratio is None else f'{ratio:.2f}'} | "
            f"{'—' if sim is None else f'{sim:.2f}'} |")

    def pct(key: str) -> str:
        value = summary[key]
        return "—" if value is None else f"{100 * value:.0f} %"

    n_defects = len(summary["rows"]) - 1
    lines += [
        "",
        f"* Detection rate (defects caught on every seed, i.e. failing a run the reference "
        f"passed): {len(summary['defects_caught_every_seed'])}/{n_defects} = "
        f"{pct('detection_rate_every_seed')}; per seed-campaign: "
        f"{pct('detection_rate_per_seed_campaign')}. Flagged at all (any failed run, shared "
        f"failures included): {pct('flagged_rate_every_seed')}; per seed-campaign: "
        f"{pct('flagged_rate_per_seed_campaign')}.",
        f"* False-alarm rate (reference campaigns with any failed run): "
        f"{pct('false_alarm_rate')} ({summary['reference_failed_runs']} failed run(s)).",
        f"* Never caught: {', '.join(summary['defects_never_caught']) or 'none'}.",
        f"* Caught only by task outcomes (no requirement failed): "
        f"{', '.join(summary['caught_only_by_task_outcome']) or 'none'}.",
        f"* Caught by a named requirement: "
        f"{', '.join(summary['caught_by_a_requirement']) or 'none'}.",
        f"* Caught by a named requirement on every seed: "
        f"{len(summary['caught_by_a_requirement_every_seed'])}/{n_defects} "
        f"({', '.join(summary['caught_by_a_requirement_every_seed']) or 'none'}).",
        "",
        "Per defect and seed, the requirements that failed in runs the reference passed "
        "(number of runs):",
        "",
        seed_table(summary),
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
    parser.add_argument("--count", type=int, default=8, help="rooms per suite (demo: 8)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per mission (demo: 2)")
    parser.add_argument("--preset", choices=("small", "medium", "large"), default="small",
                        help="room class of the suite (demo: small)")
    parser.add_argument("--stressor", default=None, metavar="KIND",
                        help="instead of the demo's suite, --count stress rooms of this one "
                             "stressor (e.g. doorway)")
    parser.add_argument("--examples", action="store_true",
                        help="add the bundled examples (humans, a goal heading) to every "
                             "campaign")
    parser.add_argument("--resume", action="store_true",
                        help="keep the campaigns of an earlier invocation with the same "
                             "settings and run only what they miss (campaign time ratios are "
                             "then meaningless)")
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
        inputs = suite(out / "suites", count, args.preset, seed, args.examples, args.stressor)
        for nav in navs:
            camp = run_one(nav, inputs, seed, repeat, args.workers,
                           out / "bugs" / f"seed{seed}" / nav.name, args.resume)
            results[nav.name].append(camp)
            failed = sum(not r.passed for r in camp.runs)
            print(f"seed {seed} {nav.name}: {failed}/{len(camp.runs)} runs failed "
                  f"({camp.wall:.0f} s)", file=sys.stderr)
    summary = summarise(navs, results, seeds)
    settings = {"seeds": seeds, "count": count, "repeat": repeat, "preset": args.preset,
                "examples": args.examples, "stressor": args.stressor,
                "workers": args.workers, "quick": args.quick,
                "resumed": args.resume,
                "wall_seconds": time.perf_counter() - started}
    report = {"settings": settings, "summary": summary,
              "campaigns": [asdict(c) for camps in results.values() for c in camps]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "bugs.json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    rooms = f"{args.stressor} stress" if args.stressor else args.preset
    print(f"{len(seeds)} seed(s) x {count} {rooms} room(s) x {repeat} run(s)"
          f"{' + examples' if args.examples else ''}; {out / 'bugs.json'}\n")
    print(table(summary, args.markdown))
    return 0


if __name__ == "__main__":
    sys.exit(main())
