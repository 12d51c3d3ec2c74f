"""The `reference` navigator beside a table's corner (issue 25: a false alarm in search).

`rei search` (tpe, seed 1, small preset) found a fair room where the reference aborted a goal:
turning round beside a table, it ended with its side 4.5 cm from the table's corner. The
local planner's swept-distance grid counts a laser point as its cell's centre, half a
diagonal nearer, so it read that gap as below zero: every motion was refused, standing still
included, and the robot only backed up and came back until it gave up. Where the grid puts a
roll-out below the margin because of what the static map explains, the gap is now measured
exactly (less a 2 cm allowance); people keep the grid's wider reading. ``RoundedClearance``
is the navigator as it was (the grid's rounded gap only): the side these tests show failing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rei.runtime.robot import NavGoal
from rei.runtime.robot.navigator.recovery import arc_poses, footprint_gaps
from rei.runtime.robot.navigator.reference import (
    EXACT_ALLOWANCE,
    HORIZON,
    MARGIN,
    TIGHT_MARGIN,
    ReferenceNavigator,
)
from tests.robot.arcs_around import ArcsAround
from tests.robot.test_reference_recovery import HALF, Box, context_of, corridor_walls, drive

REPO = Path(__file__).resolve().parents[2]
SCENE = Path(__file__).parents[1] / "scenes" / "table_corner.mission"


class RoundedClearance(ArcsAround):
    """The reference before the fix: a roll-out's gap is the grid's rounded one only. It also
    leaves a goal behind it to the local planner's forward arcs, as the reference did when the
    search found the scene: turning on the spot first (issue 22) the robot no longer swings
    into the corner's trap in this room, which is no fix of the rounding. Nor did it hold its
    turning side in a squeeze (issue 25, tests/robot/test_squeeze.py), which also keeps it
    out of the trap here."""

    def _squeezed(self, points: np.ndarray) -> bool:
        return False

    def _exact_clearance(self, k: int, points: np.ndarray, rounded: np.ndarray,
                         mapped: np.ndarray) -> float:
        return float(rounded.min())


def table_edge_beside_the_left_side(gap: float) -> np.ndarray:
    """Laser points (robot frame) along a table's edge level with the robot's left side,
    ``gap`` from it, from behind the robot to its corner just ahead of the centre."""
    xs = np.arange(-0.40, 0.021, 0.01)
    return np.stack((xs, np.full(len(xs), HALF[1] + gap)), axis=1)


def swept_gaps(nav: ReferenceNavigator, points: np.ndarray) -> np.ndarray:
    """Each roll-out's true smallest gap to ``points``, measured independently (400 poses)."""
    return np.array([footprint_gaps(points, HALF, arc_poses(float(v), float(w), HORIZON,
                                                            400)).min()
                     for v, w in nav._cmds])


def command_index(nav: ReferenceNavigator, v: float, w: float) -> int:
    return int(np.argmin(np.hypot(nav._cmds[:, 0] - v, nav._cmds[:, 1] - w)))


HERE = (0.0, 0.0, 0.0)
"""The robot's pose in these tests: the corridor's start, facing along it."""


def navigator(gap: float | None, cls: type[ReferenceNavigator] = ReferenceNavigator
              ) -> ReferenceNavigator:
    """A navigator in the corridor, whose map also holds a table with its edge ``gap`` from
    the robot's left side (None: the map has no table, what the laser sees there is a
    person or something else unmapped)."""
    walls = corridor_walls()
    if gap is not None:
        walls = [*walls, Box(-0.40, HALF[1] + gap, 0.02, 0.45)]
    nav = cls()
    nav.reset(context_of(walls))
    return nav


def test_a_gap_beside_a_table_corner_is_measured_not_rounded_away() -> None:
    points = table_edge_beside_the_left_side(0.045)
    nav, old = navigator(0.045), navigator(0.045, RoundedClearance)
    ahead = command_index(nav, nav._vmax, 0.0)
    # Before: the grid read the 4.5 cm gap as less than the tight margin, for every motion.
    assert (old._rollout_clearance(points, HERE) < TIGHT_MARGIN).all()
    clearance = nav._rollout_clearance(points, HERE)
    # Driving straight on keeps the side 4.5 cm from the edge: measured, less the allowance,
    # that is admissible with the tight margin the planner keeps after a recovery.
    assert clearance[ahead] == pytest.approx(0.045 - EXACT_ALLOWANCE, abs=1e-3)
    assert TIGHT_MARGIN <= clearance[ahead] < MARGIN
    # Turning right on the spot swings the rear left corner (0.207 m out) into the edge:
    # still refused, so the robot is no less careful than before.
    spin_right = command_index(nav, 0.0, -0.6 * nav._wmax)
    assert clearance[spin_right] < 0.0


def test_a_person_as_near_as_the_table_keeps_the_wider_rounded_gap() -> None:
    """The same points, but the map has no table there: a person (who may step nearer within
    the horizon) is kept at the grid's rounded distance, as before."""
    points = table_edge_beside_the_left_side(0.045)
    person = navigator(None)._rollout_clearance(points, HERE)
    before = navigator(None, RoundedClearance)._rollout_clearance(points, HERE)
    assert (person == before).all()
    assert (person < TIGHT_MARGIN).all()


@pytest.mark.parametrize("gap", [0.005, 0.02, 0.045, 0.07])
def test_a_measured_gap_never_reads_wider_than_it_is(gap: float) -> None:
    points = table_edge_beside_the_left_side(gap)
    nav = navigator(gap)
    clearance = nav._rollout_clearance(points, HERE)
    truth = swept_gaps(nav, points)
    measured = clearance < MARGIN + 0.06  # the roll-outs the grid put near the margin
    assert measured.any()
    # Poses every ~1 cm / 0.02 rad: a corner 0.207 m out moves at most 4 mm between them.
    assert (clearance[measured] <= truth[measured] + 0.005).all()
    # Whatever is admissible at the tight margin really keeps that margin and the allowance.
    assert (truth[clearance >= TIGHT_MARGIN] >= TIGHT_MARGIN + EXACT_ALLOWANCE - 0.005).all()


def test_the_measured_clearances_are_deterministic() -> None:
    # A table the map knows, 4.7 cm off the robot's left side: its gaps are measured.
    walls = [*corridor_walls(), Box(-0.5, HALF[1] + 0.047, 2.0, 0.45)]
    runs = [drive(walls, [], [], NavGoal("g", 5.0, 0.0, None, 0.3, 200.0),
                  (0.0, 0.0, 0.0), 20.0).commands for _ in range(2)]
    assert runs[0] == runs[1]
    assert any(c.linear > 0 for c in runs[0])


@pytest.mark.slow
def test_the_reference_gets_past_the_table_corner_the_rounded_one_does_not(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from rei.runtime.runs.session import run_into  # noqa: PLC0415

    monkeypatch.chdir(REPO)  # `tests.robot...:RoundedClearance` is imported from here
    old, _ = run_into(SCENE, tmp_path / "old", "tests.robot.test_table_corner:RoundedClearance",
                      seed=1, monitor=False)
    beyond = old.measurements["tasks"][-1]
    assert old.outcome == "failed" and "no progress" in beyond["reason"], beyond
    summary, _ = run_into(SCENE, tmp_path / "new", seed=1, monitor=False)
    assert summary.outcome == "completed", summary.measurements["tasks"]
    assert summary.measurements["tasks_succeeded"] == 2
    assert summary.measurements["collisions"] == 0
    again, _ = run_into(SCENE, tmp_path / "again", seed=1, monitor=False)
    assert again.outcome == "completed"
    # Same room, seed and version: the same bytes.
    assert (tmp_path / "new" / "trace.jsonl").read_bytes() == \
        (tmp_path / "again" / "trace.jsonl").read_bytes()
