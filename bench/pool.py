"""Benchmark of the kept worker pool (rei.runtime.campaigns.engines.WorkerPool, issue 26 item 1):
CPU seconds per candidate of a shrink (its failure oracle) and of a search (its batches),
before (each candidate or batch starts its own workers and fork servers, as before the pool)
and after (one pool for the whole command), alternating in the same invocation.

CPU time is every process of the measurement, the runs and fork servers included (getrusage of
the waited-for children), so other jobs on a shared machine do not count, but slow it. The
baseline is the "before" measured in the same round; ratios after / before are reported.

Usage: python bench/pool.py [--candidates K] [--budget N] [--batch B] [--rounds R]
"""

from __future__ import annotations

import argparse
import io
import os
import resource
import tempfile
from pathlib import Path

from rei.runtime.campaigns import LocalEngine
from rei.runtime.campaigns.engines import WorkerPool, kept_workers
from rei.runtime.campaigns.search import run_search
from rei.runtime.campaigns.search.driver import SearchConfig
from rei.runtime.campaigns.shrink.case import load_case
from rei.runtime.campaigns.shrink.oracle import FailureOracle, RunSettings

MISSION = Path(__file__).resolve().parents[1] / "examples" / "simple_wall" / \
    "simple_wall.mission"


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def shrink_candidates(root: Path, candidates: int, kept: bool) -> float:
    """CPU s per candidate of the shrink's oracle judging ``candidates`` candidates (the
    same case judged afresh each time: what a shrink pays per candidate) on 2 seeds."""
    settings = RunSettings(seeds=(0, 1), duration=2.0, workers=2)
    case = load_case(MISSION)
    cpu = children_cpu()
    pool = WorkerPool(settings.workers) if kept else None
    try:
        oracle = FailureOracle(settings, root / "work", root / "journal.jsonl", pool=pool)
        for _ in range(candidates):
            oracle.known.clear()  # judged again, as a new candidate would be
            oracle.outcomes(case)
    finally:
        if pool is not None:
            pool.close()
    return (children_cpu() - cpu) / candidates


def search_candidates(root: Path, budget: int, batch: int, kept: bool) -> float:
    """CPU s per simulated candidate of a random search of ``budget`` small rooms in
    batches of ``batch`` (runs cut at 2 simulated s)."""
    config = SearchConfig(preset="small", strategy="random", seed=0, budget=budget,
                          batch=batch, duration=2.0)
    cpu = children_cpu()
    engine = LocalEngine(2, pages="none")
    if kept:
        with kept_workers(engine) as pooled:
            result = run_search(config, root, pooled, {"command": ["bench/pool.py"]},
                                stream=io.StringIO())
    else:
        result = run_search(config, root, engine, {"command": ["bench/pool.py"]},
                            stream=io.StringIO())
    simulated = sum(r.record is not None for r in result.results)
    return (children_cpu() - cpu) / max(1, simulated)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--candidates", type=int, default=6, help="shrink candidates")
    parser.add_argument("--budget", type=int, default=12, help="search candidates")
    parser.add_argument("--batch", type=int, default=2, help="search batch size")
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    rows: dict[str, list[float]] = {}
    loads = []
    with tempfile.TemporaryDirectory(prefix="rei-bench-pool-") as tmp:
        for i in range(args.rounds):
            loads.append(os.getloadavg()[0])
            for kept in (False, True):
                label = "after" if kept else "before"
                rows.setdefault(f"shrink {label}", []).append(shrink_candidates(
                    Path(tmp) / f"shrink-{label}-{i}", args.candidates, kept))
                rows.setdefault(f"search {label}", []).append(search_candidates(
                    Path(tmp) / f"search-{label}-{i}", args.budget, args.batch, kept))
            print(f"  round {i + 1} (load average before: {loads[-1]:.2f}): " + ", ".join(
                f"{k} {v[-1]:.2f}" for k, v in rows.items()), flush=True)
    print()
    print("| CPU s per candidate (best of rounds) | before (workers per call) | after (kept "
          "pool) | after / before |")
    print("|---|---:|---:|---:|")
    for title, key in ((f"shrink oracle, 2 seeds x 2 s, {args.candidates} candidates",
                        "shrink"),
                       (f"random search, {args.budget} candidates in batches of {args.batch}, "
                        f"2 s", "search")):
        before, after = min(rows[f"{key} before"]), min(rows[f"{key} after"])
        print(f"| {title} | {before:.2f} | {after:.2f} | {after / before:.2f} |")
    print(f"\nload average before each round: {', '.join(f'{x:.2f}' for x in loads)}; "
          f"{os.cpu_count()} CPUs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
