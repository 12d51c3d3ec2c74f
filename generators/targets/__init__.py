"""The generation targets, one module each, found by name at run time.

A target module defines ``TARGET``, an object satisfying the ``Target`` protocol. The
registry imports the modules of this package on demand, so adding a target is adding a
module; `rei-gen generate --target NAME` and `textx generate` both go through ``get_target``.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

from rei.generators.concrete import ConcreteMission, ConcreteWorld
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.lang.suggest import did_you_mean


@dataclass(frozen=True)
class GenerationRequest:
    """What a target generates from: the checked input file and its concrete model."""

    source: Path
    """The .room, .mission or .vepl file given on the command line."""
    world: ConcreteWorld | None = None
    """Set for .room and .mission inputs."""
    mission: ConcreteMission | None = None
    """Set for .mission inputs."""
    options: Mapping[str, str] = field(default_factory=dict)
    """Target options from `--option KEY=VALUE` (e.g. seed=7)."""
    parameters: tuple[tuple[str, float], ...] = ()
    """A .vepl's parameter values from `--param NAME=VALUE`, sorted by name: the generated
    automata carry them in place of the file's."""


@runtime_checkable
class Target(Protocol):
    name: str
    description: str
    accepts: tuple[str, ...]
    """File suffixes this target generates from, e.g. ('.room', '.mission').

    A target may also have ``options: tuple[str, ...]``, the `--option` keys it reads; when
    every chosen target declares them, `rei-gen generate` refuses keys none of them reads.
    """

    def generate(self, request: GenerationRequest) -> OutputTree:
        """Every file of the artifact, relative to the output folder; deterministic."""
        ...


def available_targets() -> dict[str, Target]:
    targets: dict[str, Target] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        target = getattr(module, "TARGET", None)
        if isinstance(target, Target):
            targets[target.name] = target
    return targets


def get_target(name: str) -> Target:
    targets = available_targets()
    if name not in targets:
        raise GenerationError(f"expected a target among {', '.join(sorted(targets)) or 'none'}, "
                              f"found '{name}'" + did_you_mean(name, targets))
    return targets[name]


def check_target(target: object) -> list[str]:
    """Conformance problems of a target implementation (empty when it conforms)."""
    problems = []
    if not isinstance(target, Target):
        problems.append("does not have name, description, accepts and generate()")
        return problems
    if not target.name or not target.name.replace("-", "_").isidentifier():
        problems.append(f"name {target.name!r} is not a simple identifier")
    if not target.accepts or not all(s.startswith(".") for s in target.accepts):
        problems.append(f"accepts {target.accepts!r} is not a tuple of file suffixes")
    return problems
