"""The `monitor` target: what the data collector observes, and how often (thesis 5.1.4, 9.1).

``monitor.json`` lists the observed objects (every wall tile, static and dynamic object and
human, in the world's order: walls first), their footprints and heights, the robot, the
sampling rate and the data recorded per sample. Rate and data come from the mission's
``monitor`` block (thesis 3.2.2.2, 6.1.2: the monitor configuration names the data of
interest); without one, or for a .room, every kind of data at 10 samples per second. The
``rate`` option, when given, overrides the mission's rate. The collector reads it; the
stream header it publishes is built from it, so the monitor's automata see exactly these
objects. JSON, not XML, because the collector is its only reader; it is written by
``dump_json`` (sorted keys, fixed precision), so it needs no template. This module must
never write files itself or import pybullet.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.targets.pybullet import footprint_json
from rei.generators.templating import dump_json
from rei.lang.mission.model import COLLECTED_DATA, DEFAULT_SAMPLE_RATE

OUTPUT = "monitor.json"
CONFIG_VERSION = 1
DEFAULT_RATE = DEFAULT_SAMPLE_RATE
"""Samples per second of simulation time: twice the default laser rate, so no scan is lost."""
DATA = COLLECTED_DATA
"""Everything the collector can forward: a .room's configuration, or a mission's by default."""


@dataclass(frozen=True)
class MonitorTarget:
    name: str = "monitor"
    description: str = "the monitor configuration: observed objects, data and sampling rate (JSON)"
    accepts: tuple[str, ...] = (".room", ".mission")
    options: tuple[str, ...] = ("rate",)

    def generate(self, request: GenerationRequest) -> OutputTree:
        world = request.world
        if world is None:
            raise GenerationError(f"target 'monitor' expected a .room or .mission file, found "
                                  f"'{request.source.name}'")
        mission = request.mission
        rate_text = request.options.get(
            "rate", str(mission.sample_rate if mission is not None else DEFAULT_RATE))
        try:
            rate = float(rate_text)
        except ValueError:
            rate = float("nan")
        if not (rate > 0 and rate < 1e4):
            raise GenerationError(f"option 'rate' expected a positive number of samples per "
                                  f"second, found '{rate_text}'")
        tile = world.tile_size
        observed: list[dict[str, Any]] = []
        for block in world.walls:
            observed.append({"name": block.name, "role": "wall", "type": block.type.name,
                             "footprint": {"shape": "box", "size": [tile, tile]},
                             "height": block.type.height})
        for obj in world.objects:
            observed.append({"name": obj.name, "role": obj.role, "type": obj.type.name,
                             "footprint": footprint_json(obj.type, tile),
                             "height": obj.type.height})
        robot = world.robot
        config = {
            "version": CONFIG_VERSION, "world": world.name,
            "mission": request.mission.name if request.mission is not None else None,
            "rate": rate, "data": list(mission.data if mission is not None else DATA),
            "laser_scans": "when_new",
            "robot": {"name": robot.name, "role": "robot", "type": robot.type.name,
                      "footprint": footprint_json(robot.type, tile),
                      "height": robot.type.height},
            "objects": observed,
        }
        tree = OutputTree()
        tree.add_text(OUTPUT, dump_json(config))
        return tree


TARGET = MonitorTarget()
