"""The concrete model: an abstract room and mission mapped to metres (thesis 4.1.3, 6.2.1).

A breadth-first traversal of the floor graph from the robot's floor (rei.lang.room.layout)
gives every floor a cell; cells times the tile size give metres, with the robot's floor
centre at the origin, +x to the right (RIGHT) and +y to the top (TOP). The catalogue gives
each object its geometry, mass and inertia. Everything downstream (generators, the
simulator, the monitor) reads this model, never the textX one.
"""

from rei.generators.concrete.build import concretise_mission, concretise_room, load_concrete_mission
from rei.generators.concrete.model import (
    ConcreteBlock,
    ConcreteGoal,
    ConcreteMission,
    ConcreteObject,
    ConcreteWorld,
    Pose2D,
    TimedPoint,
    TimedTrajectory,
)

__all__ = [
    "ConcreteBlock",
    "ConcreteGoal",
    "ConcreteMission",
    "ConcreteObject",
    "ConcreteWorld",
    "Pose2D",
    "TimedPoint",
    "TimedTrajectory",
    "concretise_mission",
    "concretise_room",
    "load_concrete_mission",
]
