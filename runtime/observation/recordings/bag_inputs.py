"""What a ROS 2 recording REI did not make is judged against (``BagWorld``: the .mission's
stream header, tasks and declared poses), how another stack names REI's topics and frames
(``TopicMap``, `rei replay --map FILE`), and what goes wrong with a bag (``BagError``: it
cannot be judged; ``BagProblem``: data no verdict may rest on). Read by
rei.runtime.observation.recordings.foreign; this module must never import pybullet.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from rei.generators.concrete import ConcreteGoal
from rei.lang.suggest import did_you_mean
from rei.runtime.messages import StreamHeader
from rei.runtime.messages.ros import ROBOT_TOPICS
from rei.runtime.observation.recordings.errors import RecordingError

MOVING_ROLES = ("robot", "dynamic", "human")


class BagError(RecordingError):
    """A ROS 2 recording cannot be judged: unreadable, or without a topic or frame REI needs
    (the message names the file, what was expected and what the bag holds)."""


@dataclass(frozen=True)
class BagProblem:
    """Data a verdict cannot rest on: ``topic`` at ``time`` (s), ``what`` happened."""

    topic: str
    time: float
    what: str

    def text(self) -> str:
        return f"{self.topic} at t={self.time:.3f} s: {self.what}"


@dataclass(frozen=True)
class TopicMap:
    """How another stack names REI's topics and frames (``rei replay --map FILE``)."""

    topics: Mapping[str, str] = field(default_factory=dict)
    """REI's topic name (``ros.ROBOT_TOPICS``) -> the bag's."""
    frames: Mapping[str, str] = field(default_factory=dict)
    """REI's frame name (``map``, a body's name) -> the bag's."""

    def topic(self, name: str) -> str:
        return self.topics.get(name, name)

    def frame(self, name: str) -> str:
        return self.frames.get(name, name)


def load_topic_map(path: Path) -> TopicMap:
    """A mapping file: TOML with a ``[topics]`` and a ``[frames]`` table of strings::

        [topics]
        "/scan" = "/robot1/scan"
        [frames]
        map = "world"
        waffle = "base_footprint"
    """
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise BagError(f"{path}: cannot read the mapping file: {exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BagError(f"{path}: expected a TOML mapping file, found text TOML cannot read "
                       f"({exc})") from None
    unknown = sorted(set(data) - {"topics", "frames"})
    if unknown:
        raise BagError(f"{path}: {unknown[0]}: expected the tables [topics] and [frames], "
                       f"found [{unknown[0]}]" + did_you_mean(unknown[0], ["topics", "frames"]))
    tables: dict[str, dict[str, str]] = {}
    for name in ("topics", "frames"):
        table = data.get(name, {})
        if not isinstance(table, dict):
            raise BagError(f"{path}: {name}: expected a table of names, found {table!r}")
        for key, value in table.items():
            if not isinstance(value, str) or not value:
                raise BagError(f"{path}: {name}.{key}: expected a name (text), found "
                               f"{value!r}")
            if name == "topics" and key not in ROBOT_TOPICS:
                raise BagError(f"{path}: topics.{key}: expected one of REI's topics "
                               f"({', '.join(ROBOT_TOPICS)}), found {key!r}"
                               + did_you_mean(key, list(ROBOT_TOPICS)))
        tables[name] = dict(table)
    return TopicMap(tables["topics"], tables["frames"])


@dataclass(frozen=True)
class BagWorld:
    """What a bag is judged against: the .mission's stream header (its room's bodies, its
    goals, what it collects), its tasks in order and the bodies' declared poses."""

    header: StreamHeader
    tasks: tuple[ConcreteGoal, ...]
    poses: tuple[tuple[float, float, float], ...]
    """(x, y, yaw) of each of the header's objects as the room declares it."""
    settle: float = 0.0
    """The .mission's settle period: seconds the mission goes on after its last task, as in
    the live run (``runtime.loop.mission``), so its end (SIG_MISSION_END) comes as late."""
