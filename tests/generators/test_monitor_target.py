"""The `monitor` target: observed objects (walls included), data and sampling rate."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rei.generators.concrete.build import load_concrete_mission
from rei.generators.errors import GenerationError
from rei.generators.output import write_tree
from rei.generators.targets import GenerationRequest, check_target, get_target
from rei.runtime.artifacts.monitor_config import load_monitor_config
from tests.conftest import EXAMPLES


def _request(**options: str) -> GenerationRequest:
    path = EXAMPLES / "navigation" / "navigation.mission"
    mission = load_concrete_mission(path)
    return GenerationRequest(path, mission.world, mission, options)


def test_every_wall_and_object_is_observed_in_world_order(tmp_path: Path) -> None:
    assert check_target(get_target("monitor")) == []
    request = _request()
    write_tree(get_target("monitor").generate(request), tmp_path)
    config = load_monitor_config(tmp_path)
    world = request.world
    assert world is not None
    names = [o.name for o in config.objects]
    assert names == [w.name for w in world.walls] + [o.name for o in world.objects]
    walls = [o for o in config.objects if o.role == "wall"]
    assert len(walls) == len(world.walls)
    assert all(o.footprint.half_extents() == (0.5, 0.5) for o in walls)
    assert config.rate == 10.0 and config.robot.name == "waffle"


def test_rate_option_and_determinism() -> None:
    first = get_target("monitor").generate(_request(rate="20")).files["monitor.json"]
    assert first == get_target("monitor").generate(_request(rate="20")).files["monitor.json"]
    assert json.loads(first)["rate"] == 20.0
    with pytest.raises(GenerationError, match="option 'rate'"):
        get_target("monitor").generate(_request(rate="fast"))
