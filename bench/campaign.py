"""Benchmark of `rei campaign`: missions per minute on 1 and 2 local workers for a suite of the
medium preset (scaling efficiency), and the overhead of the Dask engine against the local one
on the same campaign (a real `dask scheduler` and `dask worker` processes on 127.0.0.1).

Every measurement runs the same planned runs (same missions, seeds and --duration) from an
empty campaign folder; reports are not built (they are not part of running). The baseline is
the 1-worker local campaign measured in the same invocation. Cluster start-up is timed apart.

Targets (issue 8): scaling efficiency 1 -> 2 workers >= 90 %, Dask overhead < 10 %.

With --figures, instead: what users feel, before and after, alternating in the same
invocation — runs per CPU minute of a medium campaign on 2 workers, the start-up CPU seconds
per run (the same campaign with runs cut after --startup-duration simulated seconds), and the
wall time of `rei demo` on 2 workers. --compare pages: before = every run its full page
(--pages all), after = full pages only for runs that did not pass (--pages failed, the
default of campaigns; issue 26). --compare warm (default): before = REI_WARM=off (every
process a fresh interpreter), after = warm workers (rei.runtime.platform.warm: a fork server per
worker,
the simulation and the robot's host forked), the cache on in both; --compare cache: before =
REI_CACHE_DIR=off, after = the campaign's cache. CPU time is every process of the campaign,
the runs' children included (getrusage of the waited-for children), so other jobs on a shared
machine do not count, but slow it. With --sample N (N > 0) also the headline a user compares
with a cluster: N whole runs of the medium preset on 2 workers, before and after, and 1,000
runs extrapolated from them (wall: N runs' wall x 1000/N; CPU: CPU s per run x 1000 / 2
cores, the wall two free cores would take).
With --alone N: `rei run` alone, as a user types it (examples/navigation cut at 0.01 simulated
s: start-up and outputs), N times before and after alternating, CPU s of its process tree.
Targets (issue 26): start-up <= 0.25 CPU s per run in a campaign, `rei run` alone <= 0.6 CPU
s, `rei demo` <= 20 s wall, 1,000 medium runs on two cores <= 10 minutes.

Usage: python bench/campaign.py [--count N] [--repeat K] [--duration S] [--rounds R] [--seed S]
       python bench/campaign.py --figures [--compare warm|cache] [--count N] [--repeat K]
                                [--rounds R] [--sample N]
       python bench/campaign.py --alone N [--compare warm|cache]
"""

from __future__ import annotations

import argparse
import io
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager, redirect_stdout
from pathlib import Path

from rei.lang.cli import main as rei_gen
from rei.runtime.campaigns import (
    CampaignStore,
    DaskEngine,
    LocalEngine,
    plan_campaign,
    run_campaign,
)
from rei.runtime.campaigns.dask_cluster import loopback_cluster
from rei.runtime.campaigns.engines import CampaignEngine
from rei.runtime.campaigns.plan import CampaignPlan


def timed(plan: CampaignPlan, engine: CampaignEngine, out: Path) -> float:
    start = time.perf_counter()
    result = run_campaign(plan, out, engine, {"command": ["bench"]}, stream=io.StringIO())
    elapsed = time.perf_counter() - start
    assert result.complete and all(r.status == "ran" for r in result.records), \
        [r.message for r in result.records if r.status != "ran"]
    return elapsed


def _spin(n: int) -> int:
    total = 0
    for i in range(n):
        total += i * i % 7
    return total


def machine_scaling(n: int = 6_000_000) -> float:
    """How much faster two CPU-bound processes finish than one after the other on this machine
    (1.0 = two independent cores; two hyperthreads of one core or a busy host give less): the
    ceiling any engine's scaling efficiency can reach here."""
    import multiprocessing  # noqa: PLC0415

    ctx = multiprocessing.get_context("spawn")
    start = time.perf_counter()
    with ctx.Pool(1) as pool:
        pool.map(_spin, [n, n])
    one = time.perf_counter() - start
    start = time.perf_counter()
    with ctx.Pool(2) as pool:
        pool.map(_spin, [n, n])
    two = time.perf_counter() - start
    return one / (2 * two)


def children_cpu() -> float:
    """CPU seconds of every waited-for child process (and theirs) so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


SETTINGS = {"warm": ("REI_WARM", "off"), "cache": ("REI_CACHE_DIR", "off"),
            "pages": ("--pages", "all")}
"""--compare: the variable (or, for pages, the option) that turns the measured feature off
(before)."""


def pages(compare: str, on: bool) -> str:
    """The campaigns' --pages: 'failed' (the default: full pages for runs that did not pass
    only) after with --compare pages, 'all' (every run its full page, as before the option)
    otherwise, so the warm and cache figures stay comparable with earlier ones."""
    return "failed" if compare == "pages" and on else "all"


@contextmanager
def setting(compare: str, on: bool) -> Iterator[None]:
    """The feature off (before: its variable set to off) or on (after: the variable unset)
    for the processes started meanwhile."""
    if compare == "pages":  # an option, not a variable (see ``pages``)
        yield
        return
    name, off = SETTINGS[compare]
    saved = os.environ.get(name)
    if on:
        os.environ.pop(name, None)
    else:
        os.environ[name] = off
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = saved


def measured(plan: CampaignPlan, out: Path, compare: str, on: bool) -> tuple[float, float]:
    """(wall s, CPU s of all processes) of the campaign on 2 local workers."""
    with setting(compare, on):
        cpu = children_cpu()
        wall = timed(plan, LocalEngine(2, pages=pages(compare, on)), out)
        return wall, children_cpu() - cpu


def demo(out: Path, compare: str, on: bool) -> tuple[float, float]:
    """(wall s, CPU s) of `rei demo -o OUT --workers 2`, as a user types it."""
    with setting(compare, on):
        cpu = children_cpu()
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "rei.runtime.commands", "demo", "-o", str(out),
                        "--workers", "2", "--pages", pages(compare, on), "-q"], check=False,
                       stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        return time.perf_counter() - start, children_cpu() - cpu


def figures(args: argparse.Namespace, root: Path) -> int:
    plan = plan_campaign([root / "suite" / "index.csv"], repeat=args.repeat, seed=args.seed)
    cut = plan_campaign([root / "suite" / "index.csv"], repeat=args.repeat, seed=args.seed,
                        duration=args.startup_duration)
    runs = len(plan.runs)
    name, off = SETTINGS[args.compare]
    print(f"medium preset: {args.count} rooms x {args.repeat} repeats = {runs} runs on 2 local "
          f"workers; {os.cpu_count()} CPUs; {args.rounds} rounds; before = {name}={off}, "
          f"after = {args.compare} on")
    rows: dict[str, list[tuple[float, float]]] = {}
    loads: list[float] = []
    for i in range(args.rounds):
        loads.append(os.getloadavg()[0])
        for on in (False, True):
            label = "after" if on else "before"
            rows.setdefault(f"whole {label}", []).append(
                measured(plan, root / f"whole-{label}-{i}", args.compare, on))
            rows.setdefault(f"start-up {label}", []).append(
                measured(cut, root / f"cut-{label}-{i}", args.compare, on))
            rows.setdefault(f"demo {label}", []).append(
                demo(root / f"demo-{label}-{i}", args.compare, on))
        if args.compare == "pages":
            # start-up alone: a run cut at 0.1 s does not pass, so it draws its full page
            # under both settings above; without any page, what is left is the start-up
            with setting(args.compare, True):
                cpu = children_cpu()
                wall = timed(cut, LocalEngine(2, pages="none"), root / f"cut-none-{i}")
                rows.setdefault("start-up none", []).append((wall, children_cpu() - cpu))
        print(f"  round {i + 1} (load average before: {loads[-1]:.2f}): " + ", ".join(
            f"{k} {v[-1][0]:.1f} s wall / {v[-1][1]:.1f} CPU s" for k, v in rows.items()),
            flush=True)
    simulated = sum(r.summary.duration for r in CampaignStore.read(root / "whole-after-0")[2]
                    if r.summary is not None)
    sample = headline(args, root) if args.sample > 0 else {}

    def best(key: str) -> tuple[float, float]:
        return min(rows[key], key=lambda pair: pair[1])

    print()
    print(f"| measure | before ({name}={off}) | after ({args.compare} on) | after / before |")
    print("|---|---:|---:|---:|")
    for title, key, show in (
            ("whole runs: runs per CPU minute", "whole", lambda w, c: runs / c * 60),
            ("whole runs: CPU s per run", "whole", lambda w, c: c / runs),
            ("whole runs: wall s (2 workers)", "whole", lambda w, c: w),
            (f"start-up: CPU s per run (runs cut at {args.startup_duration:g} simulated s)",
             "start-up", lambda w, c: c / runs),
            ("`rei demo --workers 2`: wall s", "demo", lambda w, c: w),
            ("`rei demo --workers 2`: CPU s", "demo", lambda w, c: c)):
        before, after = show(*best(f"{key} before")), show(*best(f"{key} after"))
        print(f"| {title} | {before:.3f} | {after:.3f} | {after / before:.2f} |")
    if "start-up none" in rows:
        print(f"| start-up: CPU s per run without any page (--pages none) | | "
              f"{best('start-up none')[1] / runs:.3f} | |")
    for title, (before, after) in sample.items():
        print(f"| {title} | {before:.1f} | {after:.1f} | {after / before:.2f} |")
    print()
    print(f"simulated per run (mean): {simulated / runs:.0f} s; best of {args.rounds} rounds "
          f"by CPU time; load average before each round: "
          + ", ".join(f"{load:.2f}" for load in loads))
    return 0


def headline(args: argparse.Namespace, root: Path) -> dict[str, tuple[float, float]]:
    """--sample N whole runs of the medium preset on 2 workers, before and after; the
    1,000-run figures extrapolated from them."""
    repeat = 2
    count = max(1, args.sample // repeat)
    with redirect_stdout(io.StringIO()):
        status = rei_gen(["rooms", "-o", str(root / "sample-suite"), "--count", str(count),
                          "--preset", "medium", "--seed", str(args.seed + 1)])
    if status != 0:
        raise SystemExit(status)
    plan = plan_campaign([root / "sample-suite" / "index.csv"], repeat=repeat, seed=args.seed)
    runs = len(plan.runs)
    found: dict[str, list[float]] = {}
    for on in (False, True):
        load = os.getloadavg()[0]
        wall, cpu = measured(plan, root / f"sample-{'after' if on else 'before'}",
                             args.compare, on)
        print(f"  sample of {runs} medium runs, {args.compare} {'on' if on else 'off'} (load "
              f"average before: {load:.2f}): {wall:.1f} s wall, {cpu:.1f} CPU s", flush=True)
        found.setdefault("wall", []).append(wall)
        found.setdefault("cpu", []).append(cpu)
    (wall_before, wall_after), (cpu_before, cpu_after) = found["wall"], found["cpu"]
    scale = 1000 / runs
    return {
        f"sample of {runs} medium runs: wall s (2 workers)": (wall_before, wall_after),
        f"sample of {runs} medium runs: runs per CPU minute":
            (runs / cpu_before * 60, runs / cpu_after * 60),
        "1,000 medium runs, extrapolated from the sample's wall: min":
            (wall_before * scale / 60, wall_after * scale / 60),
        "1,000 medium runs on two free cores (CPU s / 2), extrapolated: min":
            (cpu_before * scale / 2 / 60, cpu_after * scale / 2 / 60),
    }


def alone(args: argparse.Namespace, root: Path) -> int:
    """`rei run` alone, before and after (--compare), CPU s of its process tree."""
    mission = Path(__file__).resolve().parents[1] / "examples" / "navigation" / \
        "navigation.mission"
    found: dict[bool, list[float]] = {False: [], True: []}
    load = os.getloadavg()[0]
    for i in range(args.alone):
        for on in (False, True):
            with setting(args.compare, on):
                cpu = children_cpu()
                subprocess.run([sys.executable, "-m", "rei.runtime.commands", "run", str(mission),
                                "-o", str(root / f"alone-{on}-{i}"), "--duration", "0.01",
                                "--page", pages(args.compare, on), "-q"], check=False,
                               stdout=subprocess.DEVNULL)
                found[on].append(children_cpu() - cpu)
    name, off = SETTINGS[args.compare]
    before, after = (statistics.median(found[on]) for on in (False, True))
    print(f"`rei run` alone (navigation, 0.01 simulated s), median of {args.alone}; load "
          f"average {load:.2f} before, {os.getloadavg()[0]:.2f} after")
    print(f"| measure | before ({name}={off}) | after ({args.compare} on) | after / before |")
    print("|---|---:|---:|---:|")
    print(f"| `rei run` alone: CPU s | {before:.3f} | {after:.3f} | {after / before:.2f} |")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=8, help="medium rooms (default 8)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per mission (default 2)")
    parser.add_argument("--duration", type=float, default=None,
                        help="cap on simulated seconds per run (default: whole missions)")
    parser.add_argument("--rounds", type=int, default=2, help="measurements per setting")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--figures", action="store_true",
                        help="runs per CPU minute, start-up per run and `rei demo` wall time, "
                             "before and after (--compare)")
    parser.add_argument("--compare", choices=sorted(SETTINGS), default="warm",
                        help="with --figures: the feature turned off before and on after: "
                             "warm workers (default), the cache or the pages of passing runs")
    parser.add_argument("--sample", type=int, default=0, metavar="N",
                        help="with --figures: also N whole medium runs before and after, "
                             "and 1,000 runs extrapolated (default 0: not measured)")
    parser.add_argument("--alone", type=int, default=0, metavar="N",
                        help="only `rei run` alone, N times before and after (--compare)")
    parser.add_argument("--startup-duration", type=float, default=0.1, metavar="S",
                        help="with --figures: simulated seconds of the start-up runs")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="rei-bench-campaign-") as tmp:
        root = Path(tmp)
        if args.alone > 0:
            return alone(args, root)
        with redirect_stdout(io.StringIO()):
            status = rei_gen(["rooms", "-o", str(root / "suite"), "--count", str(args.count),
                              "--preset", "medium", "--seed", str(args.seed)])
        if status != 0:
            return status
        if args.figures:
            return figures(args, root)
        plan = plan_campaign([root / "suite" / "index.csv"], repeat=args.repeat,
                             seed=args.seed, duration=args.duration)
        runs = len(plan.runs)
        length = "whole missions" if args.duration is None else f"{args.duration:g} simulated s"
        print(f"medium preset: {args.count} rooms x {args.repeat} repeats = {runs} runs "
              f"({length}); {os.cpu_count()} CPUs; {args.rounds} rounds")

        # Settings alternate within each round so that load from other processes on a shared
        # machine hits them alike; ratios are taken per round, then the median is reported.
        times: dict[str, list[float]] = {"local-1": [], "local-2": [], "dask-2": []}
        startups: list[float] = []
        ceilings: list[float] = []
        for i in range(args.rounds):
            load = os.getloadavg()[0]
            ceilings.append(machine_scaling())
            times["local-1"].append(timed(plan, LocalEngine(1), root / f"local-1-{i}"))
            times["local-2"].append(timed(plan, LocalEngine(2), root / f"local-2-{i}"))
            start = time.perf_counter()
            # Each Dask thread only waits on its run's process: one worker process with a
            # thread per core (no nanny) leaves the most CPU to the runs.
            with loopback_cluster(workers=1, threads=2, nanny=False) as address:
                startups.append(time.perf_counter() - start)
                times["dask-2"].append(timed(plan, DaskEngine(address), root / f"dask-2-{i}"))
            print(f"  round {i + 1}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in times.items())
                  + f"  (load average before: {load:.2f}; machine ceiling "
                  f"{100 * ceilings[-1]:.0f} %)", flush=True)
        efficiency = statistics.median(a / (2 * b) for a, b in zip(times["local-1"],
                                                                   times["local-2"], strict=True))
        overhead = statistics.median(d / b - 1 for d, b in zip(times["dask-2"], times["local-2"],
                                                               strict=True))
        best = {k: min(v) for k, v in times.items()}
        print()
        print("| setting | best wall time [s] | missions/min |")
        print("|---|---|---|")
        for name, label in (("local-1", "local, 1 worker"), ("local-2", "local, 2 workers"),
                            ("dask-2", "Dask, 1 worker x 2 threads")):
            print(f"| {label} | {best[name]:.2f} | {runs / best[name] * 60:.1f} |")
        print()
        print(f"scaling efficiency 1 -> 2 workers (median of rounds): {100 * efficiency:.1f} % "
              f"(target >= 90 %)")
        print(f"machine ceiling (two CPU-bound processes vs one, median of rounds): "
              f"{100 * statistics.median(ceilings):.1f} %; campaign efficiency relative to it: "
              f"{100 * efficiency / statistics.median(ceilings):.1f} %")
        print(f"Dask engine overhead vs local, 2 workers (median of rounds): "
              f"{100 * overhead:+.1f} % (target < 10 %)")
        print(f"Dask cluster start-up (scheduler + 1 worker, not in the above): "
              f"{statistics.median(startups):.1f} s")
        print(f"single-run wall time, median over the first 1-worker campaign: "
              f"{statistics.median(runs_wall(root / 'local-1-0')):.2f} s")
    return 0


def runs_wall(folder: Path) -> list[float]:
    from rei.runtime.campaigns import CampaignStore  # noqa: PLC0415

    return [r.wall_time for r in CampaignStore.read(folder)[2]]


if __name__ == "__main__":
    sys.exit(main())
