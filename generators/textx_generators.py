"""REI's targets registered as textX generators, so `textx generate FILE --target NAME` works.

Each registration is a ``GeneratorDesc`` for one (language, target) pair, named
``<language>_<target>`` (e.g. ``room_gazebo``), referenced from pyproject.toml's
``[project.entry-points.textx_generators]``. The generator function runs the same pipeline as
`rei-gen generate` (REI's full checks, the concrete model, atomic writing); textX's own model
is used only for its file name. Targets are looked up when the generator runs, so a target
added later works through ``generator_desc(...)`` without changing this module. This module
must never generate anything at import time.

``textx generate navigation.room --target gazebo [-o DIR] [--overwrite] [--seed 7]`` writes
into DIR (default: ``<input folder>/<input stem>-<target>/``); extra ``--key value`` arguments
become target options. Without ``--overwrite`` it refuses to replace existing files.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from textx import GeneratorDesc, TextXError

from rei.generators.output import write_tree
from rei.generators.pipeline import plan
from rei.lang.errors import ReiError

LANGUAGES = {"room": ("rei-room", ".room"), "mission": ("rei-mission", ".mission"),
             "vepl": ("rei-vepl", ".vepl")}


def default_output(source: Path, target: str) -> Path:
    return source.parent / f"{source.stem}-{target}"


def textx_generator(target: str) -> Callable[..., None]:
    """The generator function textX calls for ``target``."""

    def generate(metamodel: Any, model: Any, output_path: str | None, overwrite: bool,
                 debug: bool, **custom_args: Any) -> None:
        filename = getattr(model, "_tx_filename", None)
        if not filename:
            raise TextXError(f"target '{target}' generates from a file; found a model without one")
        source = Path(filename)
        out = Path(output_path) if output_path else default_output(source, target)
        options = {key: "true" if value is True else str(value)
                   for key, value in custom_args.items()}
        try:
            result = plan(source, target, options)
            existing = sorted(rel for rel in result.tree.files if (out / rel).exists())
            if existing and not overwrite:
                raise TextXError(f"{out}: would replace {', '.join(existing)}; "
                                 f"use --overwrite to replace them")
            write_tree(result.tree, out)
        except ReiError as exc:
            raise TextXError(str(exc)) from None

    generate.__name__ = f"generate_{target}"
    return generate


def generator_desc(language: str, target: str, description: str = "") -> GeneratorDesc:
    """A textX registration of REI target ``target`` for ``language`` ('room', 'mission' or
    'vepl')."""
    textx_language, _ = LANGUAGES[language]
    return GeneratorDesc(language=textx_language, target=target,
                         description=description or f"REI '{target}' target (rei-gen generate)",
                         generator=textx_generator(target))


room_gazebo = generator_desc("room", "gazebo", "SDF 1.9 world for Gazebo Sim")
mission_gazebo = generator_desc("mission", "gazebo", "SDF 1.9 world for Gazebo Sim")
room_launch = generator_desc("room", "launch", "ROS 2 launch file and the Gazebo world")
mission_launch = generator_desc("mission", "launch", "REI run.json, its sources, ROS 2 launch")
mission_mission = generator_desc("mission", "mission", "mission XML (valid against mission.xsd)")
room_pybullet = generator_desc("room", "pybullet", "URDFs and manifest for pybullet")
mission_pybullet = generator_desc("mission", "pybullet", "URDFs and manifest for pybullet")
room_monitor = generator_desc("room", "monitor", "monitor configuration")
mission_monitor = generator_desc("mission", "monitor", "monitor configuration")
room_all = generator_desc("room", "all", "every REI target, each into its own folder")
mission_all = generator_desc("mission", "all", "every REI target, each into its own folder")
vepl_rx = generator_desc("vepl", "rx", "RxPY event automata (a readable Python module)")

REGISTRATIONS: tuple[GeneratorDesc, ...] = (
    room_gazebo, mission_gazebo, room_launch, mission_launch, mission_mission, room_pybullet,
    mission_pybullet, room_monitor, mission_monitor, room_all, mission_all, vepl_rx)
"""Every registration above, in the order of the entry points."""
