"""Benchmark of the `reference` navigator: success rate, collisions and real-time factor.

Runs a fixed suite with each controller given (default: `reference`, and `teleop` as the
baseline cost of a run whose controller does almost nothing):

* small: 20 generated small rooms (``rei-gen rooms --preset small --count 20 --seed 1``);
* medium: 10 generated medium rooms (``--preset medium --count 10 --seed 2``);
* examples: the four bundled ``examples/*/*.mission``.

Each mission is run as ``rei run`` runs it (``run_into``, monitor off: the monitor's cost is
measured by bench/monitor.py), seed 0. Success rate = tasks succeeded / tasks. Collisions are
the run's collision count (contacts begun) summed over the suite, and the number of missions
with any. Real-time factor = simulated seconds / CPU seconds of the runs (so other load on
the machine does not distort it; wall-clock factors are printed too); never asserted by tests.
A controller may also be ``module:Class`` (e.g. a saved copy of an earlier navigator, with its
folder on PYTHONPATH), which is how the before/after figures in bench/RESULTS.md were taken.

Usage: python bench/navigator.py [--controller NAME ...] [--suite small|medium|examples ...]
       [--jobs N] [--out DIR]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SUITES = {
    "small": ("small", 20, 1),
    "medium": ("medium", 10, 2),
}


@dataclass(frozen=True)
class Outcome:
    """What one mission run gave."""

    suite: str
    mission: str
    tasks: int
    succeeded: int
    collisions: int
    simulated: float
    wall: float
    cpu: float
    reasons: tuple[str, ...]


def missions_of(suite: str, folder: Path) -> list[Path]:
    if suite == "examples":
        # Not examples/faults: its faults fire on the monitor's signals, and this benchmark
        # runs with the monitor off to measure the navigator alone (`rei run` refuses such a
        # fault unmonitored: FAULT-SIGNAL).
        return sorted(m for m in REPO.glob("examples/*/*.mission") if m.parent.name != "faults")
    preset, count, seed = SUITES[suite]
    out = folder / suite
    subprocess.run([str(Path(sys.executable).parent / "rei-gen"), "rooms", "-o", str(out),
                    "--preset", preset, "--count", str(count), "--seed", str(seed)],
                   check=True, stdout=subprocess.DEVNULL)
    return sorted(out.glob("*.mission"))


def run_one(job: tuple[str, str, Path, Path]) -> Outcome:
    from rei.runtime.runs.session import run_into

    suite, controller, mission, out = job
    summary, record = run_into(mission, out, controller, 0, watchdog=None, monitor=False)
    m = summary.measurements
    tasks = m["tasks"]
    return Outcome(suite, mission.stem, len(tasks), int(m["tasks_succeeded"]),
                   int(m["collisions"]), record.duration, record.wall_seconds,
                   record.cpu_seconds,
                   tuple(t["reason"] for t in tasks if not t["succeeded"]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--controller", action="append", default=None,
                        help="controller to measure (repeatable; default reference and teleop)")
    parser.add_argument("--suite", action="append", choices=["small", "medium", "examples"],
                        default=None, help="suite to run (repeatable; default all three)")
    parser.add_argument("--jobs", type=int, default=1, help="missions run at once (default 1)")
    parser.add_argument("--out", type=Path, default=None, help="keep run outputs here")
    parser.add_argument("--failures", action="store_true", help="list every failed task")
    args = parser.parse_args()
    controllers = args.controller or ["reference", "teleop"]
    suites = args.suite or ["small", "medium", "examples"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.out or Path(tmp)
        jobs = []
        for suite in suites:
            for mission in missions_of(suite, folder / "missions"):
                for controller in controllers:
                    tag = controller.replace(":", "_").replace(".", "_")
                    jobs.append((suite, controller, mission,
                                 folder / "runs" / tag / suite / mission.stem))
        with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
            outcomes = list(pool.map(run_one, jobs))
    print("| controller | suite | missions | missions completed | tasks | success rate "
          "| collisions (missions with any) | simulated s | real-time factor per CPU s "
          "(wall) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for controller in controllers:
        for suite in suites:
            rows = [o for (_, c, _, _), o in zip(jobs, outcomes, strict=True)
                    if c == controller and o.suite == suite]
            tasks = sum(o.tasks for o in rows)
            ok = sum(o.succeeded for o in rows)
            done = sum(o.succeeded == o.tasks for o in rows)
            coll = sum(o.collisions for o in rows)
            hit = sum(o.collisions > 0 for o in rows)
            sim = sum(o.simulated for o in rows)
            cpu = sum(o.cpu for o in rows)
            wall = sum(o.wall for o in rows)
            rate = 100.0 * ok / tasks if tasks else 0.0
            print(f"| {controller} | {suite} | {len(rows)} | {done} | {tasks} | "
                  f"{ok}/{tasks} = {rate:.1f}% | {coll} ({hit}) | {sim:.0f} | "
                  f"{sim / cpu if cpu else 0:.0f} ({sim / wall if wall else 0:.0f}) |")
    reasons: Counter[tuple[str, str]] = Counter()
    for (_, c, _, _), o in zip(jobs, outcomes, strict=True):
        for r in o.reasons:
            # "outside tolerance: the robot is 0.44 m from the goal ..." counts as one reason.
            reasons[(c, r.split(":")[0] if r.startswith("outside tolerance") else r)] += 1
    if reasons:
        print("\nFailed tasks by reason:")
        for (c, r), n in sorted(reasons.items()):
            print(f"  {c}: {n} x {r}")
    if args.failures:
        for (_, c, _, _), o in zip(jobs, outcomes, strict=True):
            if o.reasons or o.collisions:
                print(f"  {c} {o.suite}/{o.mission}: {o.succeeded}/{o.tasks} tasks, "
                      f"{o.collisions} collision(s) {list(o.reasons)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
