"""The `reference` navigator's tuning: one frozen record, one field per constant.

``ReferenceNavigator(tuning=...)`` takes a ``ReferenceTuning`` (``DEFAULT_TUNING`` when none
is given) and reads every value from ``self.tuning``. Overrides written before the record
keep working unchanged:

* the former module-level constants (``SIDE_MEMORY``, ``MARGIN``, ...) are still importable
  from ``rei.runtime.robot.navigator.reference``, as read-only aliases of ``DEFAULT_TUNING``'s
  fields (the same values, so a test asserting against them asserts against the defaults);
* the three knobs a subclass sets in its body (``slow_zone_reach``, ``turn_commitment``,
  ``hold_near_people``) are ``Tuned`` class attributes: they read the instance's tuning, and
  a subclass's (or an instance's) own value shadows them exactly as it shadowed the plain
  class attribute before. The navigator reads these three through ``self.<knob>``, never
  ``self.tuning.<knob>``, so such a subclass behaves as it did.

This module must never import pybullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

T = TypeVar("T")


@dataclass(frozen=True)
class ReferenceTuning:
    """Every tuning constant of the `reference` navigator (immutable; ``dataclasses.replace``
    makes a variant)."""

    resolution: float = 0.2
    """Metres per planning cell: a tile of 1 m holds 5, so a 1 m passage keeps free centres."""
    comfort: float = 0.45
    """Metres from obstacles below which cells cost more."""
    lookahead: float = 0.6
    """Metres along the path to the point the local planner steers towards."""
    horizon: float = 1.6
    """Seconds each velocity pair is rolled out."""
    rollout_steps: int = 6
    """Half the number of steps each roll-out is sampled at for its swept-distance map."""
    margin: float = 0.04
    """Metres kept between the footprint and any laser point."""
    sense_radius: float = 1.6
    """Metres from the laser beyond which its points are left out."""
    local_res: float = 0.04
    """Metres per cell of the robot-centred grid the roll-outs are checked on."""
    blocked_after: float = 30.0
    """Seconds without 0.1 m of progress before a goal is aborted (once the recoveries failed)."""
    abort_grace: float = 15.0
    """Seconds a recovery still running at ``BLOCKED_AFTER`` may go on before the goal aborts."""
    final_approach: float = 0.35
    """Metres from the goal where the rollouts give way to a direct approach."""
    align_first: float = math.pi / 4
    """Radians: a goal whose path starts farther than this from the robot's heading is first
    turned towards on the spot (as Nav2's rotation shim controller does, its default
    ``angular_dist_threshold``). A differential drive turns about its centre at no cost in path,
    while the local planner's score, which rewards speed, took the tightest forward arc instead: a
    loop of ~0.25 m radius that made short tasks starting with the goal behind the robot up to
    twice their shortest path (issue 22: 18 of 1,000 medium runs failed EFFICIENT_PATH so)."""
    stuck_after: float = 1.0
    """Seconds without an admissible motion before a recovery starts."""
    oscillate_after: float = 10.0
    """Seconds without progress (while moving, or since the last recovery) before a recovery."""
    tight_margin: float = 0.01
    """Metres kept from laser points by the local planner for ``TIGHT_FOR`` s after a recovery."""
    tight_for: float = 10.0
    """Seconds the ``TIGHT_MARGIN`` holds after a recovery."""
    turn_commitment: float = 0.05
    """Score a driving roll-out loses, while the slow zone holds, for turning against the local
    planner's last driving turn. A person straight ahead is not in the global plan (the path
    runs through them, where it passes the map's obstacles on one side), so nothing breaks the
    tie: the arcs past either side scored within a centimetre or two, the laser's noise tipped
    the choice from tick to tick, and the robot weaved in front of a person who had stopped for
    it (issue 22: SMOOTH_MOTION in 2 of 1,000 medium runs). The hysteresis of Nav2 DWB's
    oscillation critic, as a cost: a side is kept unless the other is clearly better. Turning on
    the spot is no weaving and neither pays nor sets it. While the slow zone holds, and in a
    squeeze (``SQUEEZE_GAP``), the side of the last driving turn is held outright for
    ``SIDE_MEMORY`` (as DWB's critic refuses a flip): creeping round a person at 0.06 m/s, the
    cost let single ticks of the other side through, left, right, left within 2 s (issue 25's
    protocol, TPE cand0045: SMOOTH_MOTION). Elsewhere the planner is as before."""
    squeeze_gap: float = 0.1
    """Metres: while a laser point is this near the footprint where it stands (the local grid's
    reading, up to ~5.7 cm under the truth), the robot squeezes past something, and it does not
    drive an arc against its last driving turn of the last ``SIDE_MEMORY`` seconds at all (it
    may still turn on the spot, or drive straight). There the roll-outs' clearances sit at
    ``MARGIN`` and the laser's 1 cm noise admits and refuses arcs from scan to scan: between two
    tables 0.45 m apart the arcs towards the path were refused for one scan, the planner took
    the only forward arc left, a sharp turn the other way, and the next scan admitted the first
    side again: right, left, right within 0.8 s at 0.065-0.26 m/s (issue 25: SMOOTH_MOTION in 1
    of 1,000 medium runs, nobody near). ``TURN_COMMITMENT``'s cost was not enough there: in a
    squeeze the scores of the few admissible arcs differ by tenths. Nav2 DWB's oscillation
    critic refuses such a flip outright, as this does. Away from obstacles and people the
    planner is as before, so a heading controller that weaves in the open is as visible as
    before (bench/defects: oscillating-heading)."""
    side_memory: float = 4.0
    """Seconds a driving turn's side is held in a squeeze or near a person: the span within which
    turning back and forth while driving is weaving (the default .vepl's SMOOTH_MOTION window)."""
    slow_zone_radius: float = 0.8
    """Metres from the footprint: an unmapped laser point this close puts the robot in its slow
    zone (the promise requirements may check, with ``SLOW_ZONE_SPEED``)."""
    slow_zone_speed: float = 0.12
    """m/s: the largest linear speed commanded while in the slow zone."""
    slow_zone_lead: float = 0.25
    """Metres beyond ``SLOW_ZONE_RADIUS`` from which the navigator already keeps to the cap."""
    slow_zone_memory: float = 3.0
    """Seconds the slow zone holds after the last unmapped point in it was seen."""
    unmapped_beyond: float = 0.15
    """Metres: a laser point farther than this from every static map obstacle is unmapped."""
    exact_allowance: float = 0.02
    """Metres an exactly measured gap still counts nearer than measured (the laser's 1 cm noise,
    the drive's lag), as the swept-distance grid's rounding used to by chance."""
    map_fit_res: float = 0.05
    """Metres per cell of the fine distance-to-map grid the laser points are checked against."""
    shadow_graze: float = 0.002
    """Metres the map is cast as larger for that comparison: a point on a table's corner, its
    beam grazing the corner, was otherwise read as 0.3 m in front of the wall behind it."""
    odometry_kept: int = 20
    """Steps of odometry kept to find the pose a scan was taken from (2 s at 10 Hz)."""
    shadow_tolerance: float = 0.05
    """Metres a beam may end short of the map obstacle it points at and still be that obstacle
    (five times the laser's 1 cm range noise). A person standing against a wall or wedged by a
    pillar is within ``UNMAPPED_BEYOND`` of it, and was taken for the map: the robot drove on at
    full speed 1 m from them (issue 25: REACTION_TIME in a 1,000-run campaign's room_0127)."""
    hold_near_people: bool = True
    """Whether, while the slow zone holds, the side of the last driving turn is held outright
    for ``SIDE_MEMORY`` (``TURN_COMMITMENT``; False: only its cost, the planner before issue
    25's TPE cand0045)."""
    smooth: bool = True
    """Whether the commands pass the velocity smoother (smoother.py: within the drive's
    accelerations, COMMAND_ACCELERATION); False: the planner's commands as they are, as the
    reference sent them before issue 40 (and as tests of the planner's choices read them)."""

    @property
    def slow_zone_reach(self) -> float:
        """Metres from the footprint within which an unmapped laser point slows the robot (its
        forward protective field: ``SLOW_ZONE_RADIUS`` + ``SLOW_ZONE_LEAD``; the default
        .vepl's ``react_zone`` is this value, to be set with `--param` for a robot tuned
        otherwise)."""
        return self.slow_zone_radius + self.slow_zone_lead


DEFAULT_TUNING = ReferenceTuning()
"""The tuning ``ReferenceNavigator`` runs with unless it is given another."""


class Tuned(Generic[T]):
    """A navigator's class attribute that reads the same-named value of the instance's
    ``tuning`` (of ``DEFAULT_TUNING`` when read on the class).

    A non-data descriptor, on purpose: a subclass that sets the attribute in its body
    (``hold_near_people = False``), or code that sets it on an instance, shadows it exactly as
    it shadowed the plain class attribute this replaces."""

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    def __get__(self, navigator: Any, owner: type | None = None) -> T:
        tuning = DEFAULT_TUNING if navigator is None else navigator.tuning
        value: T = getattr(tuning, self._name)
        return value
