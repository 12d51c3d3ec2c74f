"""Benchmark of the stressor rooms: does the encounter happen, and who passes?

Generates the `stress` preset's systematic design (``rei-gen rooms --preset stress
--strategy systematic``; its rows cycle through emerge, crossing, gap, oncoming) and runs
every mission as `rei run` does (monitor on, the default .vepl) with each controller and
seed given. Per stressor and controller it reports the runs that pass, the tasks that
succeed, the runs with a collision, and the closest approach (centre to centre) of the
stressor's person or cart to the robot: median and worst over the runs. Never asserted by
tests; keep runs small on a shared machine (``--jobs 1``).

Usage: python bench/stressors.py [--rooms N] [--seeds 0,1] [--controller NAME ...]
       [--stressor emerge,gap] [--jobs N] [--out DIR]
A controller may be ``module:Class``; the checkout is on PYTHONPATH, so the test suite's
``tests.rooms.no_inflation:NoInflationPlanner`` (a point planner with no inflation) works.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)


@dataclass(frozen=True)
class Outcome:
    stressor: str
    controller: str
    mission: str
    seed: int
    passed: bool
    tasks: int
    succeeded: int
    collisions: int
    closest: float
    """m, centre to centre, from the stressor's mover to the robot (inf for the gap)."""
    failed: tuple[str, ...]
    """The requirements that failed."""


def closest_approach(trace: Path, name: str | None) -> float:
    if name is None:
        return math.inf
    lines = trace.read_text().splitlines()
    names = [o["name"] for o in json.loads(lines[0])["objects"]]
    if name not in names:
        return math.inf
    k = names.index(name)
    best = math.inf
    for line in lines[1:]:
        sample = json.loads(line)
        for pose in sample.get("poses", ()):
            if pose[0] == k:
                best = min(best, math.dist(sample["robot_pose"][:2], pose[1:3]))
    return best


def run_one(job: tuple[str, str, Path, int, Path, str | None]) -> Outcome:
    from rei.runtime.runs.session import run_into

    stressor, controller, mission, seed, out, mover = job
    summary, _ = run_into(mission, out, controller, seed, watchdog=None)
    data = summary.to_json()
    m = summary.measurements
    return Outcome(stressor, controller, mission.stem, seed, data["verdict"] == "pass",
                   len(m["tasks"]), int(m["tasks_succeeded"]), int(m["collisions"]),
                   closest_approach(out / "trace.jsonl", mover),
                   tuple(v.requirement for v in summary.verdicts if v.status == "fail"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rooms", type=int, default=8, help="rooms (default 8: 2 each)")
    parser.add_argument("--seeds", default="0", help="run seeds, comma-separated (default 0)")
    parser.add_argument("--suite-seed", type=int, default=0, help="the suite's seed")
    parser.add_argument("--controller", action="append", default=None,
                        help="controller (repeatable; default reference)")
    parser.add_argument("--stressor", default=None,
                        help="only these stressors, comma-separated (default: the preset's)")
    parser.add_argument("--jobs", type=int, default=1, help="runs at once (default 1)")
    parser.add_argument("--out", type=Path, default=None, help="keep outputs here")
    args = parser.parse_args()
    controllers = args.controller or ["reference"]
    seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.out or Path(tmp)
        suite = folder / "suite"
        subprocess.run([str(Path(sys.executable).parent / "rei-gen"), "rooms", "-o", str(suite),
                        "--preset", "stress", "--strategy", "systematic", "--count",
                        str(args.rooms), "--seed", str(args.suite_seed), "--quiet",
                        *(["--stressor", args.stressor] if args.stressor else [])],
                       check=True, stdout=subprocess.DEVNULL)
        jobs = []
        for mission in sorted(suite.glob("*.mission")):
            room = mission.with_suffix(".room").read_text()
            meta = dict(item.split("=", 1) for line in room.splitlines()
                        if line.startswith("// stressor:") for item in line[12:].split())
            for controller in controllers:
                tag = controller.replace(":", "_").replace(".", "_")
                for seed in seeds:
                    jobs.append((meta["kind"], controller, mission, seed,
                                 folder / "runs" / tag / f"{mission.stem}_s{seed}",
                                 meta.get("mover")))
        with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
            outcomes = list(pool.map(run_one, jobs))
    print("| controller | stressor | runs | runs passed | tasks succeeded | runs with a "
          "collision | closest approach, median (worst) |")
    print("|---|---|---|---|---|---|---|")
    for controller in controllers:
        for stressor in ("emerge", "crossing", "gap", "oncoming"):
            rows = [o for o in outcomes if o.controller == controller and o.stressor == stressor]
            if not rows:
                continue
            near = [o.closest for o in rows if math.isfinite(o.closest)]
            approach = (f"{statistics.median(near):.2f} m ({max(near):.2f} m)" if near
                        else "—")
            print(f"| {controller} | {stressor} | {len(rows)} | "
                  f"{sum(o.passed for o in rows)} | {sum(o.succeeded for o in rows)}/"
                  f"{sum(o.tasks for o in rows)} | {sum(o.collisions > 0 for o in rows)} | "
                  f"{approach} |")
    failed: Counter[tuple[str, str, str]] = Counter(
        (o.controller, o.stressor, r) for o in outcomes for r in o.failed)
    if failed:
        print("\nFailed requirements:")
        for (c, s, r), n in sorted(failed.items()):
            print(f"  {c} {s}: {n} x {r}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
