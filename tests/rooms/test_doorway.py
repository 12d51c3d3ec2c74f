"""The `doorway` stressor: a person steps out of a doorway beside the route when the robot
comes level with it (a start trigger, by where the robot really is). Generated rooms carry
it where the robot's real way runs past the doorway; run with the reference navigator it
passes, while a navigator that ignores its laser on the doorway's side fails REACTION_TIME
— and the same navigator passes the doorway on its other side (the failure is the
side's, not the room's)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from rei.generators.rooms import SuiteRequest, coverage_report, generate, preset_space, write_suite
from rei.generators.rooms.stressors import DOORWAY_AHEAD, DOORWAY_OFF_LINE, DOORWAY_SEEN
from rei.generators.rooms.suite import GeneratedPair
from rei.lang.workspace import Workspace, load_room

REPO = Path(__file__).resolve().parents[2]
BLIND_LEFT = "bench.defects.perception:BlindSector"
"""The benchmark's navigator that drops its laser 60-120 degrees to its left."""


def _suite(seed: int, count: int = 2) -> list[GeneratedPair]:
    space = preset_space("stress").replaced({"stressor": ("doorway",)})
    return list(generate(SuiteRequest(space, "random", count, seed), Path("unused")).pairs)


def _left(d: tuple[int, int]) -> tuple[int, int]:
    return (-d[1], d[0])


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_doorway_rooms_put_the_person_beside_the_robots_real_way(seed: int) -> None:
    pairs = _suite(seed)
    sides = []
    for pair in pairs:
        stress, plan = pair.plan.stressor, pair.plan
        assert stress is not None and stress.mover is not None
        layout, mover = stress.layout, stress.mover
        p = layout.point
        d = (layout.approach[-1][0] - layout.approach[-2][0],
             layout.approach[-1][1] - layout.approach[-2][1])
        (back, t0), (door, t1) = mover.vertices
        n = (door[0] - p[0], door[1] - p[1])
        # the person stands two tiles beside the route tile p and steps one tile towards it
        assert abs(n[0]) + abs(n[1]) == 1 and n[0] * d[0] + n[1] * d[1] == 0
        assert back == (p[0] + 2 * n[0], p[1] + 2 * n[1]) and t0 == 0.0
        assert t1 == pytest.approx(1.0 / plan.params.speed, abs=0.01)
        # behind wall stubs: the tiles either side of the doorway are not floor
        for s in (1, -1):
            assert (door[0] + s * d[0], door[1] + s * d[1]) not in plan.floors
        # started by the robot coming within `trigger` of p, written in the room file
        assert mover.start_when is not None
        floor, within = mover.start_when
        assert floor == p
        top = 0.26  # the Waffle's drive limit; the stress preset has no speed limit
        assert within == pytest.approx(DOORWAY_AHEAD + top * DOORWAY_SEEN / plan.params.speed,
                                       abs=0.01)
        assert f"when robot within {within:g} of area_{-p[1]}_{p[0]}" in pair.room_text
        # the straight line between the goals (the any-angle robot's way) passes p closely
        a, b = plan.goals[0], plan.goals[1]
        off = abs((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / \
            math.dist(a, b)
        assert off <= DOORWAY_OFF_LINE + 1e-9 and within > off
        sides.append("left" if n == _left(d) else "right")
        assert layout.side == sides[-1]
    assert sorted(sides) == ["left", "right"]  # the suite alternates the side


def test_doorway_rooms_check_clean_and_are_a_pure_function_of_the_seed(tmp_path: Path) -> None:
    space = preset_space("stress").replaced({"stressor": ("doorway",)})
    suite = generate(SuiteRequest(space, "random", 2, 4), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    workspace = Workspace()
    for pair in suite.pairs:
        assert [str(d) for d in workspace.check(tmp_path / pair.room_file)
                + workspace.check(tmp_path / pair.mission_file)] == []
        doc = load_room(tmp_path / pair.room_file, workspace)
        assert doc.room is not None
        [person] = [o for o in doc.room.objects if o.name == "doorway_person"]
        assert person.behaviour == "yielding"
        assert person.trajectory is not None and person.trajectory.trigger is not None
    again = generate(SuiteRequest(space, "random", 2, 4), tmp_path)
    assert [p.room_text for p in again.pairs] == [p.room_text for p in suite.pairs]


def _run(mission: Path, out: Path, controller: str) -> dict[str, object]:
    from rei.runtime.runs.session import run_into

    run_into(mission, out, controller, 0, watchdog=None)
    summary: dict[str, object] = json.loads((out / "summary.json").read_text())
    return summary


def _failed(summary: dict[str, object]) -> dict[str, str]:
    return {v["requirement"]: v["reason"] for v in summary["verdicts"]  # type: ignore[attr-defined]
            if v["status"] == "fail"}


@pytest.mark.slow
def test_the_reference_passes_and_a_navigator_blind_on_the_doorways_side_fails(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    folder = tmp_path / "suite"
    space = preset_space("stress").replaced({"stressor": ("doorway",)})
    suite = generate(SuiteRequest(space, "random", 2, 1), folder)
    write_suite(suite, folder, coverage_report(suite))
    by_side = {p.plan.stressor.layout.side: folder / p.mission_file  # type: ignore[union-attr]
               for p in suite.pairs}
    careful = _run(by_side["left"], tmp_path / "reference", "reference")
    assert careful["verdict"] == "pass", _failed(careful)
    started = careful["measurements"]["variations"]["doorway_person"]["started_s"]  # type: ignore[index]
    assert started is not None  # the robot came level: the person did step out
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH",
                                                                                "")]))
    blind = _run(by_side["left"], tmp_path / "blind-left", BLIND_LEFT)
    assert blind["verdict"] == "fail"
    assert "REACTION_TIME" in _failed(blind)
    # the same navigator passes the doorway on its right: it is the side that fails it
    other = _run(by_side["right"], tmp_path / "blind-right", BLIND_LEFT)
    assert "REACTION_TIME" not in _failed(other), _failed(other)
