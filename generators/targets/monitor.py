"""The `monitor` target: what the data collector observes, and how often (thesis 5.1.4, 9.1).

``monitor.json`` lists the observed objects (every wall tile, static and dynamic object and
human, in the world's order: walls first), their footprints and heights, the robot, the
sampling rate and the data recorded per sample. The collector reads it; the stream header it
publishes is built from it, so the monitor's automata see exactly these objects. JSON, not
XML, because the collector is its only reader; it is written by ``dump_json`` (sorted keys,
fixed precision), so it needs no template. This module must never write files itself or
import pybullet.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.targets.pybullet import footprint_json
from rei.generators.templating import dump_json

OUTPUT = "monitor.json"
CONFIG_VERSION = 1
DEFAULT_RATE = 10.0
"""Samples per second of simulation time: twice the default laser rate, so no scan is lost."""
DATA = ("ground_truth", "odometry", "laser", "nav_state", "mission_events")


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
        rate_text = request.options.get("rate", str(DEFAULT_RATE))
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
            "rate": rate, "data": list(DATA),
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
