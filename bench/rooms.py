"""Benchmark of `rei-gen rooms`: valid rooms per second per preset, on one core.

For each preset: generate a suite (construct, describe, write text, check with the
`rei-gen check` rules, write the files), then re-check every written file from disk with a
fresh Workspace to confirm the share that is valid. Reports the stage times, the share of
candidates the checker rejected and of construction attempts that failed, and, as the
baseline measured in the same run, the rate of checking alone (parse + link + layout of the
same files), which bounds any generator that validates with the shared checker.

Usage: python bench/rooms.py [--count N] [--seed S] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from rei.generators.rooms import (
    StageTimes,
    SuiteRequest,
    coverage_report,
    generate,
    preset_space,
    write_suite,
)
from rei.lang.workspace import Workspace


def bench_preset(preset: str, count: int, seed: int, out: Path) -> dict[str, float]:
    times = StageTimes()
    cpu_start = time.process_time()
    start = time.perf_counter()
    suite = generate(SuiteRequest(preset_space(preset), "random", count, seed), out, times)
    write_suite(suite, out, coverage_report(suite), times)
    elapsed = time.perf_counter() - start
    cpu = time.process_time() - cpu_start

    check_start = time.perf_counter()
    check_cpu_start = time.process_time()
    workspace = Workspace()
    errors = 0
    valid = 0
    for pair in suite.pairs:
        problems = [d for d in workspace.check(out / pair.room_file)
                    + workspace.check(out / pair.mission_file) if d.is_error]
        errors += len(problems)
        valid += not problems
    check_only = time.perf_counter() - check_start
    check_only_cpu = time.process_time() - check_cpu_start

    attempts = sum(p.attempts for p in suite.pairs)
    rejected = sum(p.rejected for p in suite.pairs)
    return {
        "rooms": len(suite.pairs),
        "seconds": elapsed,
        "rate": len(suite.pairs) / elapsed,
        "cpu_rate": len(suite.pairs) / cpu,
        "check_only_cpu_rate": len(suite.pairs) / check_only_cpu,
        "valid_share": valid / len(suite.pairs),
        "attempts": attempts,
        "construction_failed": attempts - len(suite.pairs) - rejected,
        "checker_rejected": rejected,
        "construct_ms": 1000 * times.construct / len(suite.pairs),
        "text_ms": 1000 * times.text / len(suite.pairs),
        "check_ms": 1000 * times.check / len(suite.pairs),
        "write_ms": 1000 * times.write / len(suite.pairs),
        "check_only_rate": len(suite.pairs) / check_only,
        "check_only_seconds": check_only,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    with tempfile.TemporaryDirectory() as tmp:
        root = args.out or Path(tmp)
        # Warm-up: imports, grammar loading, caches.
        bench_preset("small", 5, args.seed + 1, root / "warmup")
        print(f"load average before: {os.getloadavg()[0]:.2f}")
        print("| preset | rooms | valid | rooms/s wall | rooms/CPU-s | attempts per room | "
              "construction failures | checker rejections | construct ms | text ms | "
              "check ms | write ms | check-only rooms/CPU-s (baseline) | ratio (CPU) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for preset in ("small", "medium", "large", "stress"):
            count = args.count if preset != "large" else max(1, args.count // 3)
            r = bench_preset(preset, count, args.seed, root / preset)
            print(f"| {preset} | {r['rooms']:.0f} | {100 * r['valid_share']:.0f}% | "
                  f"{r['rate']:.1f} | {r['cpu_rate']:.1f} | {r['attempts'] / r['rooms']:.3f} | "
                  f"{100 * r['construction_failed'] / r['attempts']:.1f}% | "
                  f"{100 * r['checker_rejected'] / r['attempts']:.1f}% | "
                  f"{r['construct_ms']:.2f} | {r['text_ms']:.2f} | {r['check_ms']:.2f} | "
                  f"{r['write_ms']:.2f} | {r['check_only_cpu_rate']:.1f} | "
                  f"{r['cpu_rate'] / r['check_only_cpu_rate']:.2f} |", flush=True)
        print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
