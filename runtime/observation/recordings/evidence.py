"""Evidence over claims: a stream's mission events, end record and scans checked against its
own ground truth and its own mission facts, before anything is judged from them.

A recording *claims* things (the controller reported success, the run failed with one task
of two, this scan has 360 beams) and *records evidence* (the robot's ground-truth pose at
every sample, the goals' tolerances and timeouts in the header's mission facts, the times).
``EvidenceAudit`` re-derives what the mission executor would have decided from the evidence
and refuses a stream whose claims contradict it, with a located error
(``path:line: field: expected ..., found ...``): a ``task_success`` where the ground-truth
pose is outside the goal's tolerance or heading tolerance, a task that outlived its timeout
with no ``task_fail``, tasks out of the mission's order, an end record whose outcome
disagrees with the events, a scan whose geometry is not one laser's (an ``angle_increment``
of 0, 3 ranges where the laser has 360). A hand-edited trace can therefore never turn a
FAIL into a PASS by deleting or rewriting mission events or the end line.

The tolerance of each check is what sampling allows and no more: an event happens at a
control tick at or before the sample that carries it, so the robot may have moved by twice
its speed limit times that interval (and turned by twice its turn limit). The header's
mission facts (goals, tolerances, limits) are the reference: a trace whose header was edited
too is judged against the edited goals (`rei replay --mission` judges a recording's ROS
channels against the .mission itself). A stream without mission facts (not made by a
mission run) has only its scans checked. This module must never
import pybullet, and never judges requirements: it only says whether the claims hold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rei.runtime.messages import GoalFacts, LaserScan, MissionEvent, Sample, StreamHeader
from rei.runtime.observation.recordings.errors import RecordingError

FINISHED = ("completed", "failed")
"""End outcomes that claim every task ran to its end."""
_EPS = 1e-9


class EvidenceError(RecordingError):
    """A recording's claims contradict its own evidence (located: file, line or message)."""


@dataclass(frozen=True)
class ScanGeometry:
    """What stays the same in every scan of one laser."""

    angle_min: float
    angle_increment: float
    beams: int
    range_min: float
    range_max: float

    @staticmethod
    def of(scan: LaserScan) -> ScanGeometry:
        return ScanGeometry(scan.angle_min, scan.angle_increment, len(scan.ranges),
                            scan.range_min, scan.range_max)

    def text(self) -> str:
        return (f"angle_min {self.angle_min:.7g}, angle_increment {self.angle_increment:.7g}, "
                f"{self.beams} ranges, range {self.range_min:g}..{self.range_max:g} m")


def laser_geometry_problem(scan: LaserScan) -> str:
    """Why ``scan`` cannot come from a REI laser (beams spread evenly over the field of view,
    starting at ``-fov/2``, catalogue ``LaserSpec``), or ''."""
    inc, low = scan.angle_increment, scan.angle_min
    n = len(scan.ranges)
    if not (math.isfinite(inc) and inc > 0):
        return f"an angle_increment > 0, found {inc!r}"
    if not (math.isfinite(low) and -math.pi - 1e-6 <= low < 0):
        return f"an angle_min in [-pi, 0) (a laser centred on the robot's heading), found {low!r}"
    beams = -2.0 * low / inc
    if n == 0 or abs(beams - n) > 0.5:
        return (f"{round(beams)} ranges (the field of view {math.degrees(-2 * low):.4g} degrees "
                f"in steps of angle_increment {inc:.7g}), found {n}")
    if not (0 <= scan.range_min < scan.range_max):
        return (f"0 <= range_min < range_max, found range_min {scan.range_min!r}, "
                f"range_max {scan.range_max!r}")
    return ""


@dataclass
class _Task:
    index: int
    goal: GoalFacts
    start: float


class EvidenceAudit:
    """Checks one stream's claims sample by sample (``sample``) and at its end (``end``);
    raises ``EvidenceError`` at the first contradiction, located by the ``where`` given."""

    def __init__(self, header: StreamHeader) -> None:
        self.header = header
        self.facts = header.mission_facts
        self.period = 1.0 / header.rate
        self._geometry: ScanGeometry | None = None
        self._task: _Task | None = None
        self._ended = 0
        self._failed = 0
        self._finished_at: float | None = None
        self._abandoned: tuple[str, float] | None = None
        """(cause, time) of a task the mission's early end failed: 'abandoned' or 'cut'."""
        self._last = 0.0
        self._pose = (0.0, 0.0, 0.0)

    # ---- samples --------------------------------------------------------------------------

    def sample(self, s: Sample, where: str) -> None:
        """Check the sample's scan and mission events against its evidence."""
        if s.belief.scan is not None:
            self._scan(s.belief.scan, where)
        if self.facts is not None and "mission_events" in self.header.data:
            for k, event in enumerate(s.events):
                self._event(event, s, f"{where}: events[{k}]")
            self._timeout(s, where)
        self._last = s.time
        self._pose = s.robot_pose

    def _scan(self, scan: LaserScan, where: str) -> None:
        problem = laser_geometry_problem(scan)
        if problem:
            raise EvidenceError(f"{where}: belief.scan: expected the geometry of one laser: "
                                f"{problem}")
        geometry = ScanGeometry.of(scan)
        if self._geometry is None:
            self._geometry = geometry
        elif geometry != self._geometry:
            raise EvidenceError(f"{where}: belief.scan: expected the laser of the earlier "
                                f"scans ({self._geometry.text()}), found {geometry.text()}")

    def _goal(self, index: int) -> GoalFacts:
        assert self.facts is not None
        return self.facts.goals[index % len(self.facts.goals)]

    def _tasks(self) -> int:
        assert self.facts is not None
        return len(self.facts.goals) * self.facts.cycles

    def _event(self, event: MissionEvent, s: Sample, where: str) -> None:
        kind = event.kind
        if kind == "begin":
            return
        if kind == "task_start":
            self._start(event, where)
        elif kind in ("task_success", "task_fail"):
            self._task_end(event, s, where)
        else:  # the mission's end: no task may still run unless the mission was cut
            self._finished_at = event.time

    def _start(self, event: MissionEvent, where: str) -> None:
        if self._task is not None:
            raise EvidenceError(f"{where}: expected task {self._task.goal.name!r} "
                                f"(#{self._task.index}) to end before the next starts, found "
                                f"a task_start of {event.task!r} (#{event.index})")
        index = self._ended
        if index >= self._tasks():
            raise EvidenceError(f"{where}: expected no task after the mission's "
                                f"{self._tasks()} tasks, found a task_start of "
                                f"{event.task!r} (#{event.index})")
        goal = self._goal(index)
        if event.index != index or event.task != goal.name:
            raise EvidenceError(f"{where}: expected the task_start of task {goal.name!r} "
                                f"(#{index}, the mission's order), found {event.task!r} "
                                f"(#{event.index})")
        self._task = _Task(index, goal, event.time)

    def _task_end(self, event: MissionEvent, s: Sample, where: str) -> None:
        task = self._task
        if task is None or event.index != task.index or event.task != task.goal.name:
            running = "none" if task is None else f"{task.goal.name!r} (#{task.index})"
            raise EvidenceError(f"{where}: expected the end of the running task ({running}), "
                                f"found a {event.kind} of {event.task!r} (#{event.index})")
        if event.kind == "task_success":
            self._success(event, s, task.goal, where)
        else:
            self._failure(event, s, task, where)
            self._failed += 1
        self._task = None
        self._ended += 1

    def _success(self, event: MissionEvent, s: Sample, goal: GoalFacts, where: str) -> None:
        """A claimed success must hold for the ground truth, as the executor judges it."""
        assert self.facts is not None
        move, turn = self._slack(s, event)
        x, y, yaw = s.robot_pose
        distance = math.hypot(x - goal.x, y - goal.y)
        allowed = goal.tolerance + move
        if distance > allowed:
            raise EvidenceError(
                f"{where}.kind: expected task_fail (the recorded ground-truth pose at "
                f"t={s.time:g} s is {distance:.3f} m from goal {goal.name!r}, tolerance "
                f"{goal.tolerance:g} m), found task_success")
        if goal.heading is not None:
            off = abs(math.remainder(yaw - goal.heading, math.tau))
            if off > goal.heading_tolerance + turn:
                raise EvidenceError(
                    f"{where}.kind: expected task_fail (the recorded ground-truth heading at "
                    f"t={s.time:g} s is {math.degrees(off):.1f} degrees off goal "
                    f"{goal.name!r}'s, tolerance {math.degrees(goal.heading_tolerance):g} "
                    f"degrees), found task_success")

    def _slack(self, s: Sample, event: MissionEvent) -> tuple[float, float]:
        """How far (m, rad) the robot may have moved and turned between the control tick
        that decided ``event`` and the sample ``s`` that carries it."""
        assert self.facts is not None
        dt = max(0.0, s.time - event.time)
        # Twice the limits (a pushed robot can exceed them), never the sample's own recorded
        # velocity: that is as editable as the claim it would excuse.
        return 2.0 * self.facts.speed_limit * dt + 1e-6, 2.0 * self.facts.turn_limit * dt + 1e-6

    def _failure(self, event: MissionEvent, s: Sample, task: _Task, where: str) -> None:
        """A failure's cause, where the evidence can tell, must be what it says: a requirement
        may excuse some causes (a task cut by the user's --duration judges nothing)."""
        goal, cause = task.goal, event.cause
        found = f"found cause {cause!r}"
        if cause == "timeout" and event.time - task.start < goal.timeout - self.period - _EPS:
            raise EvidenceError(
                f"{where}.cause: expected a cause other than a timeout (task {goal.name!r} "
                f"ran {event.time - task.start:g} s of its {goal.timeout:g} s), {found}")
        if cause in ("position", "heading"):
            move, turn = self._slack(s, event)
            x, y, yaw = s.robot_pose
            distance = math.hypot(x - goal.x, y - goal.y)
            if cause == "position" and distance < goal.tolerance - move:
                raise EvidenceError(
                    f"{where}.cause: expected a cause other than 'position' (the recorded "
                    f"ground-truth pose at t={s.time:g} s is {distance:.3f} m from goal "
                    f"{goal.name!r}, within its tolerance {goal.tolerance:g} m), {found}")
            off = 0.0 if goal.heading is None else \
                abs(math.remainder(yaw - goal.heading, math.tau))
            if cause == "heading" and off < goal.heading_tolerance - turn:
                raise EvidenceError(
                    f"{where}.cause: expected a cause other than 'heading' (the recorded "
                    f"ground-truth heading at t={s.time:g} s is {math.degrees(off):.1f} "
                    f"degrees off goal {goal.name!r}'s, within its tolerance), {found}")
        if cause in ("abandoned", "cut"):
            self._abandoned = (cause, event.time)

    def _timeout(self, s: Sample, where: str) -> None:
        """A task running past its timeout (plus the sampling's slack) lost its task_fail."""
        task = self._task
        if task is None:
            return
        due = task.start + task.goal.timeout
        if s.time > due + 3 * self.period + _EPS:
            raise EvidenceError(
                f"{where}: events: expected the task_fail of task {task.goal.name!r} "
                f"(#{task.index}; started at t={task.start:g} s, timeout {task.goal.timeout:g} "
                f"s) by t={due:g} s, found none by t={s.time:g} s")

    # ---- the end --------------------------------------------------------------------------

    def end(self, end: tuple[float, str, str], where: str) -> None:
        """The end record's outcome must be the one the events give."""
        if self.facts is None or "mission_events" not in self.header.data:
            return
        _, outcome, _ = end
        if outcome not in (*FINISHED, "timeout"):
            return  # an error or an interruption is never a pass
        tasks = self._tasks()
        # a finished mission ended every task; one stopped by its time limit (or the user's
        # --duration) failed the running one and ended too: the executor's ``abandon``
        done = self._ended == tasks if outcome in FINISHED else True
        if self._task is not None or not done or self._finished_at is None:
            running = "" if self._task is None else \
                f", task {self._task.goal.name!r} (#{self._task.index}) never ended"
            raise EvidenceError(
                f"{where}: outcome: expected the outcome of an unfinished mission (the events "
                f"show {self._ended} of its {tasks} tasks ended{running}"
                f"{'' if self._finished_at is not None else ', no end event'}), found "
                f"{outcome!r}")
        if self._abandoned is not None:
            cause, at = self._abandoned
            if outcome in FINISHED or at != self._finished_at:
                raise EvidenceError(
                    f"{where}: outcome: expected a mission ended early at t={at:g} s (a task "
                    f"failed with cause {cause!r}, which only the mission's early end gives), "
                    f"found {outcome!r} and the mission's end event at "
                    f"t={self._finished_at:g} s")
        if outcome == "timeout":
            cut = self._abandoned is not None and self._abandoned[0] == "cut"
            # every task ended and none was abandoned: the limit cut the mission's settle
            # period (the .mission's `settle`), which leaves the tasks' outcomes as they were,
            # so claiming 'timeout' there can only keep a requirement from passing
            settling = self._ended == tasks and self._abandoned is None
            if not (cut or settling) and \
                    self._last + 2 * self.period < self.facts.time_limit - _EPS:
                raise EvidenceError(
                    f"{where}: outcome: expected an outcome other than 'timeout' (the "
                    f"recording ends at t={self._last:g} s, before the mission's time limit "
                    f"of {self.facts.time_limit:g} s, no task was cut by a duration limit and "
                    f"not every task had ended), found 'timeout'")
            return
        expected = "failed" if self._failed else "completed"
        if outcome != expected:
            raise EvidenceError(
                f"{where}: outcome: expected {expected!r} (the events show {self._failed} of "
                f"{tasks} tasks failed), found {outcome!r}")
