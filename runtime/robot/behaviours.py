"""The behaviours a navigator owes, and how a run learns which of them it exercised.

A navigation stack is more than its path follower: it recovers when stuck (each kind of
recovery), rotates in place, backs up, re-plans around what its map does not show, slows and
waits for people, squeezes through passages a few centimetres wider than itself, turns to a
goal's heading, keeps to a mission's speed limit and reacts to what appears close. A test suite
in which a behaviour never runs cannot find a defect in it, so every run counts the behaviours
it exercised (``EpisodeLog``) and a campaign reports which never ran (behaviour coverage).

Two sources, both through the public controller protocol only:

* **reported**: while a goal is active, a controller may say what it is doing in its
  feedback's ``message`` as ``"doing: name, name"`` with names from ``BEHAVIOURS``
  (``doing_message``, ``reported``). The reference navigator does; a user's controller may.
  Unknown names are kept as they are (a controller's own behaviours), never an error.
* **observed**: what any controller's commands show, whatever it reports: rotating in
  place and backing up (``observed``).

This module is a contract (robot wing, no pybullet): the simulation feeds the log, the
campaigns read its JSON from each run's summary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

DOING = "doing:"
"""Prefix of a feedback message that names the behaviours running now."""

BEHAVIOURS: dict[str, str] = {
    "recovery.replan": "recovery: re-plan around what the laser sees",
    "recovery.replan_reduced": "recovery: re-plan with the inflation cut to the half width",
    "recovery.backup": "recovery: back up",
    "recovery.spin": "recovery: rotate towards the path",
    "recovery.wait": "recovery: wait for the way to clear",
    "rotate_in_place": "rotate in place (no forward motion)",
    "back_up": "drive backwards",
    "replan_unmapped": "re-plan around an obstacle the map does not show",
    "slow_for_person": "slow down for something unmapped appearing ahead (a person, a cart)",
    "wait_for_person": "stop and wait while something the laser sees blocks every motion",
    "tight_passage": "drive through a passage within a few centimetres of the footprint",
    "goal_heading": "turn to a goal's heading",
    "speed_limit": "keep to a mission speed limit below the drive's",
}
"""Every behaviour REI knows, with what it means (the coverage table's rows, in order)."""

OBSERVED = ("rotate_in_place", "back_up", "speed_limit")
"""Behaviours REI sees in any controller's commands (the speed limit: commanding at least
``SPEED_LIMIT_SHARE`` of a mission's limit, so the limit is what holds the robot back)."""
SPEED_LIMIT_SHARE = 0.9

ROTATING = 0.1
"""rad/s of commanded turn that, with no forward command, is rotating in place."""
STILL = 0.01
"""m/s below which a commanded linear speed is no forward motion."""


def doing_message(names: list[str] | tuple[str, ...]) -> str:
    """The feedback message that reports ``names`` as running ('' when none)."""
    return f"{DOING} {', '.join(names)}" if names else ""


def reported(message: str) -> tuple[str, ...]:
    """The behaviours a feedback message reports (none unless it starts with ``doing:``)."""
    if not message.startswith(DOING):
        return ()
    return tuple(n for n in (p.strip() for p in message[len(DOING):].split(",")) if n)


def observed(linear: float, angular: float) -> tuple[str, ...]:
    """The behaviours a command shows by itself."""
    if linear < -STILL:
        return ("back_up",)
    if abs(linear) <= STILL and abs(angular) >= ROTATING:
        return ("rotate_in_place",)
    return ()


@dataclass
class _Tally:
    episodes: int = 0
    seconds: float = 0.0
    first: float = math.inf


class EpisodeLog:
    """Names that hold, tick by tick, through one run (the behaviours it exercised; the
    situations it met, rei.runtime.observation.model.situations): how often each began (an
    episode is a run of consecutive ticks), for how many seconds, and when first."""

    def __init__(self) -> None:
        self._tallies: dict[str, _Tally] = {}
        self._running: frozenset[str] = frozenset()
        self._last: float | None = None

    def tick(self, time: float, names: tuple[str, ...] | list[str] | set[str]) -> None:
        """The behaviours running at ``time`` (ticks come in time order)."""
        now = frozenset(names)
        # A tick names what the step that ended at it did: the period since the last tick.
        dt = 0.0 if self._last is None else max(0.0, time - self._last)
        for name in now - self._running:
            tally = self._tallies.setdefault(name, _Tally())
            tally.episodes += 1
            tally.first = min(tally.first, time)
        for name in now:
            self._tallies[name].seconds += dt
        self._running, self._last = now, time

    def to_json(self) -> dict[str, dict[str, float | int]]:
        """``{name: {"episodes", "seconds", "first"}}`` sorted by name (summary.json's
        ``behaviours``; only behaviours that ran)."""
        return {name: {"episodes": t.episodes, "seconds": round(t.seconds, 3),
                       "first": round(t.first, 3)}
                for name, t in sorted(self._tallies.items())}


__all__ = ["BEHAVIOURS", "DOING", "OBSERVED", "SPEED_LIMIT_SHARE", "EpisodeLog",
           "doing_message", "observed", "reported"]
