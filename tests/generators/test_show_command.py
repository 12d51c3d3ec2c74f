"""`rei-gen show`: top-down pictures of rooms and missions, and contact sheets of many."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib.image
import pytest
from matplotlib.figure import Figure

from rei.generators.picture import draw_world, render_file, sheet_entries
from rei.generators.pipeline import build_request
from rei.lang.cli import main as rei_gen
from tests.conftest import EXAMPLES
from tests.generators.conftest import Write

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"


def texts_of(path: Path) -> list[str]:
    request, _ = build_request(path)
    fig = Figure()
    ax = fig.add_subplot()
    draw_world(ax, request.world, request.mission)
    return [t.get_text() for t in ax.texts] + [ax.get_title()]


def test_mission_picture_numbers_goals_and_names_everything() -> None:
    texts = texts_of(NAVIGATION)
    assert {"1", "2", "desk", "seat", "crate", "walker", "waffle"} <= set(texts)
    assert "mission to_the_elevator in room navigation" in texts
    assert {"0s", "8s", "20s", "28s"} <= set(texts)  # times at the trajectory's vertices


def test_goals_on_one_floor_share_a_label() -> None:
    texts = texts_of(EXAMPLES / "medium_sparse" / "medium_sparse.mission")
    assert "1,4" in texts  # the round trip starts and ends at the dock


def test_png_is_written_and_readable(tmp_path: Path) -> None:
    out = tmp_path / "room.png"
    assert rei_gen(["show", str(EXAMPLES / "small_dense" / "small_dense.room"), "-o",
                    str(out)]) == 0
    image = matplotlib.image.imread(out)
    assert image.shape[0] > 300 and image.shape[1] > image.shape[0]  # legend on the right


def test_svg_is_deterministic(tmp_path: Path) -> None:
    first = render_file(NAVIGATION, "svg")
    second = render_file(NAVIGATION, "svg")
    assert first.startswith(b"<?xml") and first == second
    assert b"<dc:date>" not in first


def test_png_is_deterministic() -> None:
    assert render_file(NAVIGATION, "png") == render_file(NAVIGATION, "png")


def test_contact_sheet_from_a_folder(tmp_path: Path) -> None:
    entries = sheet_entries(EXAMPLES)
    # Every example has a mission over its room, so the sheet shows the missions only.
    assert [e.title for e in entries] == ["high_error", "human_low_error", "human_near_dropout",
                                          "low_error", "medium_sparse", "navigation",
                                          "simple_wall", "small_dense"]
    out = tmp_path / "sheet.svg"
    assert rei_gen(["show", str(EXAMPLES), "-o", str(out)]) == 0
    assert out.read_bytes().startswith(b"<?xml")


def test_contact_sheet_from_an_index_csv(write: Write, tmp_path: Path) -> None:
    write("suite/rooms/a.room", (EXAMPLES / "simple_wall" / "simple_wall.room").read_text())
    write("suite/rooms/b.room", (EXAMPLES / "small_dense" / "small_dense.room").read_text())
    index = write("suite/index.csv", "name,room,mission,seed\n"
                                     "first,rooms/a.room,,1\nsecond,rooms/b.room,,2\n")
    assert [(e.title, e.path.name) for e in sheet_entries(index)] == [
        ("first", "a.room"), ("second", "b.room")]
    out = tmp_path / "sheet.png"
    assert rei_gen(["show", str(index), "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_invalid_room_on_a_sheet_reports_its_diagnostics(
    write: Write, tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    write("suite/good.room", (EXAMPLES / "simple_wall" / "simple_wall.room").read_text())
    bad = write("suite/bad.room", "room bad { floor a robot r : turtlebot3_waffle on b }")
    out = tmp_path / "sheet.png"
    assert rei_gen(["show", str(bad.parent), "-o", str(out)]) == 2
    assert str(bad) in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("name,message", [("room.jpg", "expected a file ending in .png or .svg")])
def test_unknown_picture_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, message: str,
) -> None:
    assert rei_gen(["show", str(NAVIGATION), "-o", str(tmp_path / name)]) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_picture_bytes_match_what_the_file_holds(tmp_path: Path) -> None:
    out = tmp_path / "nav.png"
    assert rei_gen(["show", str(NAVIGATION), "-o", str(out)]) == 0
    assert out.read_bytes() == render_file(NAVIGATION, "png")
    assert matplotlib.image.imread(io.BytesIO(out.read_bytes())).ndim == 3


def test_an_index_without_room_columns_is_a_located_error(
    write: Write, tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    index = write("index.csv", "name,seed\na,1\n")
    assert rei_gen(["show", str(index), "-o", str(tmp_path / "s.png")]) == 2
    assert f"{index}:1:1: INDEX-COLUMNS: expected a 'room' or 'mission' column, found name, seed" \
        in capsys.readouterr().err
