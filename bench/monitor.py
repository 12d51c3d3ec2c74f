"""Benchmark of the monitor: samples per second through the default .vepl automata.

For 10, 30 (the recording benchmark's stream), 200 and 2,000 observed objects, a robot
drives a zig-zag among boxes, walls and humans (transitions happen, most samples change
nothing). Measured in the same run:

* live: Sample objects fed to ``MonitorSink`` (generated automata, default.vepl);
* replay: the same stream read back from a trace file and fed the same way
  (``rei replay`` without the CLI);
* hand-written: a plain-Python monitor of the same patterns (FAR/CLOSE/COLLISION on the
  minimum footprint distance, laser close/collision on the laser clearance, mission signals,
  utilities) using the same vectorised geometry; the baseline the generated automata are
  compared with.

Every other sample carries a new 360-beam scan from a laser mounted off-centre, as a real
run's 5 Hz laser does at 10 Hz sampling, so the laser clearance is computed as in a run.

Rates are samples per CPU second of this process (time.process_time), so other load on
the machine does not distort them.

Usage: python bench/monitor.py [--samples N] [--objects N [N ...]] [--out DIR]
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from rei.catalogue import Box, Cylinder
from rei.lang.vepl import load_vepl
from rei.runtime.messages import (
    SCHEMA_VERSION,
    LaserScan,
    MissionEvent,
    NavState,
    ObservedObject,
    RobotBelief,
    Sample,
    StreamHeader,
)
from rei.runtime.observation.model.geometry import FootprintSet
from rei.runtime.observation.model.laser_clearance import BeamEdges, clearance
from rei.runtime.observation.monitor import MonitorSink, generate_automata
from rei.runtime.trace import read_trace, write

ROBOT = ObservedObject("robot", "static", "turtlebot3_waffle", Box(0.281, 0.306), 0.2)
MOUNT = (-0.064, 0.0)
BEAMS, MAX_RANGE = 360, 3.5
UTILITY = {"SIG_MISSION_BEGIN": 20, "SIG_MISSION_END": 20, "SIG_MISSION_TASK_START": 5,
           "SIG_MISSION_TASK_FAIL": -100, "SIG_MISSION_TASK_SUCCESS": 10,
           "SIG_GEOM_FAR_TRANSIT_CLOSE": -2, "SIG_GEOM_CLOSE_TRANSIT_FAR": 1,
           "SIG_GEOM_CLOSE_TRANSIT_COLLISION": -10, "SIG_GEOM_COLLISION_TRANSIT_CLOSE": 1,
           "SIG_LASER_CLOSE_TRANSIT_COLLISION": -5, "SIG_LASER_COLLISION_TRANSIT_CLOSE": 1}


def scenario(n_objects: int, n_samples: int, seed: int = 0) -> tuple[StreamHeader, list[Sample]]:
    rng = np.random.default_rng(seed)
    side = max(4, int(math.ceil(math.sqrt(n_objects))) * 2)
    objects = []
    poses = np.zeros((n_objects, 3))
    for i in range(n_objects):
        kind = ("wall", "static", "human")[i % 3]
        fp = Cylinder(0.25) if kind == "human" else Box(1.0, 1.0) if kind == "wall" else \
            Box(0.6, 0.4)
        objects.append(ObservedObject(f"o{i}", kind, kind, fp, 1.0))  # type: ignore[arg-type]
        poses[i] = (rng.uniform(0, side), rng.uniform(0, side), rng.uniform(-math.pi, math.pi))
    # a floor tile under every metre of the area, as a generated room has
    floors = tuple((f"f_{i}_{j}", float(i), float(j)) for i in range(side) for j in range(side))
    header = StreamHeader(SCHEMA_VERSION, "bench", "bench", seed, 10.0, ROBOT, tuple(objects),
                          1.0, floors, MOUNT)
    samples = []
    laser_min = MAX_RANGE
    for k in range(n_samples):
        t = k / 10.0
        x = (0.05 * k) % side
        y = side / 2 + (side / 4) * math.sin(0.01 * k)
        events: tuple[MissionEvent, ...] = ()
        if k == 0:
            events = (MissionEvent("begin", t), MissionEvent("task_start", t, "g", 0))
        elif k == n_samples - 1:
            events = (MissionEvent("task_success", t, "g", 0), MissionEvent("end", t))
        scan = None
        if k % 2 == 0:
            # a few beams towards the nearest object see it; the others see nothing
            d = poses[:, :2] - (x + MOUNT[0], y + MOUNT[1])
            near = int(np.argmin(np.hypot(d[:, 0], d[:, 1])))
            reach = float(max(0.12, math.hypot(*d[near]) - 0.4))
            ranges = np.full(BEAMS, MAX_RANGE)
            beam = int(round((math.atan2(d[near, 1], d[near, 0]) + math.pi) * BEAMS
                             / (2 * math.pi))) % BEAMS
            ranges[np.arange(beam - 2, beam + 3) % BEAMS] = min(reach, MAX_RANGE)
            scan = LaserScan(-math.pi, 2 * math.pi / BEAMS, 0.12, MAX_RANGE, ranges)
            laser_min = float(ranges.min())
        belief = RobotBelief((x, y, 0.0), (0.5, 0.0), laser_min, scan, NavState.ACTIVE, "g")
        samples.append(Sample(k, t, (x, y, 0.0), (0.5, 0.0, 0.0), poses, np.zeros_like(poses),
                              belief, events))
    return header, samples


class HandWrittenMonitor:
    """The same patterns without the DSL: what one would write by hand."""

    def __init__(self, header: StreamHeader, eps_close: float, eps_collision: float) -> None:
        self.fs = FootprintSet.build(header.robot.footprint,
                                     [o.footprint for o in header.objects], header.tile_size)
        self.edges = BeamEdges(header.robot.footprint, header.laser_mount)
        self.clearance = 1e3
        self.close, self.collision = eps_close, eps_collision
        self.geom = "FAR"
        self.laser = "FAR"
        self.signals: list[tuple[float, str, float]] = []
        self.total = 0.0

    def _state(self, d: float) -> str:
        return "COLLISION" if d < self.collision else "CLOSE" if d < self.close else "FAR"

    def _raise(self, t: float, name: str) -> None:
        self.total += UTILITY[name]
        self.signals.append((t, name, self.total))

    def feed(self, s: Sample) -> None:
        d = self.fs.distances(s.robot_pose, s.poses, self.close)
        new = self._state(float(d.min()) if len(d) else math.inf)
        order = ["FAR", "CLOSE", "COLLISION"]
        while new != self.geom:
            step = order[order.index(self.geom) + (1 if order.index(new) > order.index(self.geom)
                                                   else -1)]
            self._raise(s.time, f"SIG_GEOM_{self.geom}_TRANSIT_{step}")
            self.geom = step
        if s.belief.scan is not None:
            self.clearance = clearance(s.belief.scan, self.edges.of(s.belief.scan))
        laser = self._state(self.clearance)
        if laser != self.laser:
            if laser == "COLLISION":
                self._raise(s.time, "SIG_LASER_CLOSE_TRANSIT_COLLISION")
            elif self.laser == "COLLISION":
                self._raise(s.time, "SIG_LASER_COLLISION_TRANSIT_CLOSE")
            self.laser = laser
        for e in s.events:
            self._raise(s.time, {"begin": "SIG_MISSION_BEGIN", "end": "SIG_MISSION_END",
                                 "task_start": "SIG_MISSION_TASK_START",
                                 "task_success": "SIG_MISSION_TASK_SUCCESS",
                                 "task_fail": "SIG_MISSION_TASK_FAIL"}[e.kind])


def rate(n: int, seconds: float) -> float:
    return n / seconds if seconds > 0 else math.inf


def bench(n_objects: int, n_samples: int, work: Path) -> dict[str, float]:
    header, samples = scenario(n_objects, n_samples)
    automata = generate_automata(None, work / "automata")
    trace = work / f"trace_{n_objects}.jsonl"
    write(trace, header, samples, samples[-1].time)

    start = time.process_time()
    sink = MonitorSink(None, work / f"live_{n_objects}", automata=automata)
    sink.start(header)
    for s in samples:
        sink.feed(s)
    sink.finish(samples[-1].time, "completed", "")
    live = time.process_time() - start

    start = time.process_time()
    sink2 = MonitorSink(None, work / f"replay_{n_objects}", automata=automata)
    h2, stream = read_trace(trace)
    sink2.start(h2)
    for s in stream:
        sink2.feed(s)
    sink2.finish(samples[-1].time, "completed", "")
    replay = time.process_time() - start

    start = time.process_time()
    parameters = load_vepl().parameters
    hand = HandWrittenMonitor(header, parameters["eps_close"], parameters["eps_collision"])
    for s in samples:
        hand.feed(s)
    handwritten = time.process_time() - start
    assert sink.result is not None
    geom_auto = sum(v for k, v in sink.result.signal_counts.items() if k.startswith("SIG_GEOM"))
    geom_hand = sum(1 for _, k, _ in hand.signals if k.startswith("SIG_GEOM"))
    laser_auto = sum(v for k, v in sink.result.signal_counts.items() if k.startswith("SIG_LASER"))
    laser_hand = sum(1 for _, k, _ in hand.signals if k.startswith("SIG_LASER"))
    return {"objects": n_objects, "samples": n_samples, "live": rate(n_samples, live),
            "replay": rate(n_samples, replay), "hand": rate(n_samples, handwritten),
            "ratio": live / handwritten if handwritten > 0 else math.inf,
            "geom_signals": geom_auto, "geom_signals_hand": geom_hand,
            "laser_signals": laser_auto, "laser_signals_hand": laser_hand}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=3000)
    parser.add_argument("--objects", type=int, nargs="+", default=[10, 30, 200, 2000],
                        help="observed object counts to measure (default: 10 30 200 2000)")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = args.out or Path(tmp)
        print("| objects | samples | live samples/s | live µs/sample | replay samples/s "
              "| hand-written samples/s | live / hand time | geometric signals (automata / hand) "
              "| laser signals (automata / hand) |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for n in args.objects:
            r = bench(n, args.samples, work)
            print(f"| {n:,} | {r['samples']:,} | {r['live']:,.0f} | {1e6 / r['live']:.0f} | "
                  f"{r['replay']:,.0f} | "
                  f"{r['hand']:,.0f} | {r['ratio']:.2f} | {r['geom_signals']} / "
                  f"{r['geom_signals_hand']} | {r['laser_signals']} / "
                  f"{r['laser_signals_hand']} |")


if __name__ == "__main__":
    main()
