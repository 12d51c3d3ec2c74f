"""Shrinking benchmark: how much of a failing case does `rei shrink` remove, and at what cost?

Each case is a mission that a navigator of bench/defects (one known defect) fails on every
seed. For each, the baseline is measured first in the same invocation: judging the original
case once on the K seeds (K `rei run` processes, CPU seconds of the process tree). Then
`rei shrink` runs (``rei.runtime.campaigns.shrink.shrink_into``, the original's verdicts reused from
that judgement) and the table reports: elements before and after (humans, objects, goals,
floors and trajectory vertices), the size reduction (1 - after/before, elements and
characters), runs spent, and the shrink's CPU time as a multiple of the baseline judgement.
The average reduction over the cases is the figure bench/search.py quotes for shrunk cases
(``average_reduction``).

Writes bench/out/shrinking/CASE/ (each shrink's output folder) and bench/out/shrinking.json;
``--markdown`` prints the table for bench/RESULTS.md; ``--quick`` shrinks only the fastest
case with 2 seeds.

Usage: python bench/shrinking.py [--seeds K] [--workers N] [--quick] [--markdown]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))  # bench.defects for the runs, started from REPO

from rei.runtime.campaigns.shrink import RunSettings, load_case, shrink_into  # noqa: E402
from rei.runtime.campaigns.shrink.oracle import FailureOracle  # noqa: E402
from rei.runtime.campaigns.shrink.shrinker import JOURNAL  # noqa: E402

EXAMPLES = REPO / "examples"


@dataclass(frozen=True)
class ShrinkCase:
    name: str
    mission: Path
    controller: str
    requirement: str
    duration: float | None = None


CASES = (
    ShrinkCase("cluttered/speeding", REPO / "tests" / "shrink" / "cases" / "cluttered.mission",
               "bench.defects.control:ExceedsDriveLimit", "SPEED_LIMIT", 3.0),
    ShrinkCase("navigation/footprint", EXAMPLES / "navigation" / "navigation.mission",
               "bench.defects.planning:FootprintTooSmall", "NO_ROBOT_COLLISION"),
    ShrinkCase("navigation/goal-heading", EXAMPLES / "navigation" / "navigation.mission",
               "bench.defects.mission:IgnoresGoalHeading", "GOAL_HEADING"),
    ShrinkCase("small_dense/footprint", EXAMPLES / "small_dense" / "small_dense.mission",
               "bench.defects.planning:FootprintTooSmall", "NO_ROBOT_COLLISION"),
)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def average_reduction(reductions: Sequence[float]) -> float:
    """The mean size reduction (``reduction.elements`` of shrink.json) over shrunk cases."""
    return sum(reductions) / len(reductions) if reductions else 0.0


def bench_case(case: ShrinkCase, seeds: int, workers: int, out: Path) -> dict[str, Any]:
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    settings = RunSettings(seeds=tuple(range(seeds)), controller=case.controller,
                           duration=case.duration, workers=workers)
    start = children_cpu()
    # the baseline: one judgement of the original on the K seeds (remembered in the journal,
    # so the shrink below does not run it again)
    oracle = FailureOracle(settings, out / ".baseline", out / JOURNAL)
    original = oracle.outcomes(load_case(case.mission))
    baseline = children_cpu() - start
    shutil.rmtree(out / ".baseline", ignore_errors=True)
    start = children_cpu()
    report = shrink_into(case.mission, out, settings, requirement=case.requirement,
                         max_runs=300,
                         progress=lambda line: print(f"  {case.name}: {line}", file=sys.stderr))
    cost = children_cpu() - start
    before, after = report.before, report.after or report.before
    return {"case": case.name, "controller": case.controller, "requirement": case.requirement,
            "result": report.result, "seeds": seeds,
            "original": [o.to_json() for o in original], "before": before, "after": after,
            "reduction": report.reduction(), "runs": report.runs,
            "baseline_cpu": round(baseline, 2), "shrink_cpu": round(cost, 2),
            "cost_in_judgements": round(cost / baseline, 1) if baseline > 0 else None}


def markdown(rows: list[dict[str, Any]]) -> str:
    kinds = ("humans", "objects", "goals", "floors", "trajectory_vertices")
    lines = ["| case | requirement | " + " | ".join(k.replace("_", " ") for k in kinds)
             + " | elements | reduction (elements / chars) | runs | CPU s (baseline) | "
             "cost / baseline |",
             "|---|---|" + "---|" * len(kinds) + "---|---|---|---|---|"]
    for r in rows:
        b, a = r["before"], r["after"]
        lines.append(
            f"| {r['case']} | {r['requirement']} | "
            + " | ".join(f"{b[k]} → {a[k]}" for k in kinds)
            + f" | {b['elements']} → {a['elements']} | {100 * r['reduction']['elements']:.0f} % / "
              f"{100 * r['reduction']['characters']:.0f} % | {r['runs']} | "
              f"{r['shrink_cpu']:.0f} ({r['baseline_cpu']:.0f}) | {r['cost_in_judgements']}× |")
    shrunk = [r["reduction"]["elements"] for r in rows if r["result"] == "shrunk"]
    lines.append("")
    lines.append(f"Average size reduction over {len(shrunk)} shrunk cases: "
                 f"{100 * average_reduction(shrunk):.0f} % of the elements.")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args(argv)
    os.chdir(REPO)
    cases = CASES[:1] if args.quick else CASES
    seeds = 2 if args.quick else args.seeds
    root = REPO / "bench" / "out" / "shrinking"
    rows = [bench_case(c, seeds, args.workers, root / c.name.replace("/", "-")) for c in cases]
    (REPO / "bench" / "out").mkdir(exist_ok=True)
    (REPO / "bench" / "out" / "shrinking.json").write_text(json.dumps(rows, indent=2) + "\n",
                                                           encoding="utf-8")
    print(markdown(rows) if args.markdown else json.dumps(rows, indent=2))
    print(f"load average: {os.getloadavg()[0]:.1f}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
