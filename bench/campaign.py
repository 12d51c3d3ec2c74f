"""Benchmark of `rei campaign`: missions per minute on 1 and 2 local workers for a suite of the
medium preset (scaling efficiency), and the overhead of the Dask engine against the local one
on the same campaign (a real `dask scheduler` and `dask worker` processes on 127.0.0.1).

Every measurement runs the same planned runs (same missions, seeds and --duration) from an
empty campaign folder; reports are not built (they are not part of running). The baseline is
the 1-worker local campaign measured in the same invocation. Cluster start-up is timed apart.

Targets (issue 8): scaling efficiency 1 -> 2 workers >= 90 %, Dask overhead < 10 %.

Usage: python bench/campaign.py [--count N] [--repeat K] [--duration S] [--rounds R]
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys
import tempfile
import time
from contextlib import redirect_stdout
from pathlib import Path

from rei.lang.cli import main as rei_gen
from rei.runtime.campaign import DaskEngine, LocalEngine, plan_campaign, run_campaign
from rei.runtime.campaign.cluster import loopback_cluster
from rei.runtime.campaign.engines import CampaignEngine
from rei.runtime.campaign.plan import CampaignPlan


def timed(plan: CampaignPlan, engine: CampaignEngine, out: Path) -> float:
    start = time.perf_counter()
    result = run_campaign(plan, out, engine, {"command": ["bench"]}, stream=io.StringIO())
    elapsed = time.perf_counter() - start
    assert result.complete and all(r.status == "ran" for r in result.records), \
        [r.message for r in result.records if r.status != "ran"]
    return elapsed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=8, help="medium rooms (default 8)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per mission (default 2)")
    parser.add_argument("--duration", type=float, default=30.0,
                        help="simulated seconds per run (default 30)")
    parser.add_argument("--rounds", type=int, default=2, help="measurements per setting")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="rei-bench-campaign-") as tmp:
        root = Path(tmp)
        with redirect_stdout(io.StringIO()):
            status = rei_gen(["rooms", "-o", str(root / "suite"), "--count", str(args.count),
                              "--preset", "medium", "--seed", str(args.seed)])
        if status != 0:
            return status
        plan = plan_campaign([root / "suite" / "index.csv"], repeat=args.repeat,
                             seed=args.seed, duration=args.duration)
        runs = len(plan.runs)
        print(f"medium preset: {args.count} rooms x {args.repeat} repeats = {runs} runs of "
              f"{args.duration:g} simulated s; {os.cpu_count()} CPUs; best of {args.rounds}")

        def best(name: str, engine: CampaignEngine) -> float:
            times = [timed(plan, engine, root / f"{name}-{i}") for i in range(args.rounds)]
            print(f"  {name:<8} {min(times):7.2f} s  (rounds: "
                  f"{', '.join(f'{t:.2f}' for t in times)})", flush=True)
            return min(times)

        one = best("local-1", LocalEngine(1))
        two = best("local-2", LocalEngine(2))
        start = time.perf_counter()
        with loopback_cluster(workers=2, threads=1) as address:
            startup = time.perf_counter() - start
            dask = best("dask-2", DaskEngine(address))
        per_min = {k: runs / v * 60 for k, v in (("1", one), ("2", two), ("dask", dask))}
        efficiency = one / (2 * two)
        overhead = dask / two - 1
        print()
        print("| setting | wall time [s] | missions/min |")
        print("|---|---|---|")
        print(f"| local, 1 worker | {one:.2f} | {per_min['1']:.1f} |")
        print(f"| local, 2 workers | {two:.2f} | {per_min['2']:.1f} |")
        print(f"| Dask, 2 workers x 1 thread | {dask:.2f} | {per_min['dask']:.1f} |")
        print()
        print(f"scaling efficiency 1 -> 2 workers: {100 * efficiency:.1f} % (target >= 90 %)")
        print(f"Dask engine overhead vs local (2 workers): {100 * overhead:+.1f} % "
              f"(target < 10 %)")
        print(f"Dask cluster start-up (scheduler + 2 workers, not in the above): {startup:.1f} s")
        print(f"single-run wall time, median over the 1-worker campaign: "
              f"{statistics.median(runs_wall(root / 'local-1-0')):.2f} s")
    return 0


def runs_wall(folder: Path) -> list[float]:
    from rei.runtime.campaign import CampaignStore  # noqa: PLC0415

    return [r.wall_time for r in CampaignStore.read(folder)[2]]


if __name__ == "__main__":
    sys.exit(main())
