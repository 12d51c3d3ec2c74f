"""Regression tests of issue 13 (points 3, 4, 5, 8, 9), each on its minimal reproducer: what
`rei-gen check` accepts must generate and run, no input hangs, exhausts memory or crashes
the checker, no check is quadratic, and what a message quotes from the input is shown,
never interpreted."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from types import MappingProxyType

import pytest

from rei.generators.targets.rx import render_module
from rei.lang.errors import Diagnostic, Span, printable
from rei.lang.room.layout import compute_layout
from rei.lang.room.model import FloorDecl, NameRef, PlacedObject, Room, Side
from rei.lang.source import SourceText, read_bounded
from rei.lang.vepl import analyse_vepl
from rei.lang.workspace import Workspace
from rei.runtime.artifacts.world import Trajectory
from rei.runtime.errors import RunError
from rei.runtime.observation.automata.records import load_generated
from rei.runtime.simulation.animator.bodies import spline_of

GOALS = "  goal a at x timeout 1\n  goal b at y timeout 1\n}\n"
VEPL = """specification s
query near() {{ laser_min < {condition} }}
queryEvent a() as near found
queryEvent b() as near lost
complexEvent c(){{ as (a -> b){suffixes} }}
signal S on c utility 1
"""


def check(path: Path) -> list[tuple[str, int, int, str]]:
    return [(d.rule, d.span.line, d.span.col, d.message) for d in Workspace().check(path)]


def rules(path: Path) -> list[str]:
    return [d[0] for d in check(path)]


def cli(*args: str | Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """`rei-gen` in a child process; the timeout only guards the test run against a hang."""
    return subprocess.run([sys.executable, "-m", "rei.lang.cli", *map(str, args)],
                          capture_output=True, text=True, check=False, timeout=timeout)


# ---- 3. what the checker accepts must run -----------------------------------------------

def test_200_plus_suffixes_are_a_located_limit_not_a_syntax_error_at_run_time() -> None:
    doc = analyse_vepl(SourceText("p.vepl", VEPL.format(condition="1", suffixes="{+}" * 200)))
    [d] = doc.diagnostics
    # The seventh {+} makes the automaton of (a -> b) outgrow the limit (638 parts > 500).
    assert (d.rule, d.span.line, d.span.col) == ("VEPL-LIMIT", 5, 30 + 3 * 6)


def test_a_201_term_sum_generates_and_loads(tmp_path: Path) -> None:
    text = VEPL.format(condition=" + ".join(["0.001"] * 201), suffixes="")
    doc = analyse_vepl(SourceText("sum.vepl", text))
    assert doc.ok and doc.spec is not None
    module = tmp_path / "automata.py"
    module.write_text(render_module(doc.spec, "sum.vepl"), encoding="utf-8")
    assert load_generated(module).SPEC_NAME == "s"


def test_a_condition_too_long_to_compile_is_a_located_limit() -> None:
    text = VEPL.format(condition=" + ".join(["1"] * 1500), suffixes="")
    [d] = analyse_vepl(SourceText("long.vepl", text)).diagnostics
    assert (d.rule, d.span.line) == ("VEPL-LIMIT", 2)


@pytest.mark.parametrize("trajectory", ["{ c at 0 d at 1e-9 }", "total 1e-6 { c d c }",
                                        "total 0.2 { c d b a }", "total 4 { c d d }",
                                        # found by test_check_then_run: TRAJ-CROSSES sampled
                                        # the spline of a nanosecond segment (56 GiB)
                                        "{ c at 0 c at 0.3 d at 0.30000000099999996 }"])
def test_trajectories_the_animator_cannot_walk_are_refused(write, trajectory: str  # type: ignore[no-untyped-def]
                                                          ) -> None:
    path = write("fast.room", "room fast {\n  floor a { right b }\n  floor b { right c }\n"
                              "  floor c { right d }\n  floor d\n"
                              "  robot r : turtlebot3_waffle on a\n"
                              f"  human h on c trajectory {trajectory}\n}}\n")
    found = check(path)
    assert found and {r for r, *_ in found} == {"TRAJ-SPEED"}, found
    assert all(line == 7 for _, line, _, _ in found)


def test_a_loop_that_ends_where_it_starts_walks(write) -> None:  # type: ignore[no-untyped-def]
    # Its way back has no length: it used to get a zero-length last segment (and crash).
    from rei.generators.concrete.build import concretise_room

    path = write("loop.room", "room loop {\n  floor a { right b }\n  floor b { right c }\n"
                              "  floor c\n  robot r : turtlebot3_waffle on a\n"
                              "  human h on b trajectory loop { b at 0 c at 2 b at 4 }\n}\n")
    assert check(path) == []
    world = concretise_room(Workspace().room(path))
    [human] = [o for o in world.objects if o.trajectory is not None]
    assert human.trajectory is not None
    times = [p.t for p in human.trajectory.points]
    assert times == sorted(set(times))
    spline_of(Trajectory(True, tuple((p.t, p.x, p.y) for p in human.trajectory.points)))


def test_the_animator_names_a_body_it_cannot_animate() -> None:
    with pytest.raises(RunError, match="'walker'.*increasing times"):
        spline_of(Trajectory(False, ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))), "walker")


# ---- 4. inputs that hang or exhaust memory ------------------------------------------------

@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_dev_zero_as_room_import_or_catalogue_is_refused_unread(write) -> None:  # type: ignore[no-untyped-def]
    mission = write("z.mission", 'mission m in "/dev/zero" {\n' + GOALS)
    [(rule, _, _, message)] = check(mission)
    assert rule == "MISSION-ROOM" and "expected a .room file" in message
    room = write("z.room", 'room r {\n  catalogue "/dev/zero"\n  floor a\n'
                           "  robot x : turtlebot3_waffle on a\n}\n")
    found = check(room)
    assert ("INPUT-READ", 1, 1, "expected a regular file, found a character device") in found
    assert "CATALOGUE-FILE" in [r for r, *_ in found]


def test_a_fifo_never_blocks_the_command_line(tmp_path: Path, write) -> None:  # type: ignore[no-untyped-def]
    os.mkfifo(tmp_path / "pipe.room")
    mission = write("p.mission", 'mission m in "pipe.room" {\n' + GOALS)
    proc = cli("check", tmp_path / "pipe.room", mission)
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout.count("expected a regular file, found a FIFO (named pipe)") == 2


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs Linux /proc")
def test_the_read_is_bounded_whatever_stat_says() -> None:
    # /proc files are regular files whose stat size is 0 whatever they hold.
    maps = Path("/proc/self/maps")
    assert maps.stat().st_size == 0
    data = read_bounded(maps, limit=100)
    assert isinstance(data, bytes) and len(data) == 101  # limit + 1: enough to say "too big"


# ---- 5. checker crashes ------------------------------------------------------------------

def test_a_symlink_loop_is_located_without_a_traceback(tmp_path: Path, write) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "a.room").symlink_to(tmp_path / "b.room")
    (tmp_path / "b.room").symlink_to(tmp_path / "a.room")
    mission = write("m.mission", 'mission m in "a.room" {\n' + GOALS)
    proc = cli("check", tmp_path / "a.room", mission)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr + proc.stdout
    assert proc.stdout.count("loop of symbolic links") == 2


def test_a_thousand_flat_suffixes_are_a_located_limit(write) -> None:  # type: ignore[no-untyped-def]
    for suffix in ("{+}", "{*}", "{2}", "[1000]"):
        path = write("many.vepl", VEPL.format(condition="1", suffixes=suffix * 1000))
        [(rule, line, _, _)] = check(path)
        assert (rule, line) == ("VEPL-LIMIT", 5)


def test_a_deeply_nested_catalogue_is_located(write) -> None:  # type: ignore[no-untyped-def]
    # tomllib reads nested arrays by recursion: this was a RecursionError traceback.
    path = write("deep.toml", "# nested\na = " + "[" * 5000 + "]" * 5000 + "\n")
    [(rule, line, col, message)] = check(path)
    assert (rule, line, col) == ("CATALOGUE-SYNTAX", 2, 5 + 4999)
    assert "5000 levels" in message


# ---- 8. no quadratic check ---------------------------------------------------------------

def _chain_room(n: int) -> Room:
    """A robot alone on its floor and a chain of ``n`` floors no link reaches, plus ``n // 4``
    floors alone (a component each), built directly: the parser is not what is measured."""
    span = Span.point("chain.room")
    floors = {"start": FloorDecl("start", "floor_tile", span, ())}
    neighbours: dict[str, dict[Side, str]] = {"start": {}}
    for i in range(n):
        name, nxt = f"f{i}", f"f{i + 1}"
        links = ((Side.RIGHT, NameRef(nxt, span)),) if i + 1 < n else ()
        floors[name] = FloorDecl(name, "floor_tile", span, links)
        neighbours[name] = {Side.RIGHT: nxt} if i + 1 < n else {}
        if i:
            neighbours[name][Side.LEFT] = f"f{i - 1}"
    for i in range(n // 4):
        floors[f"alone{i}"] = FloorDecl(f"alone{i}", "floor_tile", span, ())
        neighbours[f"alone{i}"] = {}
    robot = PlacedObject("bot", "robot", "turtlebot3_waffle", span, NameRef("start", span),
                         None, None, span)
    return Room("chain", "chain.room", span, 1.0, None, None, MappingProxyType(floors),
                MappingProxyType({}), (robot,), (), MappingProxyType(neighbours))


def test_a_40k_floor_disconnected_chain_is_checked() -> None:
    n = 40_000
    _, diagnostics = compute_layout(_chain_room(n))
    disconnected = [d for d in diagnostics if d.rule == "FLOOR-DISCONNECTED"]
    assert len(disconnected) == 1 + n // 4
    assert f"found {n} floor(s) starting with 'f0'" in disconnected[0].message
    assert "starting with 'alone0'" in disconnected[1].message


# ---- 9. smaller points -------------------------------------------------------------------

def test_syntax_depth_points_at_the_nesting(write) -> None:  # type: ignore[no-untyped-def]
    text = ("specification deep\n\nquery q() {\n  laser_min < 1 and\n  "
            + "(" * 3000 + " laser_min < 1 " + ")" * 3000 + "\n}\n")
    [(rule, line, col, message)] = check(write("deep.vepl", text))
    assert (rule, line, col) == ("SYNTAX-DEPTH", 5, 3 + 2999)
    assert "3001 levels" in message  # the query's { and 3000 '('


def test_control_characters_from_the_input_are_escaped(write) -> None:  # type: ignore[no-untyped-def]
    path = write("ansi.room", "room r {\n  floor a\n}\n\x1b[31mred\u202e")
    proc = cli("check", path)
    assert "\x1b" not in proc.stdout and "\u202e" not in proc.stdout
    assert "found '\\x1b[31mred\\u202e'" in proc.stdout
    assert printable("tab\there\x9b") == "tab\\x09here\\x9b"
    assert Diagnostic(Span.point("f"), "X", "a\x07b").message == "a\\x07b"


def test_importing_a_file_that_is_not_a_room_does_not_echo_it(write) -> None:  # type: ignore[no-untyped-def]
    write("secrets.txt", "password=hunter2 and more text\n")
    write("odd.room", "password=hunter2 and more text\n")
    for name in ("secrets.txt", "odd.room"):
        mission = write("m.mission", f'mission m in "{name}" {{\n' + GOALS)
        [(rule, _, _, message)] = check(mission)
        assert rule == "MISSION-ROOM" and "hunter2" not in message and "password" not in message


def test_an_empty_room_name_says_so(write) -> None:  # type: ignore[no-untyped-def]
    [(rule, line, col, message)] = check(write("e.mission", 'mission m in "" {\n' + GOALS))
    assert (rule, line, col) == ("MISSION-ROOM", 1, 14)
    assert message == "expected a file name, found an empty string"
