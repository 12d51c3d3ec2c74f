"""The `mission` target: the mission as XML for the mission executor (thesis 4.3.1, 6.2.3).

Goals are written in the world frame (the concrete model's metres, yaw in radians in
(-pi, pi]) with their tolerance and timeout, followed by the task order (the goal sequence
repeated ``cycles`` times) and the time limit. The output is validated against
``generators/schemas/mission.xsd`` before it is returned. This module must never write files
itself (``write_tree`` does) or read the textX model.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import jinja2

from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.templating import (
    check_xml,
    make_environment,
    normalise_angle,
    relative_to,
    render,
    template_loader,
)

OUTPUT = "mission.xml"
SCHEMA = "mission.xsd"


@dataclass(frozen=True)
class Task:
    index: int
    cycle: int
    goal: str


@dataclass(frozen=True)
class MissionTarget:
    name: str = "mission"
    description: str = "the mission as XML (goals in the world frame), valid against mission.xsd"
    accepts: tuple[str, ...] = (".mission",)
    options: tuple[str, ...] = ()
    """The --option keys this target reads (none)."""
    loader: jinja2.BaseLoader | None = field(default=None, compare=False)
    """Template loader; None means the bundled templates/mission/ folder."""

    def generate(self, request: GenerationRequest) -> OutputTree:
        mission = request.mission
        if mission is None:
            raise GenerationError(f"target 'mission' expected a .mission file, found "
                                  f"'{request.source.name}'")
        goals = tuple(replace(g, yaw=normalise_angle(g.yaw) if g.yaw is not None else None)
                      for g in mission.goals)
        mission = replace(mission, goals=goals)
        tasks = [Task(i + 1, i // len(goals) + 1, goal.name)
                 for i, goal in enumerate(mission.tasks())]
        env = make_environment(self.loader or template_loader("mission"), xml=True)
        text = render(env, "mission.xml.j2", mission=mission, tasks=tasks,
                      mission_file=request.source.name,
                      room_file=relative_to(mission.world.source, str(request.source)))
        check_xml(text, OUTPUT, SCHEMA)
        tree = OutputTree()
        tree.add_text(OUTPUT, text)
        return tree


TARGET = MissionTarget()
