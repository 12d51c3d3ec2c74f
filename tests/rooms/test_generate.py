"""Generated suites: every pair checks clean, goals are reachable in order, humans keep clear
of walls and objects, the same seed gives the same bytes, descriptors ignore names."""

from __future__ import annotations

import csv
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rei.generators.rooms import (
    SuiteRequest,
    coverage_report,
    describe,
    generate,
    index_csv,
    preset_space,
    read_metadata,
    scene_of_documents,
    write_suite,
)
from rei.generators.rooms.geometry import CellMask, catmull_rom, disc_touches, polyline
from rei.generators.rooms.space import ParameterError, parse_row
from rei.lang.cli import main as rei_gen
from rei.lang.room.checks import blocking_objects, passable_floors
from rei.lang.workspace import Workspace, load_mission


def _suite(preset: str, seed: int, count: int, strategy: str = "random", **levels: str):
    space = preset_space(preset).replaced({k: (v,) for k, v in levels.items()})
    return SuiteRequest(space, strategy, count, seed)  # type: ignore[arg-type]


def _assert_valid_pair(room_path: Path, mission_path: Path) -> None:
    workspace = Workspace()
    problems = workspace.check(room_path) + workspace.check(mission_path)
    assert [str(d) for d in problems] == []
    mission_doc = load_mission(mission_path, workspace)
    room_doc = mission_doc.room
    assert room_doc is not None and room_doc.room is not None and room_doc.layout is not None
    room, layout = room_doc.room, room_doc.layout
    # Goals reachable in order on the inflated floor graph (tiles free of standing objects).
    free = passable_floors(room, layout)
    graph = layout.floor_graph.subgraph(free)
    goals = [g.floor.name for g in mission_doc.mission.goals]  # type: ignore[union-attr]
    assert goals[0] == room.robot.floor.name  # type: ignore[union-attr]
    for a, b in zip(goals, goals[1:], strict=False):
        assert nx.has_path(graph, a, b)
    # Humans: spline and control polygon keep clear of walls, outside cells and objects.
    cells = layout.cells
    floor_cells = {cells[n] for n in room.floors}
    standing = {cells[o.floor.name] for o in blocking_objects(room)}
    xs = [c[0] for c in floor_cells]
    ys = [c[1] for c in floor_cells]
    box = {(i, j) for i in range(min(xs) - 2, max(xs) + 3) for j in range(min(ys) - 2, max(ys) + 3)}
    blocked = CellMask((box - floor_cells) | standing)
    for obj in room.objects:
        if obj.trajectory is None:
            continue
        pts = [(float(cells[v.floor.name][0]), float(cells[v.floor.name][1]))
               for v in obj.trajectory.vertices]
        assert not disc_touches(catmull_rom(pts, obj.trajectory.loop), blocked, 0.25)
        assert not disc_touches(polyline(pts, obj.trajectory.loop), blocked, 0.25)
    # Nothing overlaps at the start: one thing per floor.
    floors = [o.floor.name for o in room.objects]
    assert len(floors) == len(set(floors))


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(preset=st.sampled_from(["small", "medium", "large", "stress"]),
       seed=st.integers(min_value=0, max_value=2**31),
       shape=st.sampled_from(["rect", "L", "joined"]))
def test_every_generated_pair_checks_clean_and_its_goals_are_reachable(
        tmp_path_factory: pytest.TempPathFactory, preset: str, seed: int, shape: str) -> None:
    out = tmp_path_factory.mktemp("suite")
    levels = {"shape": shape} if preset != "small" else {}
    if preset == "large":
        levels["size"] = "24x16"
    suite = generate(_suite(preset, seed, 2, **levels), out)
    write_suite(suite, out, coverage_report(suite))
    for pair in suite.pairs:
        _assert_valid_pair(out / pair.room_file, out / pair.mission_file)
        # The descriptors the generator wrote are those of the files as parsed.
        workspace = Workspace()
        mission_doc = load_mission(out / pair.mission_file, workspace)
        described = describe(scene_of_documents(mission_doc.room, mission_doc))
        assert described.as_row() == pair.plan.descriptors.as_row()


def test_crossing_humans_cross_the_robots_route(tmp_path: Path) -> None:
    suite = generate(_suite("medium", 11, 6, crossing="cross"), tmp_path)
    assert all(p.plan.descriptors.crossings >= 1 for p in suite.pairs)


def test_same_seed_same_bytes_in_process(tmp_path: Path) -> None:
    a = generate(_suite("medium", 42, 4), tmp_path / "a")
    b = generate(_suite("medium", 42, 4), tmp_path / "b")
    c = generate(_suite("medium", 43, 4), tmp_path / "c")
    texts = [(p.room_text, p.mission_text) for p in a.pairs]
    assert texts == [(p.room_text, p.mission_text) for p in b.pairs]
    assert index_csv(a) == index_csv(b)
    assert texts != [(p.room_text, p.mission_text) for p in c.pairs]


@pytest.mark.slow
def test_same_seed_same_bytes_across_processes(tmp_path: Path) -> None:
    outputs = []
    for hash_seed, folder in (("1", "one"), ("987", "two")):
        env = dict(os.environ, PYTHONHASHSEED=hash_seed)
        subprocess.run([sys.executable, "-m", "rei.lang.cli", "rooms", "-o",
                        str(tmp_path / folder), "--preset", "medium", "--count", "3", "--seed",
                        "5", "--quiet"], check=True, env=env, capture_output=True)
        outputs.append({p.name: p.read_bytes() for p in sorted((tmp_path / folder).iterdir())})
    assert outputs[0] == outputs[1]
    assert len(outputs[0]) == 3 * 2 + 2


def test_descriptors_do_not_change_when_objects_are_renamed(tmp_path: Path) -> None:
    suite = generate(_suite("small", 3, 2), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    for pair in suite.pairs:
        room_path = tmp_path / pair.room_file
        original = describe(scene_of_documents(*_docs(tmp_path / pair.mission_file)))
        renamed_text = re.sub(r"\b(object|human) (\w+)", lambda m: f"{m[1]} renamed_{m[2][::-1]}",
                              room_path.read_text())
        renamed_text = renamed_text.replace("robot robot", "robot other_name")
        assert renamed_text != room_path.read_text()
        room_path.write_text(renamed_text)
        renamed = describe(scene_of_documents(*_docs(tmp_path / pair.mission_file)))
        assert renamed == original


def _docs(mission_path: Path):  # type: ignore[no-untyped-def]
    mission_doc = load_mission(mission_path, Workspace())
    return mission_doc.room, mission_doc


def test_index_and_metadata_carry_parameters_and_descriptors(tmp_path: Path) -> None:
    suite = generate(_suite("medium", 9, 3), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    with (tmp_path / "index.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 3
    for row in rows:
        room_path = tmp_path / row["room"]
        assert (tmp_path / row["mission"]).is_file()
        meta = read_metadata(room_path.read_text())
        for key, value in meta["parameters"].items():
            assert row[key] == value
        for key, value in meta["descriptors"].items():
            assert row[key] == value
        assert float(row["tortuosity"]) >= 1.0
        assert float(row["visibility_m"]) > 0


def test_systematic_pairwise_suite_covers_every_pair(tmp_path: Path) -> None:
    space = preset_space("small").replaced({"size": ("6x5", "7x6"), "objects": ("6", "10"),
                                            "cycles": ("1", "2"), "mix": ("mixed", "clutter")})
    suite = generate(SuiteRequest(space, "systematic", None, 1, max_grid=4), tmp_path)
    assert suite.design.design == "pairwise"
    report = coverage_report(suite)
    match = re.search(r"Pairs of levels covered: (\d+) of (\d+)", report)
    assert match and match[1] == match[2]


def test_cli_writes_a_suite_that_rei_gen_check_accepts(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    out = tmp_path / "suite"
    assert rei_gen(["rooms", "-o", str(out), "--preset", "small", "--strategy", "systematic",
                    "--count", "4", "--seed", "2"]) == 0
    assert "Pairs of levels covered" in capsys.readouterr().out
    assert rei_gen(["check", str(out)]) == 0
    assert len(list(out.glob("*.room"))) == 4


@pytest.mark.parametrize(("args", "option"), [
    (["--count", "0"], "--count"),
    (["--objects", "500"], "--objects"),
    (["--size", "5x5", "--objects", "20", "--preset", "small"], "--objects"),
    (["--spacing", "100"], "--spacing"),
    (["--speed", "inf"], "--speed"),
    (["--humans", "-1"], "--humans"),
    (["--size", "4x4", "--spacing", "3", "--goals", "3", "--humans", "0", "--objects", "9"],
     "--objects"),
])
def test_impossible_requests_exit_2_naming_the_option_and_write_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], option: str
) -> None:
    out = tmp_path / "suite"
    assert rei_gen(["rooms", "-o", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert option in err and "expected" in err and "found" in err
    assert not out.exists()


@pytest.mark.parametrize("preset", ["small", "medium", "large", "stress"])
def test_every_preset_systematic_suite_checks_clean(tmp_path: Path, preset: str) -> None:
    space = preset_space(preset)
    suite = generate(SuiteRequest(space, "systematic", 3, 6), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    assert suite.design.design == ("full" if space.grid_size <= 256 else "pairwise")
    for pair in suite.pairs:
        _assert_valid_pair(tmp_path / pair.room_file, tmp_path / pair.mission_file)


@pytest.mark.parametrize("strategy", ["random", "systematic"])
@pytest.mark.parametrize("preset", ["small", "medium", "large", "stress"])
def test_generated_missions_generate_every_target(tmp_path: Path, preset: str,
                                                  strategy: str) -> None:
    suite = generate(SuiteRequest(preset_space(preset), strategy, 1, 12), tmp_path)  # type: ignore[arg-type]
    write_suite(suite, tmp_path, coverage_report(suite))
    mission = tmp_path / suite.pairs[0].mission_file
    assert rei_gen(["generate", "--target", "all", "-o", str(tmp_path / "out"),
                    str(mission)]) == 0
    assert any((tmp_path / "out").rglob("*"))


@pytest.mark.slow
@pytest.mark.parametrize("preset", ["small", "medium"])
def test_generated_mission_runs_with_rei_run(tmp_path: Path, preset: str) -> None:
    runtime_cli = pytest.importorskip("rei.runtime.commands.cli")
    suite = generate(SuiteRequest(preset_space(preset), "random", 1, 4), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    out = tmp_path / "run"
    status = runtime_cli.main(["run", str(tmp_path / suite.pairs[0].mission_file), "-o",
                               str(out), "--duration", "5", "--quiet"])
    assert status in (0, 1)  # a mission cut short by --duration is a failed verdict, not an error
    assert (out / "summary.json").is_file()


def test_describe_prints_the_descriptors_of_existing_missions(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    suite = generate(_suite("medium", 21, 2), tmp_path)
    write_suite(suite, tmp_path, coverage_report(suite))
    missions = [str(tmp_path / p.mission_file) for p in suite.pairs]
    assert rei_gen(["rooms", "--describe", *missions]) == 0
    rows = list(csv.DictReader(capsys.readouterr().out.splitlines()))
    for row, pair in zip(rows, suite.pairs, strict=True):
        expected = pair.plan.descriptors.as_row()
        assert {k: row[k] for k in expected} == expected
    assert rei_gen(["rooms", "--describe", str(tmp_path / suite.pairs[0].room_file)]) == 2
    assert "expected a .mission file" in capsys.readouterr().err


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), di=st.integers(-50, 50), dj=st.integers(-50, 50))
def test_descriptors_do_not_depend_on_the_frame(seed: int, di: int, dj: int) -> None:
    from dataclasses import replace

    from rei.generators.rooms.descriptors import Scene

    suite = generate(_suite("medium", seed, 1), Path("unused"))
    plan = suite.pairs[0].plan
    doc_free = describe(_plan_scene(plan))

    def shift(c: tuple[int, int]) -> tuple[int, int]:
        return (c[0] + di, c[1] + dj)

    scene: Scene = _plan_scene(plan)
    moved = replace(scene, floors=frozenset(shift(c) for c in scene.floors),
                    obstacles=tuple(replace(o, cell=shift(o.cell)) for o in scene.obstacles),
                    goals=tuple(shift(c) for c in scene.goals),
                    trajectories=tuple((tuple(shift(c) for c in v), loop)
                                       for v, loop in scene.trajectories))
    assert describe(moved) == doc_free == plan.descriptors


def _plan_scene(plan):  # type: ignore[no-untyped-def]
    from rei.catalogue import default_catalogue
    from rei.generators.rooms.descriptors import Obstacle, Scene

    catalogue = default_catalogue()
    return Scene(1.0, plan.floors,
                 tuple(Obstacle(o.cell, catalogue.get(o.type).footprint, o.heading)
                       for o in plan.objects),
                 plan.goals, plan.params.cycles,
                 tuple((h.vertices, h.loop) for h in plan.humans), len(plan.humans))


def test_the_behaviour_factor_is_covered_pairwise_and_written_into_the_rooms(
        tmp_path: Path) -> None:
    space = preset_space("medium").replaced({"behaviour": ("scripted", "yielding", "social",
                                                           "mix"), "humans": ("1", "2")})
    suite = generate(SuiteRequest(space, "systematic", None, 3, max_grid=4), tmp_path)
    assert suite.design.design == "pairwise"
    report = coverage_report(suite)
    match = re.search(r"Pairs of levels covered: (\d+) of (\d+)", report)
    assert match and match[1] == match[2]
    seen: set[str] = set()
    for pair in suite.pairs:
        written = re.findall(r"} behaviour (\w+)", pair.room_text)
        level = pair.params.behaviour
        expected = (["yielding", "social"][:pair.params.humans] if level == "mix"
                    else [level] * pair.params.humans)
        assert written == expected
        seen |= set(written)
    assert seen == {"scripted", "yielding", "social"}


def test_generated_humans_walk_at_human_speeds_and_suites_are_reactive_by_default() -> None:
    for preset in ("small", "medium", "large"):
        space = preset_space(preset)
        assert all(0.5 <= float(s) <= 1.4 for s in space.levels("speed"))
        assert "scripted" not in space.levels("behaviour")
    with pytest.raises(ParameterError, match="--speed"):
        parse_row({**{f.name: f.levels[0] for f in preset_space("small").factors},
                   "speed": "2"}, ("table", "chair", "shelf", "box", "pillar"))


def test_the_small_preset_exercises_heading_speed_limit_doorway_and_crossing(
        tmp_path: Path) -> None:
    suite = generate(SuiteRequest(preset_space("small"), "random", 6, 0), tmp_path)
    missions = [p.mission_text for p in suite.pairs]
    assert any(" heading " in m for m in missions)
    assert any("max_speed 0.18" in m for m in missions)
    assert any("max_speed" not in m for m in missions)
    assert all(p.plan.descriptors.crossings >= 1 for p in suite.pairs)
    # The joined shape's doorway across 5 tiles is one tile wide: a narrow passage.
    assert any(p.params.shape == "joined" and p.plan.descriptors.narrowest_m <= 1.1
               for p in suite.pairs)


def test_a_final_heading_is_a_quarter_turn_from_the_way_the_robot_arrives(
        tmp_path: Path) -> None:
    """A goal heading is worth checking only if reaching the goal does not meet it by itself:
    the heading is a quarter turn from the last step of the planned route into the goal,
    so a navigator that ignores headings arrives at least 45 degrees off (it once matched the
    way from the previous goal, and a straight last leg met it for free)."""
    checked = 0
    for seed in range(12):
        for pair in generate(_suite("medium", seed, 4, heading="yes"), tmp_path / f"{seed}").pairs:
            (written,) = re.findall(r" heading (\d+)", pair.mission_text)
            goal = pair.plan.goals[-1]
            route = pair.plan.route
            last = max(k for k, cell in enumerate(route) if cell == goal)
            before = route[last - 1]
            arrival = math.degrees(math.atan2(goal[1] - before[1], goal[0] - before[0]))
            off = abs((float(written) - arrival + 180.0) % 360.0 - 180.0)
            assert off >= 45.0, (seed, pair.plan.params.name, written, arrival)
            checked += 1
    assert checked == 48


def test_no_open_human_path_ends_on_a_goal(tmp_path: Path) -> None:
    """Issue 22: a human stands at its open path's last vertex for the rest of the run; on a
    goal's tile (in medium room 394 a corner) it stood on the robot's goal until the
    reference aborted it, in both repeats. Medium seed 0's first 30 rooms held one such path
    (room 30, before the balanced rows of wp-design) before the generator refused them."""
    suite = generate(_suite("medium", 0, 30), tmp_path)
    open_paths = [(p.name, h.vertices[-1], p.plan.goals) for p in suite.pairs
                  for h in p.plan.humans if not h.loop]
    assert len(open_paths) > 10  # the check below has something to judge
    assert [(name, end) for name, end, goals in open_paths if end in goals] == []
