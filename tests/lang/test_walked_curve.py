"""TRAJ-CROSSES checks the curve a moving body walks (the animator's Catmull-Rom spline with
the body's radius), not the straight lines between its vertices (issue 14.8)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rei.lang.cli import main
from rei.lang.room.document import analyse_room
from rei.lang.room.spline import CatmullRom, vertex_times, walked_path
from rei.lang.source import SourceText
from rei.runtime.artifacts.world import Trajectory
from rei.runtime.simulation.animator import spline_of

L_CORRIDOR = """room l_corridor {
    grid g {
        "#####"
        "#..##"
        "##.##"
        "##.##"
        "##.##"
        "##.##"
        "##.##"
        "##.##"
        "##.##"
        "#####"
    }
    robot r : turtlebot3_waffle on g_8_2
    human h on g_1_1 trajectory {
        g_1_1 at 0
        g_1_2 at TURN
        g_8_2 at 8
    }
}
"""


def check(text: str) -> list[tuple[str, int, str]]:
    doc = analyse_room(SourceText("l.room", text))
    return [(d.rule, d.span.line, d.message) for d in doc.diagnostics]


def test_the_issue_l_corridor_is_refused_where_the_spline_overshoots() -> None:
    # Vertices at 0, 1 and 8 s: every straight way stays in the corridor, but the curve
    # keeps half its speed into the wall after the corner and swings ~0.5 m wide.
    found = check(L_CORRIDOR.replace("TURN", "1"))
    crossing = [f for f in found if f[0] == "TRAJ-CROSSES"]
    assert len(crossing) == 1, found
    rule, line, message = crossing[0]
    assert line == L_CORRIDOR.splitlines().index("        g_1_2 at TURN") + 1
    assert "from 'g_1_2' to 'g_8_2'" in message
    assert "into the wall" in message and "0.25 m round" in message
    depth = float(message.split(" m into ")[0].rsplit(" ", 1)[1])
    # the centre swings 0.52 m past the corridor's axis; the corridor's half width is 0.5 m
    assert 0.2 < depth < 0.35


def test_a_vertex_after_the_corner_keeps_the_curve_in_the_corridor() -> None:
    # The fix a user makes: a vertex one tile after the corner shortens the swing.
    text = L_CORRIDOR.replace("        g_8_2 at 8\n", "        g_2_2 at 2\n        g_8_2 at 8\n")
    assert [f for f in check(text.replace("TURN", "1")) if f[0] == "TRAJ-CROSSES"] == []


def test_the_check_walks_the_animators_curve() -> None:
    points, loop = [(0.0, 0.0), (1.0, 0.0), (1.0, -7.0)], False
    times, pts = vertex_times(points, [0.0, 1.0, 8.0], None, loop)
    ours = CatmullRom(np.array(times), np.array(pts), loop)
    animator = spline_of(Trajectory(loop, tuple((t, x, y) for t, (x, y) in
                                                zip(times, pts, strict=True))))
    t, path = walked_path(ours, 0.02)
    assert np.array_equal(path, animator.positions(t))
    assert np.max(np.linalg.norm(np.diff(path, axis=0), axis=1)) <= 0.02 + 1e-9
    assert path[:, 0].max() > 1.5  # the overshoot the check must see


def test_every_bundled_example_passes(tmp_path: Path) -> None:
    rooms = sorted((Path(__file__).parents[2] / "examples").rglob("*.room"))
    assert rooms
    for room in rooms:
        found = [d for d in analyse_room(SourceText(str(room), room.read_text())).diagnostics
                 if d.is_error]
        assert found == [], (room, found)


def test_generated_rooms_walk_only_accepted_curves(tmp_path: Path) -> None:
    for preset in ("small", "medium", "large"):
        out = tmp_path / preset
        assert main(["rooms", "--preset", preset, "--strategy", "random", "--count", "6",
                     "--seed", "11", "-o", str(out), "--quiet"]) == 0
        rooms = sorted(out.glob("*.room"))
        assert len(rooms) == 6
        for room in rooms:
            doc = analyse_room(SourceText(str(room), room.read_text()))
            assert [d for d in doc.diagnostics if d.rule == "TRAJ-CROSSES"] == [], room
