"""The scenario's search dimensions (generators/rooms/scenario.py): the humans' start phase,
the stressor's shift and sensor fault parameters. For each: a candidate's files carry the
value, they pass the `rei-gen check` rules on disk, what the runtime reads from them is the
value (the humans' curve, the mover's times, the mission's faults), a room that cannot take
a value is a candidate 'not built' naming the flag, and the same row gives the same bytes.
Bad ranges (exit 2 naming the flag) are in test_search_input.py."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from rei.generators.concrete.build import load_concrete_mission
from rei.generators.rooms.design import decode_point
from rei.generators.rooms.writer import read_metadata
from rei.lang.room.spline import CatmullRom
from rei.lang.workspace import Workspace
from rei.runtime.campaigns.search.candidates import Candidate, build_candidate, write_candidates
from rei.runtime.campaigns.search.driver import SearchConfig, check_config, search_table

ONE_HUMAN = (("shape", "rect"), ("size", "8x5"), ("objects", "2"), ("mix", "furniture"),
             ("humans", "1"), ("vertices", "3"), ("loop", "no"), ("crossing", "cross"),
             ("goals", "2"), ("spacing", "4"), ("cycles", "1"), ("behaviour", "yielding"),
             ("heading", "no"), ("max_speed", "none"))
EMERGE = (("shape", "rect"), ("size", "10x6"), ("objects", "3"), ("mix", "furniture"),
          ("speed", "1.0"), ("stressor", "emerge"))


def candidate(folder: Path, scenario: Sequence[tuple[str, str]], u: float,
              levels: Sequence[tuple[str, str]] = ONE_HUMAN, preset: str = "small",
              layout: int = 3) -> Candidate:
    """The candidate at coordinate ``u`` of every dimension, its files written (if built)."""
    config = SearchConfig(preset=preset, levels=tuple(levels), scenario=tuple(scenario),
                          layout=layout)
    space, dims = check_config(config)
    point = tuple(u for _ in dims)
    built = build_candidate(decode_point(space, dims, point, layout), 1, 1, point, folder, "0")
    write_candidates([built], folder, "random", preset)
    return built


def written(folder: Path, scenario: Sequence[tuple[str, str]], u: float) -> dict[str, bytes]:
    """The bytes of every file the candidate at ``u`` writes, by name."""
    candidate(folder, scenario, u)
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def checked(folder: Path, built: Candidate) -> tuple[Path, Path]:
    pair = built.pair
    assert pair is not None, built.problem
    room, mission = folder / pair.room_file, folder / pair.mission_file
    workspace = Workspace()
    errors = [d for p in (room, mission) for d in workspace.check(p) if d.is_error]
    assert errors == [], errors  # `rei-gen check`'s rules, on the files on disk
    return room, mission


def walker(mission: Path) -> CatmullRom:
    """The generated human's curve as the runtime gets it (concrete model -> spline)."""
    world = load_concrete_mission(mission).world
    human = next(o for o in world.objects if o.name == "walker_1")
    assert human.trajectory is not None
    points = human.trajectory.points
    return CatmullRom(np.array([p.t for p in points]), np.array([[p.x, p.y] for p in points]),
                      human.trajectory.loop)


def test_the_start_phase_is_in_the_room_and_the_human_waits_for_it(tmp_path: Path) -> None:
    built = candidate(tmp_path / "phase", [("phase", "0:20")], 0.5)
    room, mission = checked(tmp_path / "phase", built)
    assert dict(built.row.scenario) == {"phase": "10"}
    text = room.read_text()
    assert read_metadata(text)["scenario"] == {"phase": "10"}
    assert re.search(r"human walker_1 on (area_\d+_\d+) trajectory stop \{\n\s+\1 at 10\n",
                     text), text
    curve = walker(mission)
    start = curve.position(0.0)
    assert curve.position(9.9) == pytest.approx(start)  # waits on its first tile until 10 s
    assert np.hypot(*np.subtract(curve.position(12.0), start)) > 0.5  # then walks

    # The check can fail: at phase 0 (the generator's own form, `total`) the same room's
    # human is on its way by 9.9 s.
    plain = candidate(tmp_path / "plain", [("phase", "0:20")], 0.0)
    assert "trajectory total" in checked(tmp_path / "plain", plain)[0].read_text()
    curve = walker(checked(tmp_path / "plain", plain)[1])
    assert np.hypot(*np.subtract(curve.position(9.9), curve.position(0.0))) > 0.5


def test_a_looping_human_reaches_its_first_vertex_at_the_phase(tmp_path: Path) -> None:
    levels = tuple((k, "yes" if k == "loop" else v) for k, v in ONE_HUMAN)
    built = candidate(tmp_path / "loop", [("phase", "0:20")], 0.3, levels=levels)
    _, mission = checked(tmp_path / "loop", built)
    assert dict(built.row.scenario) == {"phase": "6"}
    curve = walker(mission)
    first = tuple(curve.p[0])
    assert curve.loop and curve.position(6.0) == pytest.approx(first)
    # Already walking its loop before then (a shift in time, not a wait).
    assert np.hypot(*np.subtract(curve.position(0.0), first)) > 0.1


def test_the_stressor_shift_moves_the_movers_times_and_the_meeting(tmp_path: Path) -> None:
    base = candidate(tmp_path / "base", [("stress_shift", "0:1")], 0.0, levels=EMERGE,
                     preset="stress")
    later = candidate(tmp_path / "later", [("stress_shift", "0:4")], 0.75, levels=EMERGE,
                      preset="stress")
    assert dict(later.row.scenario) == {"stress_shift": "3"}
    texts = [checked(tmp_path / n, c)[0].read_text()
             for n, c in (("base", base), ("later", later))]
    meetings = [float(read_metadata(t)["stressor"]["meeting_s"]) for t in texts]
    assert meetings[1] == pytest.approx(meetings[0] + 3.0)

    def walk_times(text: str) -> list[float]:
        block = text.split("human emerging_person on ")[1].split("}")[0]
        rows = re.findall(r"(area_\d+_\d+) at ([\d.]+)", block)
        first = rows[0][0]
        return [float(t) for c, t in rows if c != first]

    assert np.allclose(np.subtract(walk_times(texts[1]), walk_times(texts[0])), 3.0)
    again = candidate(tmp_path / "again", [("stress_shift", "0:4")], 0.75, levels=EMERGE,
                      preset="stress")
    assert again.pair is not None and later.pair is not None
    assert (again.pair.room_text, again.pair.mission_text) == (later.pair.room_text,
                                                               later.pair.mission_text)


def test_a_room_that_cannot_take_a_shift_is_a_candidate_not_built(tmp_path: Path) -> None:
    too_early = candidate(tmp_path / "early", [("stress_shift", "-60:-59")], 0.0,
                          levels=EMERGE, preset="stress")
    assert too_early.pair is None and "--stress-shift" in too_early.problem
    assert "wait" in too_early.problem
    cart = candidate(tmp_path / "cart", [("stress_shift", "1:2")], 0.0,
                     levels=(*EMERGE[:-1], ("stressor", "crossing")), preset="stress")
    assert cart.pair is None and "cart" in cart.problem
    none = candidate(tmp_path / "none", [("stress_shift", "1:2")], 0.0)
    assert none.pair is None and "--stress-shift" in none.problem
    assert not list((tmp_path / "none").glob("*.room"))  # nothing written for it


def test_fault_parameters_go_into_the_missions_fault_section(tmp_path: Path) -> None:
    scenario = [("laser_poisson.rate", "1:21"), ("laser_poisson.gain", "0.1:0.5"),
                ("laser_dropout.share", "0.1:0.3")]
    built = candidate(tmp_path / "faults", scenario, 0.5)
    room, mission = checked(tmp_path / "faults", built)
    assert "    fault {\n        laser_dropout share 0.2\n" \
           "        laser_poisson gain 0.3 rate 11\n    }\n" in mission.read_text()
    faults = {f.kind: f for f in load_concrete_mission(mission).faults}
    assert faults["laser_poisson"].value("rate") == 11.0
    assert faults["laser_poisson"].value("gain") == pytest.approx(0.3)
    assert faults["laser_poisson"].value("period") == 1.0  # the kind's default
    assert faults["laser_dropout"].value("share") == pytest.approx(0.2)
    assert read_metadata(room.read_text())["scenario"] == {
        "laser_dropout.share": "0.2", "laser_poisson.gain": "0.3", "laser_poisson.rate": "11"}
    index = (tmp_path / "faults" / "index.csv").read_text()
    assert "laser_poisson.rate=11 laser_poisson.gain=0.3 laser_dropout.share=0.2" in index


def same_bytes_and_table_row(tmp_path: Path, scenario: Sequence[tuple[str, str]], u: float,
                             v: float) -> tuple[str, str]:
    """Check that the candidate at ``u`` writes the same bytes twice and another at ``v``
    other bytes, and that the search's dimensions are the scenario's in order; the header
    and the row search.csv gives the candidate at ``u``."""
    first, again, other = (written(tmp_path / "a", scenario, u),
                           written(tmp_path / "b", scenario, u),
                           written(tmp_path / "c", scenario, v))
    assert first == again
    assert other != first  # the comparison can fail: another point, other bytes
    config = SearchConfig(levels=ONE_HUMAN, scenario=tuple(scenario), layout=3)
    _, dims = config.dimensions()
    assert [d.name for d in dims] == [name for name, _ in scenario]
    from rei.runtime.campaigns.search.driver import CandidateResult  # noqa: PLC0415

    built = candidate(tmp_path / "t", scenario, u)
    head, row = search_table([CandidateResult(built, None, 10.0)], dims).splitlines()
    return head, row


def test_same_row_same_bytes_and_the_table_lists_each_dimension(tmp_path: Path) -> None:
    scenario = [("phase", "0:20"), ("laser_noise.sigma", "0.01:0.2")]
    head, row = same_bytes_and_table_row(tmp_path, scenario, 0.4, 0.6)
    assert head.endswith("phase,laser_noise.sigma,problem")
    assert ",8,0.086," in row


@pytest.mark.slow
def test_a_real_search_runs_the_scenario_it_wrote_and_resumes_to_the_same_bytes(
        tmp_path: Path) -> None:
    """Two real runs (pybullet): each run injects the fault its mission was given and its
    human starts at the searched phase; run again, the search replays and changes nothing."""
    import json  # noqa: PLC0415
    import subprocess  # noqa: PLC0415
    import sys  # noqa: PLC0415

    from tests.search.test_search_runs import SAFETY_LIMIT, outputs, table  # noqa: PLC0415

    out = tmp_path / "out"
    argv = [sys.executable, "-m", "rei.runtime.commands", "search", "-o", str(out), "--layout", "5",
            *(a for k, v in ONE_HUMAN for a in (f"--{k.replace('_', '-')}", v)),
            "--phase", "0:20", "--fault-range", "laser_noise.sigma=0.01:0.1", "--budget", "2",
            "--batch", "2", "--workers", "1", "--strategy", "random", "--no-report", "-q"]
    first = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert first.returncode == 0, first.stderr  # the correct navigator passes both
    rows = table(out)
    assert len(rows) == 2 and all(r["verdict"] == "pass" for r in rows)
    for row in rows:
        summary = json.loads((out / "runs" / row["run_id"] / "summary.json").read_text())
        assert f"laser_noise sigma {row['laser_noise.sigma']}" in json.dumps(summary)
        room = (out / "candidates" / f"{row['candidate']}_0001.room").read_text()
        assert f" at {row['phase']}\n" in room
    before = outputs(out)
    again = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert again.returncode == 0, again.stderr
    assert outputs(out) == before
