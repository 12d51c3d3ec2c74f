"""Timing defects: the navigator acts on old information, or its commands arrive late."""

from __future__ import annotations

from collections import deque
from dataclasses import replace

from rei.runtime.messages import LaserScan
from rei.runtime.robot.contract import STOP, ControllerContext, Observation, VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator

SCAN_EVERY = 5
"""StaleScans uses one scan in this many."""
LATENCY = 0.5
"""Seconds ControlLatency's commands are late."""


class StaleScans(ReferenceNavigator):
    """Defect: uses only every 5th laser scan and keeps acting on it until the next one (at a
    5 Hz laser, a view up to a second old, as if the world had stood still meanwhile).

    Imitates: a throttled laser topic (a `throttle` node left in the launch file from a
    bandwidth test) or a callback queue that drops most messages under load.

    Expected catcher: REACTION_TIME when the scan that first shows a person or a moving object
    ahead is one it drops (it then slows 0.2-0.8 s late; three times in five); the collision
    requirements with moving humans (MISSION_WITH_HUMAN_TRAJECTORY), HUMAN_SLOW_ZONE.
    """

    name = "stale-scans"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._scans_seen = 0
        self._last_scan_time: float | None = None
        self._held: tuple[LaserScan, float | None] | None = None

    def step(self, observation: Observation) -> VelocityCommand:
        scan = observation.scan
        if scan is not None and (self._held is None
                                 or observation.scan_time != self._last_scan_time):
            self._last_scan_time = observation.scan_time
            if self._scans_seen % SCAN_EVERY == 0:
                self._held = (scan, observation.scan_time)
            self._scans_seen += 1
        held, held_time = self._held if self._held is not None else (None, None)
        return super().step(replace(observation, scan=held, scan_time=held_time))


class ControlLatency(ReferenceNavigator):
    """Defect: every command reaches the drive 0.5 s after the navigator decided it (the
    navigator plans as if it took effect at once).

    Imitates: a command path through a congested network or a deep message queue (a
    `cmd_vel` relay with a large buffer, a velocity smoother with a long window).

    Expected catcher: REACTION_TIME (it slows 0.5 s after its laser showed a person or a
    moving object ahead); the collision requirements (overshooting into obstacles), task
    failures from overshooting goals (MISSION_GOALS_REACHED), HUMAN_SLOW_ZONE (slows late).
    """

    name = "control-latency"
    latency = LATENCY
    """Seconds (a subclass may change it: the tests measure REACTION_TIME against it)."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._queue: deque[tuple[float, VelocityCommand]] = deque()
        self._released = STOP

    def step(self, observation: Observation) -> VelocityCommand:
        self._queue.append((observation.time, super().step(observation)))
        while self._queue and self._queue[0][0] <= observation.time - self.latency + 1e-9:
            self._released = self._queue.popleft()[1]
        return self._released


DROPOUT_PERIOD = 2.0
"""Seconds between the starts of two of CommandDropout's outages."""
DROPOUT_LENGTH = 0.6
"""Seconds each outage lasts."""


class CommandDropout(ReferenceNavigator):
    """Defect: for 0.6 s of every 2 s no command reaches the drive, and the base keeps
    executing the last one it received (the navigator goes on deciding, unaware).

    Imitates: `cmd_vel` over a lossy wireless link or a saturated DDS writer dropping
    messages, with a base driver that holds the last command instead of timing out to zero.

    Expected catcher: REACTION_TIME when a person or a moving object shows up ahead early in
    an outage (it slows up to 0.6 s late; more than the window's 0.3 s in about one
    encounter in seven); the collision requirements and HUMAN_SLOW_ZONE (it keeps driving
    towards a person it has already seen), task failures from overshooting goals
    (MISSION_GOALS_REACHED), SMOOTH_MOTION (late corrections).
    """

    name = "command-dropout"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._held = STOP

    def step(self, observation: Observation) -> VelocityCommand:
        command = super().step(observation)
        if observation.time % DROPOUT_PERIOD >= DROPOUT_LENGTH:
            self._held = command  # delivered
        return self._held


SCAN_DELAY = 0.6
"""Seconds DelayedScans' scans arrive after they were taken."""


class DelayedScans(ReferenceNavigator):
    """Defect: every laser scan reaches the navigator 0.6 s after it was taken (at the laser's
    full rate), and the navigator treats it as the world now.

    Imitates: a laser driver or a message filter with a deep queue on an overloaded computer
    (a TF wait, a `message_filters` cache), delivering old scans without dropping any.

    Expected catcher: REACTION_TIME (it slows 0.6 s after its laser showed a person or a
    moving object ahead); the collision requirements with moving humans and dynamic objects
    (MISSION_WITH_HUMAN_TRAJECTORY, NO_ROBOT_COLLISION), HUMAN_SLOW_ZONE (a person is seen
    where they were); the stressor rooms' emerging people and crossing carts.
    """

    name = "delayed-scans"

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        self._scans: deque[tuple[float, LaserScan]] = deque()
        self._last_time: float | None = None
        self._delivered: tuple[LaserScan, float] | None = None

    def step(self, observation: Observation) -> VelocityCommand:
        if observation.scan is not None and observation.scan_time != self._last_time:
            self._last_time = observation.scan_time
            taken = observation.scan_time if observation.scan_time is not None \
                else observation.time
            self._scans.append((taken, observation.scan))
        while self._scans and self._scans[0][0] <= observation.time - SCAN_DELAY + 1e-9:
            taken, scan = self._scans.popleft()
            self._delivered = (scan, taken)
        scan, taken = self._delivered if self._delivered is not None else (None, None)
        return super().step(replace(observation, scan=scan, scan_time=taken))
