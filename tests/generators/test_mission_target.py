"""The `mission` target: goals in the world frame, task order, valid against mission.xsd."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import jinja2
import pytest
from lxml import etree

from rei.generators.errors import GenerationError
from rei.generators.targets import check_target
from rei.generators.targets.mission import TARGET, MissionTarget
from tests.conftest import example_files
from tests.generators.conftest import RequestFor, Write

NS = {"m": "urn:rei:mission:1"}


def schema() -> etree.XMLSchema:
    with resources.files("rei.generators.schemas").joinpath("mission.xsd").open("rb") as f:
        return etree.XMLSchema(etree.parse(f))


def mission_xml(request) -> etree._Element:
    return etree.fromstring(TARGET.generate(request).files["mission.xml"])


def test_target_conforms() -> None:
    assert check_target(TARGET) == []


@pytest.mark.parametrize("path", example_files(".mission"), ids=lambda p: p.name)
def test_every_example_validates_against_the_schema(path: Path, request_for: RequestFor) -> None:
    document = mission_xml(request_for(path))
    validator = schema()
    assert validator.validate(document), validator.error_log


def test_goals_are_in_the_world_frame_and_tasks_repeat_per_cycle(
    write: Write, request_for: RequestFor,
) -> None:
    write("r.room", """room r {
        tile 0.5
        grid g { legend { "S" = floor s } "#####" "#S..#" "#...#" "#####" }
        robot bot : turtlebot3_waffle on s
    }""")
    path = write("m.mission", """mission m in "r.room" {
        cycles 3
        time_limit 99.5
        goal a at s tolerance 0.2 timeout 10
        goal b at g_2_3 heading 270 timeout 20
    }""")
    root = mission_xml(request_for(path))
    assert root.get("frame") == "world" and root.get("cycles") == "3"
    assert root.get("time_limit") == "99.5"
    goals = root.findall("m:goals/m:goal", NS)
    assert [(g.get("name"), g.get("x"), g.get("y"), g.get("yaw")) for g in goals] == [
        ("a", "0", "0", None), ("b", "1", "-0.5", "-1.570796")]
    assert [g.get("tolerance") for g in goals] == ["0.2", "0.25"]
    tasks = root.findall("m:tasks/m:task", NS)
    assert [(t.get("cycle"), t.get("goal")) for t in tasks] == [
        ("1", "a"), ("1", "b"), ("2", "a"), ("2", "b"), ("3", "a"), ("3", "b")]
    assert root.find("m:source", NS).get("room") == "r.room"  # type: ignore[union-attr]


def test_the_schema_rejects_what_the_executor_could_not_use() -> None:
    validator = schema()
    bad = b"""<mission xmlns="urn:rei:mission:1" name="m" world="w" frame="world" cycles="1"
        time_limit="10"><source mission="m.mission" room="r.room"/><goals>
        <goal id="1" name="a" floor="f" x="0" y="0" tolerance="0" timeout="5"/>
        <goal id="2" name="a" floor="f" x="NaN" y="0" tolerance="1" timeout="5"/></goals>
        <tasks><task index="1" cycle="1" goal="a"/></tasks></mission>"""
    assert not validator.validate(etree.fromstring(bad))
    messages = " ".join(e.message for e in validator.error_log)
    assert "tolerance" in messages and "x" in messages and "Duplicate" in messages


def test_a_template_that_breaks_the_schema_is_refused(request_for: RequestFor) -> None:
    broken = MissionTarget(loader=jinja2.DictLoader({
        "mission.xml.j2": '<mission xmlns="urn:rei:mission:1" name="{{ mission.name }}"/>\n'}))
    with pytest.raises(GenerationError, match="does not follow mission.xsd"):
        broken.generate(request_for(example_files(".mission")[0]))


def test_a_room_is_not_a_mission(request_for: RequestFor) -> None:
    with pytest.raises(GenerationError, match="expected a .mission file"):
        TARGET.generate(request_for(example_files(".room")[0]))
