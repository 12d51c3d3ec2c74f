"""`rei-gen generate`: every target, deterministic bytes, and failures that leave nothing behind."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import jinja2
import pytest

from rei.generators.errors import GenerationError
from rei.generators.output import write_tree
from rei.generators.pipeline import build_request, render_targets
from rei.generators.targets import available_targets
from rei.generators.targets.gazebo import TARGET as GAZEBO
from rei.generators.targets.mission import MissionTarget
from rei.lang.cli import main as rei_gen
from tests.conftest import EXAMPLES
from tests.generators.conftest import Write

NAVIGATION = EXAMPLES / "navigation" / "navigation.mission"


def snapshot(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_all_targets_write_into_their_own_folders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    assert rei_gen(["generate", str(NAVIGATION), "--target", "all", "-o", str(tmp_path)]) == 0
    folders = {p.name for p in tmp_path.iterdir()}
    accepting = {n for n, t in available_targets().items() if ".mission" in t.accepts}
    assert folders == accepting
    assert (tmp_path / "mission" / "mission.xml").is_file()
    # run.json names the mission it runs relative to itself, inside the launch folder.
    run = json.loads((tmp_path / "launch" / "run.json").read_text())
    assert (tmp_path / "launch" / run["mission"]).is_file()
    assert "wrote" in capsys.readouterr().err


def test_one_target_writes_into_the_folder_itself(tmp_path: Path) -> None:
    assert rei_gen(["generate", str(NAVIGATION), "-t", "mission", "-o", str(tmp_path)]) == 0
    assert sorted(snapshot(tmp_path)) == ["mission.xml"]


def test_same_input_gives_byte_identical_output(tmp_path: Path) -> None:
    copy = tmp_path / "elsewhere"
    shutil.copytree(EXAMPLES / "navigation", copy)
    assert rei_gen(["generate", str(NAVIGATION), "-t", "all", "-o", str(tmp_path / "a")]) == 0
    assert rei_gen(["generate", str(copy / "navigation.mission"), "-t", "all", "-o",
                    str(tmp_path / "b")]) == 0
    first, second = snapshot(tmp_path / "a"), snapshot(tmp_path / "b")
    assert first and first == second


def test_options_reach_the_targets(tmp_path: Path) -> None:
    assert rei_gen(["generate", str(NAVIGATION), "-t", "launch", "-o", str(tmp_path),
                    "--option", "seed=42"]) == 0
    assert '"seed": 42' in (tmp_path / "run.json").read_text()


def test_invalid_input_reports_every_located_diagnostic(
    write: Write, tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    bad = write("bad.room", """room bad {
        floor a { right b }
        floor b
        object x : tabel on a
        object y : chiar on nowhere
        robot r : turtlebot3_waffle on a
    }""")
    out = tmp_path / "out"
    assert rei_gen(["generate", str(bad), "-t", "all", "-o", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) >= 3
    assert any(line.startswith(f"{bad}:4:") and "did you mean 'table'" in line for line in err)
    assert any(line.startswith(f"{bad}:5:") for line in err)
    assert not out.exists()


ROOM = EXAMPLES / "navigation" / "navigation.room"


@pytest.mark.parametrize("source,argv,message", [
    (NAVIGATION, ["-t", "gazeb"], "did you mean 'gazebo'"),
    (ROOM, ["-t", "mission"], "expected a file ending in .mission"),
    (NAVIGATION, ["-t", "all", "--option", "seed"], "expected KEY=VALUE"),
    (NAVIGATION, ["-t", "launch", "--option", "seed=x"], "option seed"),
    (NAVIGATION, ["-t", "launch", "--option", "sed=1"], "did you mean 'seed'"),
    (NAVIGATION, ["-t", "mission", "--option", "seed=1"], "expected a key among none"),
])
def test_bad_requests_exit_2_with_a_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], source: Path, argv: list[str],
    message: str,
) -> None:
    out = tmp_path / "out"
    assert rei_gen(["generate", str(source), "-o", str(out), *argv]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_missing_input_file_is_a_located_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    assert rei_gen(["generate", str(tmp_path / "nope.room"), "-t", "gazebo", "-o",
                    str(tmp_path / "out")]) == 2
    assert "nope.room" in capsys.readouterr().err


def test_an_unwritable_output_folder_is_reported_and_nothing_is_left(
    tmp_path: Path, capsys: pytest.CaptureFixture[str],
) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    out = blocker / "out"
    assert rei_gen(["generate", str(NAVIGATION), "-t", "all", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "cannot write to the output folder" in err and str(out) in err
    assert "Traceback" not in err
    assert blocker.read_text() == "not a folder"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]


def test_a_template_failure_leaves_the_output_folder_unchanged(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "mission").mkdir()
    (out / "mission" / "mission.xml").write_text("previous run")
    before = snapshot(out)
    broken = MissionTarget(loader=jinja2.DictLoader({
        "mission.xml.j2": "<mission>\n{% for g in mission.goals %}\n{{ g.no_such_field }}\n"
                          "{% endfor %}\n</mission>\n"}))
    request, _ = build_request(NAVIGATION)
    with pytest.raises(GenerationError) as info:
        # gazebo succeeds first; the broken mission template must still prevent every write.
        write_tree(render_targets(request, [GAZEBO, broken], subfolders=True), out)
    message = str(info.value)
    assert "target 'mission'" in message and "template 'mission.xml.j2' line 3" in message
    assert "no_such_field" in message
    assert snapshot(out) == before
    assert [p.name for p in out.iterdir()] == ["mission"]
