"""What the efficiency requirements and the settle period would see in recorded runs.

Replays every run's trace.jsonl under the given folders (campaign folders, or bench/bugs.py's
output: one folder per navigator) through the monitor's runtime model alone
(rei.runtime.monitor.model.RuntimeModel: the same code `rei run` judges with) and prints, per
navigator, the distribution of each task's path ratio, time ratio and turning in place near
the goal (tasks that succeeded and were long enough to judge), and of the robot's own travel
after its last task. This is how the default .vepl's thresholds (max_path_ratio,
max_time_ratio, max_goal_spin, settle_tolerance) were chosen: the reference navigator must pass
every preset with margin. Runs recorded before the settle period existed end at their last
goal, so their settle travel reads 0.

Usage: python bench/efficiency.py FOLDER... [--by navigator|folder]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from rei.runtime.collector.trace import read_trace  # noqa: E402
from rei.runtime.monitor.model import RuntimeModel  # noqa: E402


def replay(trace: Path) -> tuple[list[tuple[float, float, float]], float]:
    """((path ratio, time ratio, spin) of every judged task, settle travel) of one run."""
    header, samples = read_trace(trace)
    model = RuntimeModel(header)
    w = model.baseline()
    for sample in samples:
        w = model.observe(sample)
        for event in sample.events:
            w = model.apply(event, w)
    tasks = [(e.path_ratio, e.time_ratio, e.spin) for _, e in model.efficiency
             if e.path_ratio > 0]
    return tasks, model.idle_travel


def quantiles(values: list[float]) -> str:
    if not values:
        return "—"
    q = np.quantile(values, [0.5, 0.9, 1.0])
    return f"median {q[0]:.2f}, p90 {q[1]:.2f}, max {q[2]:.2f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    args = parser.parse_args()
    groups: dict[str, list[Path]] = {}
    for folder in args.folders:
        for trace in sorted(folder.rglob("trace.jsonl")):
            if "static" in trace.parts:
                continue
            runs = trace.parent.parent
            name = runs.parent.name if runs.name == "runs" else folder.name
            groups.setdefault(name, []).append(trace)
    for name, traces in groups.items():
        tasks: list[tuple[float, float, float]] = []
        settle: list[float] = []
        for trace in traces:
            judged, travel = replay(trace)
            tasks += judged
            settle.append(travel)
        paths, times, spins = (list(v) for v in zip(*tasks, strict=True)) if tasks \
            else ([], [], [])
        print(f"{name}: {len(traces)} runs, {len(tasks)} judged tasks\n"
              f"  path ratio   {quantiles(paths)}\n  time ratio   {quantiles(times)}\n"
              f"  goal spin    {quantiles(spins)} rad\n  settle travel {quantiles(settle)} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
