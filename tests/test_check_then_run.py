"""Whatever `rei-gen check` accepts must run (issue 13.3): a property test over mutants.

Each example is a tiny room, mission and .vepl in the shape of the examples (a grid, a
robot, an object, a walking human; the navigation example's queries and events), mutated
where the checker's limits are: trajectory times and totals (down to nanoseconds), loops,
behaviours, tiles, goals, and event patterns with chains of {n} {+} {*} [ms], NOT, OR, AND,
and conditions of up to 1,200 terms. Every file must check without raising; a room and
mission the checker accepts are generated for every target (`rei-gen generate --target
all`), and a short real run (pybullet, reference controller, monitored by the automata of
the mutated .vepl when it was accepted, else the default's) must end without raising
anything, not even a REI error, and without an "error" outcome.

The budget is bounded: hypothesis is derandomized (the same examples every time) with a
small number of examples, each a run of 0.5 simulated seconds.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from rei.lang.cli import main as rei_gen
from rei.lang.errors import ReiError
from rei.lang.workspace import Workspace
from rei.runtime.runs.session import run_into

ROWS = 2
COLS = 4
FLOORS = [f"g_{r}_{c}" for r in range(1, ROWS + 1) for c in range(1, COLS + 1)]
WALKABLE = st.sampled_from(["0.3", "1", "2.5", "40"])
EDGES = st.sampled_from(["0", "1e-9", "1e-6", "0.004", "0.01", "0.02", "1e5"])
TIMES = st.one_of(WALKABLE, WALKABLE, WALKABLE, EDGES)
"""Seconds between vertices (or a total): mostly walkable, a quarter at the edges."""


@st.composite
def rooms(draw: st.DrawFn) -> str:
    tile = draw(st.sampled_from(["1.0", "1.5", "3", "0.5"]))
    robot = draw(st.sampled_from(FLOORS[:2]))
    crate = draw(st.sampled_from(["box", "table", "chair", "pillar"]))
    crate_at = draw(st.sampled_from(FLOORS[-2:]))
    free = [f for f in FLOORS if f not in (robot, crate_at)]
    walker_path = draw(st.lists(st.sampled_from(free), min_size=2, max_size=5))
    loop = draw(st.sampled_from(["", " loop", " stop"]))
    behaviour = draw(st.sampled_from(["", " behaviour yielding", " behaviour social"]))
    if draw(st.booleans()):
        total = draw(TIMES.filter(lambda t: float(t) > 0))
        options, vertices = f" total {total}", [f"        {f}" for f in walker_path]
    else:
        steps = draw(st.lists(TIMES, min_size=len(walker_path), max_size=len(walker_path)))
        times = [sum(float(x) for x in steps[:i + 1]) - float(steps[0])
                 for i in range(len(steps))]
        options = ""
        vertices = [f"        {f} at {t!r}" for f, t in zip(walker_path, times, strict=True)]
    return "\n".join([
        "room tiny {", f"    tile {tile}", "    grid g {", '        "######"',
        '        "#....#"', '        "#....#"', '        "######"', "    }",
        f"    robot bot : turtlebot3_waffle on {robot} heading 0",
        f"    object crate : {crate} on {crate_at}",
        f"    human walker on {walker_path[0]} trajectory{options}{loop} {{",
        *vertices, f"    }}{behaviour}", "}", ""])


@st.composite
def missions(draw: st.DrawFn) -> str:
    goals = draw(st.lists(st.sampled_from(FLOORS), min_size=1, max_size=3))
    timeout = draw(st.sampled_from(["0.001", "1", "30", "1e6"]))
    tolerance = draw(st.sampled_from(["0.01", "0.3", "5"]))
    lines = [f"    goal {g} at {g} tolerance {tolerance} timeout {timeout}"
             for g in dict.fromkeys(["g_1_1", *goals])]
    return "\n".join(['mission tiny in "tiny.room" {', "    time_limit 60", *lines, "}", ""])


def patterns(depth: int = 2) -> st.SearchStrategy[str]:
    suffix = st.sampled_from(["{+}", "{*}", "{2}", "{100}", "[500]", "[1e9]"])
    suffixes = st.one_of(st.lists(suffix, max_size=2), st.lists(suffix, max_size=2),
                         st.lists(suffix, max_size=12)).map("".join)
    atom = st.builds(lambda name, s: name + s, st.sampled_from(["a", "b"]), suffixes)
    if depth == 0:
        return atom
    inner = patterns(depth - 1)
    return st.one_of(
        atom,
        st.builds(lambda x, op, y, s: f"({x} {op} {y}){s}", inner,
                  st.sampled_from(["->", "OR", "AND"]), inner, suffixes),
        st.builds(lambda x, y, s: f"({x} -> NOT {y})[1000]{s}", inner, inner, suffixes))


@st.composite
def vepls(draw: st.DrawFn) -> str:
    terms = draw(st.sampled_from([1, 2, 50, 201, 900, 1200]))
    condition = " + ".join(["0.001"] * terms)
    pattern = draw(patterns())
    context = draw(st.sampled_from(["immediate", "strict immediate", "chronicle"]))
    return f"""specification mutant
parameters {{ eps_close = 0.25 eps_collision = 0.02 }}
query near() {{ laser_min < {condition} }}
query close(o: object) {{ distance(robot, o) < eps_close }}
queryEvent a() as near found
queryEvent b(o) as close(o) found
complexEvent pattern(){{ as {pattern} context {context} }}
signal SIG_PATTERN on pattern utility -1
requirement NO_PATTERN "the pattern never happens" {{ never SIG_PATTERN }}
"""



def _errors(workspace: Workspace, path: Path) -> list[str]:
    """Checking never raises: every problem is a diagnostic."""
    return [str(d) for d in workspace.check(path) if d.is_error]


def _run(mission: Path, out: Path, vepl: Path | None) -> None:
    """Stricter than "only REI errors": every file of this run was accepted by the checker,
    so even a located RunError would mean the checker accepted what cannot run."""
    try:
        summary, _ = run_into(mission, out, duration=0.5, vepl=vepl, watchdog=None)
    except ReiError as exc:
        pytest.fail(f"the checker accepted what the runtime refused: {exc}")
    assert summary.outcome != "error", summary.reason


VALID_ROOM = """room tiny {
    grid g {
        "######"
        "#....#"
        "#....#"
        "######"
    }
    robot bot : turtlebot3_waffle on g_1_1 heading 0
    human walker on g_2_3 trajectory loop {
        g_2_3 at 0
        g_2_4 at 2
    }
}
"""
VALID_MISSION = """mission tiny in "tiny.room" {
    goal start at g_1_1 timeout 10
    goal there at g_1_2 timeout 30
}
"""


@pytest.mark.slow
@settings(max_examples=24, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(room=rooms(), mission=missions(), vepl=vepls())
def test_what_check_accepts_generates_and_runs(tmp_path_factory: pytest.TempPathFactory,
                                               room: str, mission: str, vepl: str) -> None:
    folder = tmp_path_factory.mktemp("mutant")
    (folder / "tiny.room").write_text(room, encoding="utf-8")
    (folder / "tiny.mission").write_text(mission, encoding="utf-8")
    (folder / "mutant.vepl").write_text(vepl, encoding="utf-8")
    workspace = Workspace()
    room_ok = not _errors(workspace, folder / "tiny.room")
    mission_ok = not _errors(workspace, folder / "tiny.mission")
    vepl_ok = not _errors(workspace, folder / "mutant.vepl")
    event(f"room and mission {'accepted' if room_ok and mission_ok else 'refused'}")
    event(f"vepl {'accepted' if vepl_ok else 'refused'}")
    if not (room_ok and mission_ok):
        # Run the accepted parts on the valid scene.
        folder = tmp_path_factory.mktemp("valid")
        (folder / "tiny.room").write_text(VALID_ROOM, encoding="utf-8")
        (folder / "tiny.mission").write_text(VALID_MISSION, encoding="utf-8")
        (folder / "mutant.vepl").write_text(vepl, encoding="utf-8")
    assert rei_gen(["generate", str(folder / "tiny.mission"), "--target", "all",
                    "-o", str(folder / "generated")]) == 0
    if vepl_ok:
        assert rei_gen(["generate", str(folder / "mutant.vepl"), "--target", "rx",
                        "-o", str(folder / "automata")]) == 0
    _run(folder / "tiny.mission", folder / "run", folder / "mutant.vepl" if vepl_ok else None)
