"""The graph traversal of thesis 6.2.1 against coordinates computed by hand.

The robot's floor is the origin; a floor's RIGHT neighbour is one tile further along +x, its
TOP neighbour one tile along +y (a grid's first row is its top, so rows count downwards).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from rei.generators.concrete import ConcreteWorld, concretise_room
from rei.lang.workspace import Workspace
from tests.generators.conftest import Write


def world_of(write: Write, text: str, name: str = "t.room") -> ConcreteWorld:
    path: Path = write(name, text)
    doc = Workspace().room(path)
    assert [str(d) for d in doc.diagnostics if d.is_error] == []
    return concretise_room(doc)


def coordinates(world: ConcreteWorld) -> dict[str, tuple[float, float]]:
    return {b.name: (b.x, b.y) for b in world.floors + world.walls}


def test_straight_corridor_of_explicit_floors(write: Write) -> None:
    world = world_of(write, """room straight {
        tile 0.5
        floor a { right b }
        floor b { right c }
        floor c { top n  right e }
        wall n  wall e
        robot r : turtlebot3_waffle on b
    }""")
    # The robot stands on b: b is the origin, a is one half-metre tile to the left.
    assert coordinates(world) == {"a": (-0.5, 0.0), "b": (0.0, 0.0), "c": (0.5, 0.0),
                                  "n": (0.5, 0.5), "e": (1.0, 0.0)}
    assert world.robot.pose.x == 0.0 and world.robot.pose.y == 0.0


def test_l_shaped_room_from_a_grid(write: Write) -> None:
    world = world_of(write, """room ell {
        grid g {
            "#####"
            "#...#"
            "#.###"
            "#.#  "
            "###  "
        }
        robot r : turtlebot3_waffle on g_3_1 heading 90
    }""")
    floors = {b.name: (b.x, b.y) for b in world.floors}
    # The robot's floor g_3_1 (row 3, column 1) is the origin; row 1 is two tiles above it.
    assert floors == {"g_1_1": (0.0, 2.0), "g_1_2": (1.0, 2.0), "g_1_3": (2.0, 2.0),
                      "g_2_1": (0.0, 1.0), "g_3_1": (0.0, 0.0)}
    walls = coordinates(world)
    assert walls["g_0_0"] == (-1.0, 3.0)  # a corner that touches no floor
    assert walls["g_4_2"] == (1.0, -1.0)
    assert walls["g_2_2"] == (1.0, 1.0)   # the inner corner of the L
    assert world.floor_at(0.0, 2.0) == "g_1_1"
    assert world.floor_at(1.0, 1.0) is None  # a wall, not a floor
    assert world.floor_at(3.0, 0.0) is None  # empty cells of the grid are outside the room


def test_room_with_an_inner_wall_block_and_an_empty_cell(write: Write) -> None:
    world = world_of(write, """room holes {
        grid g {
            legend { "S" = floor start }
            "#####"
            "#S..#"
            "#.#.#"
            "#.. #"
            "#####"
        }
        robot r : turtlebot3_waffle on start
    }""")
    floors = {b.name: (b.x, b.y) for b in world.floors}
    assert floors == {"start": (0.0, 0.0), "g_1_2": (1.0, 0.0), "g_1_3": (2.0, 0.0),
                      "g_2_1": (0.0, -1.0), "g_2_3": (2.0, -1.0),
                      "g_3_1": (0.0, -2.0), "g_3_2": (1.0, -2.0)}
    assert coordinates(world)["g_2_2"] == (1.0, -1.0)  # the inner wall block
    # The empty cell (row 3, column 3) is neither floor nor wall: nothing is placed there.
    assert world.floor_at(2.0, -2.0) is None
    assert (2.0, -2.0) not in set(coordinates(world).values())
    assert world.floor_at(1.4, -1.6) == "g_3_2"  # inside a tile, not only at its centre


def test_explicit_floors_attached_to_a_grid(write: Write) -> None:
    world = world_of(write, """room mixed {
        tile 2.0
        grid lab {
            "####"
            "#..."
            "####"
        }
        floor annex { left lab_1_3  right door }
        floor door { top wall_t }
        wall wall_t
        robot r : turtlebot3_waffle on lab_1_1
        object crate : box on door
    }""")
    coords = coordinates(world)
    # The grid's open right edge (lab_1_3) continues into the explicit floors, 2 m apart.
    assert coords["lab_1_1"] == (0.0, 0.0) and coords["lab_1_3"] == (4.0, 0.0)
    assert coords["lab_0_3"] == (4.0, 2.0)
    assert coords["annex"] == (6.0, 0.0) and coords["door"] == (8.0, 0.0)
    assert coords["wall_t"] == (8.0, 2.0)
    crate = next(o for o in world.objects if o.name == "crate")
    assert (crate.pose.x, crate.pose.y, crate.floor) == (8.0, 0.0, "door")


@pytest.mark.parametrize("heading,expected_yaw", [(0, 0.0), (90, 1.5707963267948966)])
def test_robot_heading_becomes_yaw(write: Write, heading: int, expected_yaw: float) -> None:
    world = world_of(write, f"""room h {{
        floor a {{ right b }}
        floor b
        robot r : turtlebot3_waffle on a heading {heading}
    }}""")
    assert world.robot.pose.yaw == pytest.approx(expected_yaw)


@st.composite
def grid_rooms(draw: st.DrawFn) -> tuple[list[str], tuple[int, int], float]:
    """A walled grid with random inner walls and holes, and a robot on one of its floors."""
    rows = draw(st.integers(2, 6))
    cols = draw(st.integers(2, 7))
    inner = [[draw(st.sampled_from("...#_")) for _ in range(cols)] for _ in range(rows)]
    floors = [(r, c) for r in range(rows) for c in range(cols) if inner[r][c] == "."]
    assume(floors)
    robot = draw(st.sampled_from(floors))
    text = ["#" * (cols + 2)] + ["#" + "".join(r) + "#" for r in inner] + ["#" * (cols + 2)]
    tile = draw(st.sampled_from([0.5, 1.0, 1.25]))
    return text, (robot[0] + 1, robot[1] + 1), tile


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much])
@given(grid_rooms())
def test_traversal_puts_every_grid_floor_where_the_grid_draws_it(
    write: Write, room: tuple[list[str], tuple[int, int], float],
) -> None:
    rows, (r0, c0), tile = room
    body = "\n".join(f'"{row}"' for row in rows)
    path = write("p.room", f"room p {{ tile {tile} grid g {{ {body} }} "
                           f"robot r : turtlebot3_waffle on g_{r0}_{c0} }}")
    doc = Workspace().room(path)
    rules = {d.rule for d in doc.diagnostics if d.is_error}
    assume(not rules)  # grids whose floors fall apart are rejected by the checks, not placed
    world = concretise_room(doc)
    for block in world.floors + world.walls:
        _, r, c = block.name.split("_")
        # Column to the right is +x, row downwards is -y, measured from the robot's cell.
        assert (block.x, block.y) == ((int(c) - c0) * tile, -(int(r) - r0) * tile)
    for block in world.floors:
        assert world.floor_at(block.x + 0.49 * tile, block.y - 0.49 * tile) == block.name
