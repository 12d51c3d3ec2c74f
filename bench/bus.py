"""Benchmark of the bus (issue 23): throughput and latency through the router on loopback,
and the mission's real-time factor per CPU second with the robot and the monitor in their
own processes over Zenoh, against the run in one process.

* throughput: a simulation session publishes N messages, a viewer session receives them
  all (reliable, blocking congestion control): 1 KB raw payloads, odometry messages and
  360-beam scans, messages/s from the first put to the last delivery;
* latency: the round trip of a request/answer (the robot contract's carrier: a query
  answered by another session), median and 99th percentile over N calls;
* real-time factor: every example mission (or --missions), run to its end with the
  reference navigator and the default specification: in process (`run_into` and the run
  page, as `rei run`: the simulation, its monitor, the navigator in its hosted process) and
  distributed (`rei bus`, `rei robot --once` and `rei monitor` — which writes the run page
  — as processes, the simulation via `run_into` with ``bus`` and without a monitor of its
  own). CPU seconds of every process are counted (this one's, and the children's
  when reaped: router, robot, monitor, hosted navigator); "run" subtracts the start-up CPU
  of the distributed processes (measured by starting and stopping them without a run);
  events.csv is checked byte-identical between the two.

Usage: python bench/bus.py [--messages N] [--missions GLOB]
Nothing here is asserted by tests; figures go to bench/RESULTS.md by hand.
"""

from __future__ import annotations

import argparse
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rei.lang.errors import ReiError
from rei.runtime.bus import BusError, connect
from rei.runtime.bus.router import free_port, start
from rei.runtime.bus.schema import TRACE, encode_message
from rei.runtime.commands.run import write_page
from rei.runtime.messages import LaserScan, OdometryReading, ScanReading
from rei.runtime.runs.session import run_into

REPO = Path(__file__).resolve().parent.parent


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def throughput(folder: Path, n: int) -> None:
    with start(folder / "bus") as router:
        sim = connect(router.bus.endpoint, role="simulation", credentials=router.bus.path)
        viewer = connect(router.bus.endpoint, role="viewer", credentials=router.bus.path)
        scan = LaserScan(-np.pi, 2 * np.pi / 360, 0.12, 3.5, np.linspace(0.2, 3.5, 360))
        kinds: list[tuple[str, int, str, Callable[[int], bytes]]] = [
            # raw payloads on the trace's key (the schema's one raw key the simulation has)
            ("1 KB payload", n, TRACE, lambda i: b"x" * 1024),
            ("odometry message", n, "rei/v1/sensor/odometry", lambda i: encode_message(
                OdometryReading(i, i * 0.1, (1.0, 2.0, 0.3), (0.2, 0.1)))),
            ("360-beam scan", n // 10, "rei/v1/sensor/laser",
             lambda i: encode_message(ScanReading(i, i * 0.2, scan))),
        ]
        print("| messages | count | messages/s | MB/s |")
        print("|---|---|---|---|")
        for name, count, key, payload in kinds:
            done = threading.Event()
            got = [0]

            def on(key: str, data: bytes, count: int = count, got: list[int] = got,
                   done: threading.Event = done) -> None:
                got[0] += 1
                if got[0] == count:
                    done.set()

            sub = viewer.subscribe_raw(key, on)
            assert sim.await_readers(key, 30)
            wires = [payload(i) for i in range(count)]
            began = time.perf_counter()
            for wire in wires:
                sim.put(key, wire)
            assert done.wait(300), f"{got[0]} of {count} delivered"
            took = time.perf_counter() - began
            size = sum(len(w) for w in wires)
            print(f"| {name} | {count} | {count / took:,.0f} | {size / took / 1e6:.1f} |",
                  flush=True)
            sub.close()
        # latency: the robot contract's carrier (a query answered by another session)
        robot = connect(router.bus.endpoint, role="robot", credentials=router.bus.path)
        robot.answer_raw("rei/v1/robot/call/step", lambda payload: b'{"ok":[0.1,0.0]}')
        for _ in range(1000):  # until the answerer's declaration reached the router
            try:
                sim.call("rei/v1/robot/call/step", b"{}", 30)
                break
            except BusError:
                time.sleep(0.01)
        times = []
        for _ in range(n // 10):
            began = time.perf_counter()
            sim.call("rei/v1/robot/call/step", b'{"args":[]}', 30)
            times.append(time.perf_counter() - began)
        times.sort()
        print(f"\nquery round trip over {len(times)} calls: median "
              f"{statistics.median(times) * 1e3:.2f} ms, p99 "
              f"{times[int(len(times) * 0.99)] * 1e3:.2f} ms")
        for session in (robot, viewer, sim):
            session.close()


def _rei(*args: str, env: dict[str, str], ready: bool = False) -> subprocess.Popen[bytes]:
    """A `rei` process; with ``ready``, once it said its first line on stderr (it has
    imported what it needs and joined)."""
    process = subprocess.Popen([sys.executable, "-m", "rei.runtime.commands", *args], cwd=REPO,
                               env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE if ready else subprocess.DEVNULL)
    if ready:
        assert process.stderr is not None
        process.stderr.readline()
    return process


def _processes(folder: Path, env: dict[str, str], monitor_out: Path | None,
               ready: bool = False) -> tuple[str, list[subprocess.Popen[bytes]]]:
    port = str(free_port("127.0.0.1"))
    bus = _rei("bus", "--port", port, "--dir", str(folder / "bus"), env=env)
    assert bus.stdout is not None
    endpoint = bus.stdout.readline().decode().split()[1]
    robot = _rei("robot", "--bus", endpoint, "--controller", "reference", "--once", env=env,
                 ready=ready)
    started = [bus, robot]
    if monitor_out is not None:
        started.append(_rei("monitor", "--bus", endpoint, "-o", str(monitor_out),
                            *(() if ready else ("-q",)), env=env, ready=ready))
    return endpoint, started


def _stop(processes: list[subprocess.Popen[bytes]], cpu: dict[int, float] | None = None,
          ending: tuple[int, ...] = ()) -> None:
    """Reap ``processes`` (those at the positions ``ending`` end by themselves, the others
    are terminated first); their CPU seconds into ``cpu`` (by position)."""
    for k in reversed(range(len(processes))):
        process = processes[k]
        if k not in ending:
            process.send_signal(signal.SIGTERM)  # a zombie ignores it; it is still ours
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        if cpu is not None:
            cpu[k] = usage.ru_utime + usage.ru_stime
        for stream in (process.stdout, process.stderr):
            if stream is not None:
                stream.close()


def rtf(folder: Path, missions: list[Path]) -> None:
    env = {**os.environ, "REI_BUS_CREDENTIALS": str(folder / "bus")}
    # start-up CPU of the distributed processes, without a run
    before = _cpu()
    _, started = _processes(folder / "startup", {**env, "REI_BUS_CREDENTIALS":
                                                 str(folder / "startup" / "bus")},
                            folder / "startup" / "mon", ready=True)
    _stop(started)
    startup = _cpu() - before
    print(f"\nstart-up CPU of rei bus + rei robot + rei monitor: {startup:.2f} s\n")
    print("| mission | simulated s | in process: CPU s (all) | x per CPU s | loop: x per "
          "CPU s | distributed: CPU s (all processes) | x per CPU s | without start-up: x "
          "per CPU s | events.csv |")
    print("|---|---|---|---|---|---|---|---|---|")
    parts: list[str] = []
    notes: list[str] = []
    for mission in missions:
        out = folder / mission.stem
        before = _cpu()
        local, local_record = run_into(mission, out / "local")
        write_page(out / "local")  # as `rei run` and `rei monitor` write it
        local_cpu = _cpu() - before
        before = _cpu()
        ended: tuple[int, ...] = ()  # an exception: stop everyone
        endpoint, started = _processes(out, {**env, "REI_BUS_CREDENTIALS":
                                             str(out / "bus")}, out / "monitor")
        try:
            # the simulation only simulates: the monitor and the evaluator run elsewhere —
            # unless a fault of the mission waits for the monitor's signals (then it
            # monitors too)
            own = _cpu()
            try:
                dist, _ = run_into(mission, out / "dist", bus=endpoint, monitor=False,
                                   bus_credentials=out / "bus", wait_monitor=True)
            except ReiError:
                dist, _ = run_into(mission, out / "dist", bus=endpoint,
                                   bus_credentials=out / "bus", wait_monitor=True)
                notes.append(f"{mission.stem}: the simulation monitors too (a fault waits "
                             f"for a signal)")
            own = _cpu() - own
            ended = (1, 2)
        finally:
            each: dict[int, float] = {}
            _stop(started, each, ending=ended)
        dist_cpu = _cpu() - before
        parts.append(f"{mission.stem}: simulation {own:.2f}, router {each.get(0, 0):.2f}, "
                     f"robot {each.get(1, 0):.2f}, monitor {each.get(2, 0):.2f}")
        same = ((out / "local" / "events.csv").read_bytes()
                == (out / "monitor" / "events.csv").read_bytes()
                and (out / "local" / "trace.jsonl").read_bytes()
                == (out / "dist" / "trace.jsonl").read_bytes())
        sim = local.duration
        print(f"| {mission.stem} | {sim:.1f} | {local_cpu:.2f} | {sim / local_cpu:.0f} | "
              f"{sim / local_record.cpu_seconds:.0f} | {dist_cpu:.2f} | {sim / dist_cpu:.0f} | "
              f"{sim / max(dist_cpu - startup, 1e-9):.0f} | "
              f"{'identical' if same else 'DIFFERENT'} |", flush=True)
        assert dist.duration == sim
    print("\nCPU seconds per process, distributed (simulation includes its hosted start-up "
          "work: world and trace):")
    for line in parts + notes:
        print(f"- {line}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--messages", type=int, default=20000)
    parser.add_argument("--missions", default="*", help="glob of example missions' names")
    args = parser.parse_args()
    missions = sorted(p for p in (REPO / "examples").rglob(f"{args.missions}.mission"))
    with tempfile.TemporaryDirectory(prefix="rei-bench-bus-") as tmp:
        throughput(Path(tmp), args.messages)
        rtf(Path(tmp), missions)


if __name__ == "__main__":
    main()
