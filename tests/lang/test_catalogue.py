"""The default catalogue, users' own catalogues, and their errors."""

from __future__ import annotations

import math

import pytest

from rei.catalogue import Box, CatalogueError, Cylinder, default_catalogue, load_catalogue
from rei.lang.workspace import Workspace


def test_default_catalogue_has_the_issue_types() -> None:
    cat = default_catalogue()
    assert {"floor_tile", "wall", "table", "chair", "shelf", "box", "pillar", "human",
            "turtlebot3_waffle"} <= set(cat.names())


def test_turtlebot3_waffle_published_figures() -> None:
    tb3 = default_catalogue().get("turtlebot3_waffle")
    assert tb3 is not None and tb3.kind == "robot"
    assert tb3.footprint == Box(0.281, 0.306)
    assert tb3.drive is not None and tb3.drive.max_linear == 0.26 and tb3.drive.max_angular == 1.82
    # ROBOTIS's Nav2 parameters for the waffle (DWB acc_lim_x / acc_lim_theta and decel)
    assert (tb3.drive.max_linear_accel, tb3.drive.max_linear_decel,
            tb3.drive.max_angular_accel, tb3.drive.max_angular_decel) == (2.5, 2.5, 3.2, 3.2)
    assert tb3.laser is not None
    assert (tb3.laser.beams, tb3.laser.min_range, tb3.laser.max_range) == (360, 0.12, 3.5)
    assert math.isclose(tb3.laser.fov, 2 * math.pi)


def test_inertia_is_computed_from_a_uniform_solid() -> None:
    human = default_catalogue().get("human")
    assert human is not None and human.footprint == Cylinder(0.25)
    ixx, iyy, izz = human.inertia
    assert math.isclose(izz, 75.0 * 0.25 ** 2 / 2)
    assert math.isclose(ixx, 75.0 * (3 * 0.25 ** 2 + 1.75 ** 2) / 12) and ixx == iyy


def test_user_catalogue_adds_and_overrides(write) -> None:  # type: ignore[no-untyped-def]
    path = write("mine.toml", """
[types.table]
kind = "static"
footprint = { shape = "cylinder", radius = 0.4 }
height = 0.7
mass = 12.0

[types.crate]
kind = "static"
footprint = { shape = "polygon", points = [[-0.2, -0.2], [0.2, -0.2], [0.0, 0.25]] }
height = 0.5
mass = 3.0
inertia = [0.1, 0.1, 0.1]
""")
    cat = load_catalogue(path)
    assert cat.get("table").footprint == Cylinder(0.4)  # type: ignore[union-attr]
    assert cat.get("crate").inertia == (0.1, 0.1, 0.1)  # type: ignore[union-attr]
    assert cat.get("chair") == default_catalogue().get("chair")


def test_room_uses_its_own_catalogue(write) -> None:  # type: ignore[no-untyped-def]
    write("types.toml", """
[types.crate]
kind = "static"
footprint = { shape = "box", size = [0.5, 0.5] }
height = 0.5
mass = 3.0
""")
    path = write("r.room", """room r {
    catalogue "types.toml"
    floor a { right b } floor b
    robot bot : turtlebot3_waffle on a
    object c : crate on b
}""")
    assert Workspace().check(path) == []


_ROBOT = ('kind = "robot"\nfootprint = { shape = "box", size = [0.3, 0.3] }\nheight = 1\n'
          'mass = 1\nlaser = { beams = 8, min_range = 0.1, max_range = 3.0, rate = 5 }\n'
          'drive.max_linear = 0.3\ndrive.max_angular = 1.0\ndrive.wheel_separation = 0.3\n'
          'drive.wheel_radius = 0.03\ndrive.')


def test_a_drive_without_accelerations_takes_nav2s_defaults(write) -> None:  # type: ignore[no-untyped-def]
    path = write("old.toml", "[types.t]\n" + _ROBOT.removesuffix("drive.") + "\n")
    drive = load_catalogue(path).get("t").drive  # type: ignore[union-attr]
    assert drive is not None
    assert (drive.max_linear_accel, drive.max_linear_decel, drive.max_angular_accel,
            drive.max_angular_decel) == (2.5, 2.5, 3.2, 3.2)


@pytest.mark.parametrize("body,needle", [
    ('kind = "robotic"',
     "types.t.kind: expected one of floor, wall, static, dynamic, human, robot"),
    ('kind = "static"\nfootprint = { shape = "box", size = [0.5] }\nheight = 1\nmass = 1',
     "types.t.footprint.size: expected a list of 2 numbers"),
    ('kind = "static"\nfootprint = { shape = "box", size = [0.5, 0.5] }\nheight = nan\nmass = 1',
     "types.t.height: expected a finite number > 0"),
    ('kind = "human"\nfootprint = { shape = "cylinder", radius = 0.2 }\nheight = 1\nmass = 0',
     "types.t.mass: expected a positive mass for a human type"),
    ('kind = "static"\nfootprint = { shape = "box", size = [0.5, 0.5] }\nheight = 1\nmas = 1',
     "types.t.mas: expected a known field; did you mean 'mass'?"),
    ('kind = "robot"\nfootprint = { shape = "box", size = [0.3, 0.3] }\nheight = 1\nmass = 1',
     "types.t.drive: expected a table"),
    (_ROBOT + "max_linear_accel = 0.0\n", "types.t.drive.max_linear_accel: expected a finite "
     "number > 0 and <= 1000, found 0.0"),
    (_ROBOT + "max_angular_decel = inf\n", "types.t.drive.max_angular_decel: expected a finite "
     "number > 0"),
    (_ROBOT + "max_angular_decl = 3.2\n", "types.t.drive.max_angular_decl: expected a known "
     "field; did you mean 'max_angular_decel'"),
])
def test_catalogue_errors_name_the_field(write, body: str, needle: str) -> None:  # type: ignore[no-untyped-def]
    path = write("bad.toml", f"# header\n\n[types.t]\n{body}\n")
    with pytest.raises(CatalogueError) as info:
        load_catalogue(path)
    messages = [str(d) for d in info.value.diagnostics]
    assert any(needle in m for m in messages), messages
    assert all(d.span.line == 3 for d in info.value.diagnostics)
