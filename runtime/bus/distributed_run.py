"""The simulation's side of a distributed run (`rei run --bus`): its sessions, the robot
it calls, the trace it publishes and the configuration it answers.

``open_run_bus`` joins the bus twice — as the simulation (world, sensors, the trace, the
robot's control calls) and as the mission executor (the only role that may send goals) —
waits for a robot to answer (``BusController.load``) and, when asked, for a reader of the
trace (a monitor) before the run begins: what is published before a subscription reaches
the router is lost to it. ``TracePublisher`` is a sample sink publishing the lines the trace
writer has just written (a monitor elsewhere reads the very bytes of trace.jsonl), with
keyframes so a monitor that missed a line can read on. This module must never import
pybullet.
"""

from __future__ import annotations

import json
import sys
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rei.runtime.bus.client import BusSession, connect
from rei.runtime.bus.errors import BusError
from rei.runtime.bus.remote_robot import BusController, to_json
from rei.runtime.bus.schema import TRACE, config_key, dumps
from rei.runtime.errors import RunError
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.trace import TraceEncoder, TraceWriter

KEYFRAME = 10
"""Before every KEYFRAME-th sample (seq 0, 10, 20, ...) the bus carries a keyframe: every
object's pose and twist at that sample. The sample lines themselves are trace.jsonl's,
whose rows are only the changed ones; a reader that missed a line reads on from the next
keyframe."""


def keyframe(sample: Sample) -> bytes:
    """The keyframe payload of ``sample``: ``{"keyframe": seq, "poses": [[i, x, y, yaw],
    ...], "twists": [[i, vx, vy, wz], ...]}`` (the trace's row form, every row)."""
    return json.dumps({"keyframe": sample.seq,
                       "poses": [[i, *row] for i, row in enumerate(sample.poses.tolist())],
                       "twists": [[i, *row] for i, row in enumerate(sample.twists.tolist())]},
                      separators=(",", ":"), allow_nan=False).encode("utf-8")


class TracePublisher:
    """A ``SampleSink`` publishing the run's trace on ``rei/v1/trace``: the header, each
    sample's line and the end line — those the trace ``writer`` has just written, byte for
    byte trace.jsonl's, when the sink comes right after it; else encoded here by the
    trace's own encoder (``encoder``) — a keyframe before every ``KEYFRAME``-th sample and
    the sample count before the end line; after the end line, ``done`` (the run has
    nothing more to say on the bus). It answers the header line as the configuration
    ``trace`` for a monitor that joins late."""

    def __init__(self, session: BusSession, writer: TraceWriter | None = None,
                 done: Callable[[], None] = lambda: None) -> None:
        self.session, self.writer, self.done = session, writer, done
        self.encoder = TraceEncoder(TRACE) if writer is None else None
        """Without a writer: the encoder of the lines (a sample published to nobody may be
        passed through it to keep the lines' changed rows right)."""
        self.samples = 0
        self._header = b""

    def _publish(self, payload: bytes) -> None:
        self.session.put(TRACE, payload)

    def _written(self) -> str:
        assert self.writer is not None
        return self.writer.line

    def start(self, header: StreamHeader) -> None:
        line = self._written() if self.encoder is None else self.encoder.header(header)
        self._header = line.encode("utf-8")
        self.session.answer_raw(config_key("trace"), lambda _request: self._header)
        self._publish(self._header)

    def feed(self, sample: Sample) -> None:
        if sample.seq % KEYFRAME == 0:
            self._publish(keyframe(sample))
        line = self._written() if self.encoder is None else self.encoder.sample(sample)
        self._publish(line.encode("utf-8"))
        self.samples += 1

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        try:
            # how many samples there were: a monitor that missed the last ones knows it
            count = self.samples if self.encoder is None else self.encoder.line - 1
            self._publish(json.dumps({"samples": count}).encode("utf-8"))
            line = self._written() if self.encoder is None \
                else self.encoder.end(end_time, outcome, reason)
            self._publish(line.encode("utf-8"))
        finally:
            self.done()


class RunController(BusController):
    """The robot on the bus, owning the run's two sessions. Closing it tells the robot the
    run is over (the loop closes it before the outputs are finished); the sessions stay
    until the trace's end line is published (``leave``), or the controller is collected."""

    def __init__(self, simulation: BusSession, mission: BusSession,
                 timeout: float | None) -> None:
        super().__init__(simulation, mission, timeout)
        self._left = weakref.finalize(self, _leave, simulation, mission)

    def publisher(self, writer: TraceWriter) -> TracePublisher:
        """The sink publishing the run's trace (placed right after ``writer``)."""
        return TracePublisher(self._sessions["simulation"], writer, done=self.leave)

    def leave(self) -> None:
        if self._left.alive and self.retries:
            _say(f"bus: {self.retries} call(s) to the robot sent again while nobody could "
                 f"answer (the router or the robot away), each answered once")
        self._left()


def _leave(*sessions: BusSession) -> None:
    for session in sessions:
        session.close()


def open_run_bus(endpoint: str, credentials: Path | None, watchdog: float | None,
                 wait: float, wait_monitor: bool, world_dir: Path) -> RunController:
    """Join, find the robot (and the monitor), answer configuration; RunError (exit 2) for
    a bus that cannot be joined or a robot that does not answer within ``wait`` seconds."""
    try:
        simulation = connect(endpoint, role="simulation", credentials=credentials)
    except BusError as exc:
        raise RunError(f"--bus: {exc}") from None
    try:
        mission = connect(endpoint, role="mission", credentials=credentials)
    except BusError as exc:
        simulation.close()
        raise RunError(f"--bus: {exc}") from None
    controller = RunController(simulation, mission, watchdog)
    try:
        world: dict[str, Any] = json.loads((world_dir / "world.json").read_text("utf-8"))
        simulation.answer("world", lambda: world)

        def robot_context(_request: bytes) -> bytes:
            if controller.context is None:
                raise BusError("the run has not reset the robot yet")
            return dumps(to_json(controller.context))

        simulation.answer_raw(config_key("robot"), robot_context)
        name = controller.load(wait)
        _say(f"bus {simulation.endpoint}: robot '{name}' answered")
        if wait_monitor:
            if not simulation.await_readers(TRACE, wait):
                raise RunError(f"--wait-for-monitor: no monitor subscribed to {TRACE} within "
                               f"{wait:g} s: start `rei monitor --bus {simulation.endpoint} "
                               f"-o DIR`")
            _say(f"bus {simulation.endpoint}: a monitor reads the trace")
    except BaseException:
        controller.close()
        controller.leave()
        raise
    return controller


def _say(line: str) -> None:
    print(f"rei run: {line}", file=sys.stderr, flush=True)
