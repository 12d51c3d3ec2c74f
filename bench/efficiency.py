"""What the efficiency requirements and the settle period would see in recorded runs.

Replays every run's trace.jsonl under the given folders (campaign folders, or bench/bugs.py's
output: one folder per navigator) through the monitor's runtime model alone
(rei.runtime.observation.model.runtime_model.RuntimeModel: the same code `rei run` judges with) and
prints, per
navigator, the distribution of each task's path ratio, time ratio and turning in place near
the goal (tasks that succeeded and were long enough to judge), and of the robot's own travel
after its last task. This is how the default .vepl's thresholds (max_path_ratio,
max_time_ratio, max_goal_spin, settle_tolerance) were chosen: the reference navigator must pass
every preset with margin. Runs recorded before the settle period existed end at their last
goal, so their settle travel reads 0.

With --estimates it compares the two shortest-path estimates instead (issue 25): the tile
estimate (a tile under a static object's centre blocked) and the footprint one (walls' and
static objects' footprints inflated by the robot's inradius,
rei.runtime.observation.model.efficiency
``FreeSpace``), re-judging each task from the trace's poses and mission events alone (the
figures of the tile estimate are checked against the run's summary.json), and prints each
estimate's distribution of path and time ratios, the runs whose worst task fails a bound and
the smallest margins.

With --halls it measures the two estimates' CPU cost in bench/simulation.py's halls of 200,
1,000 and 2,000 objects (the same lattice of the same catalogue types, walls round them):
building each, and a short task, one across the hall each way and one among the objects.

Usage: python bench/efficiency.py FOLDER... [--estimates] [--max-path 1.5] [--max-time 3.0]
       python bench/efficiency.py --halls
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

from rei.runtime.observation.model.efficiency import TaskProgress, judge_task  # noqa: E402
from rei.runtime.observation.model.free_space import FloorGraph, FreeSpace  # noqa: E402
from rei.runtime.observation.model.runtime_model import RuntimeModel  # noqa: E402
from rei.runtime.trace import read_trace  # noqa: E402


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


def rejudge(trace: Path) -> tuple[list[tuple[float, float, float, float, float, float]],
                                  tuple[float, float]]:
    """((tile shortest, its path ratio, its time ratio, footprint shortest, its path ratio,
    its time ratio) of every task that succeeded, (CPU s of the tile estimate, of the
    footprint one: construction and every task's distance)) of one run, from its poses and
    mission events: the runtime model's own bookkeeping (a task starts where the sample
    carrying its start puts the robot, and adds each later step)."""
    header, samples = read_trace(trace)
    model = RuntimeModel(header)
    facts = header.mission_facts
    speed = facts.speed_limit if facts is not None else math.inf
    tiles: FloorGraph | None = None
    space: FreeSpace | FloorGraph | None = None
    last: tuple[float, float] | None = None
    task: TaskProgress | None = None
    out: list[tuple[float, float, float, float, float, float]] = []
    cpu = [0.0, 0.0]
    for n, sample in enumerate(samples):
        x, y = float(sample.robot_pose[0]), float(sample.robot_pose[1])
        if n == 0:
            began = time.process_time()
            tiles = model.tile_space(sample)
            between = time.process_time()
            space = model.free_space(sample, tiles) if tiles is not None else None
            cpu[0] += between - began
            cpu[1] += time.process_time() - between
        if task is not None and last is not None:
            task.travelled += math.hypot(x - last[0], y - last[1])
        last = (x, y)
        for e in sample.events:
            if e.kind == "task_start" and facts is not None and e.index is not None:
                task = TaskProgress(last, e.time, facts.goals[e.index % len(facts.goals)])
            elif e.kind in ("task_success", "task_fail"):
                done, task = task, None
                if e.kind == "task_fail" or done is None or done.goal is None:
                    continue
                goal = (done.goal.x, done.goal.y)
                began = time.process_time()
                old = tiles.distance(done.start_xy, goal) if tiles is not None else math.inf
                between = time.process_time()
                new = space.distance(done.start_xy, goal) if space is not None else math.inf
                cpu[0] += between - began
                cpu[1] += time.process_time() - between
                a, b = judge_task(done, e.time, old, speed), judge_task(done, e.time, new, speed)
                out.append((old, a.path_ratio, a.time_ratio, new, b.path_ratio, b.time_ratio))
    return out, (cpu[0], cpu[1])


def estimates(traces: list[tuple[Path, Path]], max_path: float, max_time: float,
              rows_csv: Path | None = None) -> int:
    """Print the two estimates' figures over ``traces`` (see the module's docstring); with
    ``rows_csv``, write every task's figures there too (one row per task)."""
    rows: dict[str, list[tuple[float, float, float, float, float, float]]] = {}
    cpu, mismatched = [0.0, 0.0], 0
    for folder, trace in traces:
        name = str(trace.parent.relative_to(folder)).removeprefix("runs/")
        rows[name], spent = rejudge(trace)
        cpu = [cpu[0] + spent[0], cpu[1] + spent[1]]
        summary = trace.parent / "summary.json"
        if summary.exists():
            # recorded by a monitor of either estimate: its figures must be one's or the other's
            recorded = json.loads(summary.read_text())["measurements"]["efficiency"]
            if len(recorded) != len(rows[name]) or not any(all(
                    math.isclose(r["path_ratio"], t[at + 1], rel_tol=1e-6, abs_tol=1e-9)
                    and math.isclose(r["time_ratio"], t[at + 2], rel_tol=1e-6, abs_tol=1e-9)
                    for r, t in zip(recorded, rows[name], strict=True)) for at in (0, 3)):
                mismatched += 1
                print(f"{name}: neither estimate reproduces summary.json's figures")
    if rows_csv is not None:
        rows_csv.write_text("run,task,tile_shortest,tile_path_ratio,tile_time_ratio,"
                            "footprint_shortest,footprint_path_ratio,footprint_time_ratio\n"
                            + "".join(f"{n},{k}," + ",".join(f"{v:.6g}" for v in t) + "\n"
                                      for n, r in rows.items() for k, t in enumerate(r)))
    print(f"{len(traces)} runs, {sum(map(len, rows.values()))} tasks that succeeded; "
          f"{mismatched} runs whose recorded figures the re-judging does not reproduce; "
          f"CPU s (construction and every task's distance): tile estimate {cpu[0]:.2f}, "
          f"footprint estimate {cpu[1]:.2f} (the tile one's construction apart), ratio "
          f"{cpu[1] / cpu[0] if cpu[0] > 0 else math.inf:.2f}")
    for label, at in (("tile estimate", 0), ("footprint estimate", 3)):
        paths = [t[at + 1] for r in rows.values() for t in r if t[at + 1] > 0]
        times = [t[at + 2] for r in rows.values() for t in r if t[at + 2] > 0]
        worst_path = {n: max((t[at + 1] for t in r), default=0.0) for n, r in rows.items()}
        worst_time = {n: max((t[at + 2] for t in r), default=0.0) for n, r in rows.items()}
        print(f"{label}: {len(paths)} judged tasks\n  path ratio {quantiles(paths)}\n"
              f"  time ratio {quantiles(times)}")
        for what, worst, bound in (("path", worst_path, max_path), ("time", worst_time,
                                                                     max_time)):
            fails = sorted(n for n, v in worst.items() if v > bound)
            top = sorted(worst.items(), key=lambda kv: -kv[1])[:5]
            print(f"  {what} ratio > {bound}: {len(fails)} runs {fails[:10]}; smallest margin "
                  f"{bound - top[0][1] if top else math.inf:.3f}; worst "
                  + ", ".join(f"{n} {v:.2f}" for n, v in top))
    ratios = sorted(t[0] / t[3] for r in rows.values() for t in r
                    if t[4] > 0 and math.isfinite(t[0]) and t[3] > 0)
    if ratios:
        print(f"tile / footprint shortest, judged tasks: {quantiles(ratios)}, "
              f"min {ratios[0]:.3f}")
    return 0


def halls() -> int:
    """Print the estimates' CPU cost in bench/simulation.py's halls (see the docstring)."""
    from bench.simulation import SCALING_HALLS, TYPES
    from rei.catalogue import Tile
    from rei.catalogue.loader import default_catalogue
    from rei.runtime.observation.model.floors import FloorMap
    from rei.runtime.observation.model.free_space import footprint_shapes
    from rei.runtime.observation.model.geometry import FootprintSet

    catalogue = default_catalogue()
    robot = catalogue.types["turtlebot3_waffle"].footprint
    inradius = FootprintSet.build(robot, [], 1.0).robot_inradius()
    print("| hall | vertices | build: tiles / footprints (CPU s) | task | tiles: m, CPU s | "
          "footprints: m, CPU s |\n|---|---:|---|---|---|---|")
    for cols, rows, statics in SCALING_HALLS:
        floors = [(float(c), float(r)) for r in range(1, rows + 1) for c in range(1, cols + 1)]
        walls = [(float(c), float(r)) for r in range(rows + 2) for c in range(cols + 2)
                 if r in (0, rows + 1) or c in (0, cols + 1)]
        lattice = [(float(c), float(r)) for r in range(2, rows + 1, 2)
                   for c in range(2, cols, 2)][:statics]
        began = time.process_time()
        grid = FloorMap(np.array(floors), 1.0)
        blocked = np.zeros(len(floors), dtype=bool)
        blocked[grid.of(np.array(lattice))] = True
        tiles = FloorGraph(grid.grid, grid.origin, 1.0, blocked)
        built_tiles = time.process_time() - began
        began = time.process_time()
        footprints = [Tile()] * len(walls) + [catalogue.types[TYPES[n % len(TYPES)]].footprint
                                              for n in range(len(lattice))]
        poses = np.array([(x, y, 0.0) for x, y in walls + lattice])
        space = FreeSpace(tiles, footprint_shapes(footprints, poses, 1.0, inradius), inradius)
        built_space = time.process_time() - began
        tasks = {"short": ((1.0, 1.0), (1.3, 1.1)), "across": ((1.0, 1.0), (cols, rows)),
                 "back": ((cols - 1.0, rows - 1.0), (1.0, 1.0)),
                 "among objects": ((5.0, 3.0), (9.0, 7.0))}
        for n, (name, (p, q)) in enumerate(tasks.items()):
            began = time.process_time()
            old = tiles.distance(p, q)
            between = time.process_time()
            new = space.distance(p, q)
            done = time.process_time()
            head = (f"| {statics + 8} | {len(space.vertices)} | {built_tiles:.3f} / "
                    f"{built_space:.3f}") if n == 0 else "| | |"
            print(f"{head} | {name} | {old:.2f}, {between - began:.3f} | "
                  f"{new:.2f}, {done - between:.3f} |")
    return 0


def quantiles(values: list[float]) -> str:
    if not values:
        return "—"
    q = np.quantile(values, [0.5, 0.9, 1.0])
    return f"median {q[0]:.2f}, p90 {q[1]:.2f}, max {q[2]:.2f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", nargs="*", type=Path)
    parser.add_argument("--estimates", action="store_true",
                        help="compare the tile and the footprint shortest-path estimates")
    parser.add_argument("--max-path", type=float, default=1.5)
    parser.add_argument("--max-time", type=float, default=3.0)
    parser.add_argument("--csv", type=Path, help="with --estimates: every task's figures")
    parser.add_argument("--halls", action="store_true",
                        help="the estimates' CPU cost in bench/simulation.py's halls")
    args = parser.parse_args()
    if args.halls:
        return halls()
    if not args.folders:
        parser.error("give at least one FOLDER (or --halls)")
    if args.estimates:
        return estimates(sorted((f, t) for f in args.folders for t in f.rglob("trace.jsonl")
                                if "static" not in t.parts), args.max_path, args.max_time,
                         args.csv)
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
